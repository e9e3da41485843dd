//! Projections as FITS images: the column densities with a linear world
//! coordinate system (the image plane's axes, in the data's length unit),
//! `BUNIT` (mass per area in the snapshot's units, when the file states
//! them and the weights are its masses), the epoch and the kernel, and the
//! command line as `HISTORY` — what astronomers' tools (astropy, DS9)
//! expect of a map.

use std::path::Path;

use voxless_io::fits::{CardValue, FitsImage, LinearWcs, write_fits_image};
use voxless_io::{SnapshotHeader, Units};
use voxless_scene::SceneDesc;

use crate::load::formats::ParticleFormat;
use crate::{ProjectionView, SceneError};

/// What a map says about its data besides the view: the snapshot's header
/// (units, epoch) when the weights are its masses, and the kernel.
#[derive(Clone, Debug, Default)]
pub struct MapMeta {
    pub snapshot: Option<SnapshotHeader>,
    pub kernel: Option<String>,
}

/// The metadata of frame `frame` of the particles `desc` names (`None`
/// parts for other data): only the headers are read.
pub fn map_meta(desc: &SceneDesc, base: &Path, frame: usize) -> Result<MapMeta, SceneError> {
    let Some(p) = &desc.particles else {
        return Ok(MapMeta::default());
    };
    let kernel = p.kernel.map(|k| format!("{k:?}"));
    let Some(spec) = &p.file else {
        return Ok(MapMeta {
            snapshot: None,
            kernel,
        });
    };
    let path = crate::load::particles::frame_file(spec, base, frame)?;
    let snapshot = match ParticleFormat::detect(&path)? {
        Some(format) if format.is_snapshot() => voxless_io::snapshot_header(&path, format)?,
        _ => None,
    };
    // Units of mass per area only when the weights are the file's masses.
    let masses = p
        .weights
        .as_deref()
        .is_none_or(|w| ["masses", "mass"].contains(&w.to_ascii_lowercase().as_str()));
    Ok(MapMeta {
        snapshot: snapshot.map(|mut s| {
            if !masses {
                s.units = None;
            }
            s
        }),
        kernel,
    })
}

/// Writes the `w`×`h` column densities `column` (row 0 at the top) seen
/// through `view` as a FITS image at `path`, with `history` (the command
/// line) as `HISTORY`.
pub fn write_projection_fits(
    path: &Path,
    view: &ProjectionView,
    size: (u32, u32),
    column: &[f32],
    meta: &MapMeta,
    history: &[String],
) -> Result<(), SceneError> {
    write_map_fits(path, view, size, column, meta, history, None)
}

/// Writes the `w`×`h` slice `values` of `quantity` (see [`crate::slice`])
/// through `view` as a FITS image at `path`: the plane's world coordinates,
/// `BUNIT` mass per volume for a particle density in the snapshot's units,
/// and the plane's position.
pub fn write_slice_fits(
    path: &Path,
    view: &ProjectionView,
    size: (u32, u32),
    values: &[f32],
    meta: &MapMeta,
    quantity: &str,
    history: &[String],
) -> Result<(), SceneError> {
    write_map_fits(path, view, size, values, meta, history, Some(quantity))
}

