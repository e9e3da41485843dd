//! `voxless slice`: the field on a plane (see `voxless::slice`), written as
//! raw values or a colormapped picture.

use std::path::Path;
use std::time::Instant;

use anyhow::{Result, bail};
use voxless::output::{ImageFormat, OutputKind};
use voxless::slice::{SliceDesc, SliceLook};
use voxless::{Placement, Purpose, SceneDesc};

use crate::progress::Progress;
use crate::{out, render};

/// How a `.png` slice looks, and whether any picture flag was given (they
/// apply to `.png` only, and are refused for raw outputs).
pub struct Picture {
    pub look: SliceLook,
    pub scale_bar: bool,
    pub colormap: bool,
}

/// Slices frame `frame` of the scene and writes `output` (checked before
/// anything is loaded).
pub fn run(
    placement: Placement,
    desc: &SceneDesc,
    base: &Path,
    frame: usize,
    slice: &SliceDesc,
    picture: &Picture,
    output: &Path,
) -> Result<()> {
    out::check(&[output.to_path_buf()], OutputKind::Slice, desc, base, &[])?;
    let png = ImageFormat::of(output) == Some(ImageFormat::Png);
    let styled = picture.look != SliceLook::default() || picture.scale_bar || picture.colormap;
    if !png && styled {
        bail!(
            "--colormap, --log, --linear, --value-range, --colorbar and --scale-bar style a .png \
             slice; {} holds the raw values",
            output.display()
        );
    }
    let size = voxless::projection::image_size(&desc.image)?;
    let t = Instant::now();
    let data = placement.load(desc, base, frame, Purpose::Render)?;
    render::report_loaded(
        placement,
        data.notes(),
        data.kind().name(),
        data.world_bounds(),
        t,
    );
    let progress = Progress::new("slicing", 1, placement.is_root());
    let report = |d: u64, total: u64| progress.set_fraction(0, d, total);
    let t = Instant::now();
    let (view, name, values) = data.slice(desc, slice, size, &report)?;
    progress.finish();
    let written = values.map_or(Ok(()), |values| {
        let meta = || voxless::map_fits::map_meta(desc, base, frame);
        if png {
            let mut image =
                voxless::slice::picture(&values, size, &desc.transfer, base, &name, &picture.look)?;
            if picture.scale_bar {
                let (unit, per) = match voxless::map_fits::length_unit(&meta()?) {
                    Some((u, per)) => (Some(u), per),
                    None => (None, 1.0),
                };
                let wpp = view.width[0] / size.0 as f64 * per;
                if voxless::render::annotate::draw_scale_bar(&mut image, wpp, unit.as_deref())
                    .is_none()
                {
                    eprintln!(
                        "note: a {}×{} image is too small for a scale bar",
                        size.0, size.1
                    );
                }
            }
            out::write_image(output, &image, [0.0; 3])?;
        } else if out::is_fits(output) {
            let line: Vec<String> = std::env::args().collect();
            voxless::map_fits::write_slice_fits(
                output,
                &view,
                size,
                &values,
                &meta()?,
                &name,
                &[format!("voxless: {}", line.join(" "))],
            )?;
        } else {
            out::write_gray(output, size.0, size.1, &values)?;
        }
        let finite = values.iter().filter(|v| v.is_finite());
        let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
        let outside = values.iter().filter(|v| v.is_nan()).count();
        let c = view.center;
        eprintln!(
            "sliced {}×{} of {name} on the plane through [{:.4e}, {:.4e}, {:.4e}] (normal \
             [{:.3}, {:.3}, {:.3}]){} in {:.3}s → {} (values {lo:.4e} … {hi:.4e}{})",
            size.0,
            size.1,
            c[0],
            c[1],
            c[2],
            view.normal[0],
            view.normal[1],
            view.normal[2],
            render::on_ranks(placement),
            t.elapsed().as_secs_f64(),
            output.display(),
            if outside > 0 {
                format!("; {outside} pixels outside the cells are NaN")
            } else {
                String::new()
            }
        );
        Ok(())
    });
    render::agree(placement, written)?;
    render::say(placement.memory_report(data.counts())?);
    Ok(())
}
