//! Frame labels: the time or redshift a data frame records, as the text a
//! movie or image carries in its corner ([`frame_label`]). Only headers
//! are read where the format has them (snapshots, AMRClaw's `fort.t`);
//! formats that record a time per frame inside the frame (LAMMPS, XYZ,
//! VTK, PySPH) read that frame's table.

use std::path::Path;

use voxless_io::ParticleFormat;
use voxless_scene::SceneDesc;

use crate::SceneError;
use crate::load::{formats, particles};

/// A number in a label: 4 significant digits, plain where that reads well.
fn num(v: f64) -> String {
    if v == 0.0 || (1e-3..1e5).contains(&v.abs()) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s.is_empty() || s == "-" {
            "0".into()
        } else {
            s.into()
        }
    } else {
        format!("{v:.3e}")
    }
}

/// The label of frame `frame` of the data `desc` names (paths relative to
/// `base`): `z = 0.5` for a snapshot with a redshift, `t = 1.25` where the
/// file records a time, `step 1000` for a LAMMPS dump (whose frames carry
/// the step), else `frame N`.
pub fn frame_label(desc: &SceneDesc, base: &Path, frame: usize) -> Result<String, SceneError> {
    let fallback = format!("frame {frame}");
    if let Some(spec) = desc.particles.as_ref().and_then(|p| p.file.as_deref()) {
        let (path, within) = particles::locate(spec, base, frame)?;
        let Some(format) = ParticleFormat::detect(&path)? else {
            return Ok(fallback);
        };
        if format.is_snapshot() {
            if let Some(h) = voxless_io::snapshot_header(&path, format)? {
                if let Some(z) = h.redshift.filter(|z| z.is_finite()) {
                    return Ok(format!("z = {}", num(z)));
                }
                if let Some(t) = h.time.filter(|t| t.is_finite()) {
                    return Ok(format!("t = {}", num(t)));
                }
            }
            return Ok(fallback);
        }
        if matches!(format, ParticleFormat::Npy | ParticleFormat::Csv) {
            return Ok(fallback);
        }
        let t = formats::read_table(&path, format, within, &Default::default())?.table;
        return Ok(match (format, t.time) {
            (ParticleFormat::Lammps, Some(step)) => format!("step {}", num(step)),
            (_, Some(time)) if time.is_finite() => format!("t = {}", num(time)),
            _ => fallback,
        });
    }
    if let Some(spec) = desc
        .amr
        .as_ref()
        .and_then(|a| a.amrclaw.as_ref().or(a.file.as_ref()))
    {
        let path = particles::frame_file(spec, base, frame)?;
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        if name.is_some_and(|n| n.starts_with("fort.q"))
            && let Some(t) = voxless_io::amrclaw_time(&path)?
        {
            return Ok(format!("t = {}", num(t)));
        }
    }
    Ok(fallback)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn label_numbers_read_well() {
        assert_eq!(num(0.5), "0.5");
        assert_eq!(num(1000.0), "1000");
        assert_eq!(num(0.0), "0");
        assert_eq!(num(1.23456), "1.2346");
        assert_eq!(num(2.5e-7), "2.500e-7");
    }
}