/// A projection's map (`slice` None) or a slice of `slice`'s quantity.
fn write_map_fits(
    path: &Path,
    view: &ProjectionView,
    (w, h): (u32, u32),
    column: &[f32],
    meta: &MapMeta,
    history: &[String],
    slice: Option<&str>,
) -> Result<(), SceneError> {
    let units = meta.snapshot.as_ref().and_then(|s| s.units.as_ref());
    let (length, per) = match units {
        Some(u) => {
            let (name, f) = u.length_name();
            // CUNIT takes a plain unit: a non-unit factor stays in CDELT.
            if (f - 1.0).abs() < 1e-5 {
                (name, 1.0)
            } else {
                (name, f)
            }
        }
        None => ("", 1.0),
    };
    let name = |v: [f64; 3]| match v.map(|c| (c.abs() - 1.0).abs() < 1e-12 && c > 0.0) {
        [true, _, _] => "X",
        [_, true, _] => "Y",
        [_, _, true] => "Z",
        _ => "LINEAR",
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (c1, c2) = (dot(view.center, view.right), dot(view.center, view.up));
    let lo = [c1 - 0.5 * view.width[0], c2 - 0.5 * view.width[1]];
    let hi = [c1 + 0.5 * view.width[0], c2 + 0.5 * view.width[1]];
    let mut wcs = LinearWcs::covering(
        w as usize,
        h as usize,
        lo.map(|v| v * per),
        hi.map(|v| v * per),
        [name(view.right), name(view.up)],
        [length, length],
    );
    if per != 1.0 {
        wcs.cunit = [length.to_string(), length.to_string()];
    }
    let axes = text(
        "PROJAXES",
        &format!("right {:?} up {:?}", round(view.right), round(view.up)),
        "image axes in world coordinates",
    );
    let mut cards = match slice {
        None => vec![
            text(
                "DATAKIND",
                "column density",
                "integral of the field along the line of sight",
            ),
            axes,
            text(
                "LOS",
                &format!("{:?}", round(view.normal.map(|v| -v))),
                "line of sight (away from the viewer)",
            ),
        ],
        Some(q) => vec![
            text("DATAKIND", &format!("slice of {q}"), "the field on a plane"),
            axes,
            text(
                "PLANE",
                &format!("{:?}", round(view.center)),
                "a point of the plane (the image centre)",
            ),
            text(
                "NORMAL",
                &format!("{:?}", round(view.normal)),
                "the plane's normal (towards the viewer)",
            ),
        ],
    };
    if let Some(k) = &meta.kernel {
        cards.push(text("KERNEL", k, "RBF / SPH kernel"));
    }
    if let Some(s) = &meta.snapshot {
        cards.push(text("ORIGIN", &s.code, "the code or format of the data"));
        if let Some(t) = s.time.filter(|t| t.is_finite()) {
            cards.push((
                "TIME".into(),
                CardValue::Real(t),
                "snapshot time (scale factor in cosmological runs)".into(),
            ));
        }
        if let Some(z) = s.redshift.filter(|z| z.is_finite()) {
            cards.push((
                "REDSHIFT".into(),
                CardValue::Real(z),
                "snapshot redshift".into(),
            ));
        }
        if let Some(u) = units {
            cards.push(text("UNITSRC", &u.source, "where the units come from"));
            if u.comoving {
                cards.push((
                    "COMOVING".into(),
                    CardValue::Logical(true),
                    "coordinates comoving, as stored".into(),
                ));
            }
            if let Some(hub) = u.hubble {
                cards.push((
                    "HUBBLE".into(),
                    CardValue::Real(hub),
                    "lengths and masses in h^-1 units".into(),
                ));
            }
        }
    }
    let image = FitsImage {
        width: w as usize,
        height: h as usize,
        data: column,
        wcs: Some(wcs),
        bunit: Some(match slice {
            None => units.map(|u| fits_unit(u, 2)).unwrap_or_default(),
            Some("density") => units.map(|u| fits_unit(u, 3)).unwrap_or_default(),
            Some(_) => String::new(),
        }),
        cards,
        history: history.to_vec(),
    };
    write_fits_image(path, &image)?;
    Ok(())
}

/// A (KEYWORD, text, comment) card.
fn text(key: &str, value: &str, comment: &str) -> (String, CardValue, String) {
    let mut v: String = value
        .chars()
        .filter(|c| c.is_ascii() && !c.is_ascii_control())
        .collect();
    v.truncate(60);
    (key.into(), CardValue::Text(v), comment.into())
}

/// Components rounded for a readable card.
fn round(v: [f64; 3]) -> [f64; 3] {
    v.map(|c| (c * 1e6).round() / 1e6 + 0.0)
}

/// Mass per length^`power` (area: 2, volume: 3) in the FITS standard's
/// unit syntax ("10**10 solMass Mpc-2"); lengths in h⁻¹ units say so with
/// "h".
fn fits_unit(u: &Units, power: i32) -> String {
    let (l, lf) = u.length_name();
    let (m, mf) = u.mass_name();
    let m = if m == "Msun" { "solMass" } else { m };
    // Factors: powers of ten as 10**k, others as plain numbers.
    let factor = mf / lf.powi(power);
    let scale = if (factor - 1.0).abs() < 1e-5 {
        String::new()
    } else {
        let k = factor.log10();
        if (k - k.round()).abs() < 1e-6 {
            format!("10**{} ", k.round() as i64)
        } else {
            format!("{factor:.6e} ")
        }
    };
    let h = if u.hubble.is_some() { " h" } else { "" };
    format!("{scale}{m} {l}-{power}{h}")
}

/// The unit world lengths are in, when the snapshot states it: its name
/// (`kpc`, `Mpc/h`) and how many of it one world unit is — what a scale bar
/// labels its length with.
pub fn length_unit(meta: &MapMeta) -> Option<(String, f64)> {
    let u = meta.snapshot.as_ref()?.units.as_ref()?;
    let (name, per) = u.length_name();
    let h = if u.hubble.is_some() { "/h" } else { "" };
    Some((format!("{name}{h}"), per))
}
