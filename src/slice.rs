//! Slices: the reconstructed field on a plane, one value per pixel.
//!
//! A slice is a grid of [`crate::PlacedData::sample`] points, so it equals
//! `sample` at the same points bit for bit, for every data kind and however
//! the data is held (one process or the ranks of `mpirun`). Its geometry is
//! a projection's ([`ProjectionView`]: `axis` or `normal` and `north`,
//! `center`, `width`), with the plane through the image centre:
//!
//! - pixel (row i, column j) of a w × h slice is centred at
//!   `center + ((j + ½)/w − ½)·W·right + (½ − (i + ½)/h)·H·up`, row 0 at the
//!   top, as in projections (for `axis` z, right is +x and up +y);
//! - [`SlicePixels::Area`] averages each pixel's square instead, by a
//!   4 × 4 Gauss–Legendre rule in each pixel (exact for fields that are
//!   polynomials of degree ≤ 7 across a pixel; for the kernels and cells
//!   in general it is a stated quadrature, converging as the pixel shrinks
//!   against the features it holds);
//! - the plane must cross the data: a plane beside the data's bounds is an
//!   error that says where the data is (a periodic box is never missed:
//!   points outside it wrap, as every query of a periodic field does).
//!
//! Values are those of `sample`'s columns ([`crate::Fields::columns`]):
//! particle density Φ or attribute Θ, tessellation density or stream
//! count, any AMR field (NaN outside the cells).

use voxless_core::Aabb;
use voxless_scene::SceneDesc;

use crate::{Fields, ProjectionDesc, ProjectionView, SceneError, WorldFrame};

/// How a slice's pixel takes its value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SlicePixels {
    /// The value at the pixel's centre (exactly `sample`'s).
    #[default]
    Centre,
    /// The mean over the pixel's square, by the 4 × 4 Gauss–Legendre rule.
    Area,
}

/// Nodes of the 4-point Gauss–Legendre rule on [−½, ½] and their weights
/// (summing to 1).
const GAUSS4: [(f64, f64); 4] = [
    (-0.430_568_155_797_026_3, 0.173_927_422_568_726_9),
    (-0.169_990_521_792_428_1, 0.326_072_577_431_273_1),
    (0.169_990_521_792_428_1, 0.326_072_577_431_273_1),
    (0.430_568_155_797_026_3, 0.173_927_422_568_726_9),
];

/// Rows sampled per call: bounds the points held at once.
const ROWS_PER_CHUNK: u32 = 32;

/// What a slice shows: its plane (a projection's geometry; `bounds` only
/// choose the default footprint, a `depth` is refused), the quantity (a
/// `sample` column by name; default: see [`quantity_column`]) and how
/// pixels are integrated.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SliceDesc {
    pub plane: ProjectionDesc,
    pub quantity: Option<String>,
    pub pixels: SlicePixels,
}

/// The column of `sample`'s output a slice shows, and its name. `quantity`
/// is a column name (`density`, `attribute`, `streams`, an AMR field by
/// its name, ignoring case, or the quantity the codes spell differently,
/// see [`voxless_io::amr_field`]) or the particles' attribute name. By
/// default: the AMR field the scene selects (`amr.field`, else the first),
/// else the first column (density).
pub fn quantity_column(
    fields: &Fields,
    desc: &SceneDesc,
    quantity: Option<&str>,
) -> Result<(usize, String), SceneError> {
    let columns = fields.columns(false);
    let names: Vec<&str> = columns.iter().map(String::as_str).collect();
    let asked = quantity.map(str::to_string).or_else(|| match fields {
        Fields::Amr(_) => desc.amr.as_ref().and_then(|a| a.field.clone()),
        _ => None,
    });
    let Some(q) = asked else {
        return Ok((0, columns[0].clone()));
    };
    let attribute_name = match fields {
        Fields::Particles {
            attribute: true, ..
        } => fields.colour_name(desc),
        _ => None,
    };
    let found = voxless_io::amr_field(&names, &q).or_else(|| {
        attribute_name
            .filter(|a| a.eq_ignore_ascii_case(&q))
            .and_then(|_| names.iter().position(|n| *n == "attribute"))
    });
    match found {
        Some(i) => Ok((i, columns[i].clone())),
        None => Err(SceneError::setting(
            "quantity",
            format!(
                "'{q}' is not a field of this data; it has {}",
                columns.join(", ")
            ),
        )),
    }
}

/// The plane `desc` describes over data with `bounds` (the volume's
/// frame): its view, or an error when the plane misses the data (unless
/// `periodic`: then every plane meets the tiled box).
pub fn slice_view(
    desc: &ProjectionDesc,
    bounds: &Aabb,
    frame: &WorldFrame,
    periodic: bool,
) -> Result<ProjectionView, SceneError> {
    if desc.depth.is_some() {
        return Err(SceneError::setting(
            "depth",
            "a slice is a plane; depth applies to projections",
        ));
    }
    let view = ProjectionView::new(desc, bounds, frame)?;
    if periodic {
        return Ok(view);
    }
    let (lo, hi) = (frame.to_world(bounds.min), frame.to_world(bounds.max));
    let along = |p: [f64; 3]| (0..3).map(|a| p[a] * view.normal[a]).sum::<f64>();
    let (a, b) = crate::projection::corners(lo, hi)
        .map(along)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| {
            (a.min(d), b.max(d))
        });
    let at = along(view.center);
    if at < a || at > b {
        return Err(SceneError::setting(
            "center",
            format!(
                "the slice plane through {:?} misses the data, whose bounds are {lo:?} to {hi:?} \
                 (along the plane's normal {:?} the data spans {a:.6e} to {b:.6e}, the plane is \
                 at {at:.6e})",
                view.center, view.normal
            ),
        ));
    }
    Ok(view)
}

/// Samples world points: `sample`'s rows on rank 0, `None` on the others.
pub type Sampler<'a, E> = dyn FnMut(&[[f64; 3]]) -> Result<Option<Vec<f32>>, E> + 'a;

/// A slice: its plane, the quantity's name and (rank 0) the values.
pub type Sliced = (ProjectionView, String, Option<Vec<f32>>);

/// Where a slice's data lies: its fields, bounds (the volume's frame) and
/// the frame.
pub struct Space<'a> {
    pub fields: &'a Fields,
    pub bounds: &'a Aabb,
    pub frame: &'a WorldFrame,
}

/// The slice `slice` describes of data in `space` at `w`×`h`, sampled
/// through `sample` (world points → `sample`'s rows, `None` on ranks other
/// than 0) in chunks of rows: its plane, the quantity's name and (where
/// `sample` gives values) the values, row-major. `progress` hears the rows
/// done of all. Every front-end slices through here.
pub fn slice_with<E: From<SceneError>>(
    space: &Space,
    desc: &SceneDesc,
    slice: &SliceDesc,
    (w, h): (u32, u32),
    sample: &mut Sampler<E>,
    progress: &dyn Fn(u64, u64),
) -> Result<Sliced, E> {
    let fields = space.fields;
    let (column, name) = quantity_column(fields, desc, slice.quantity.as_deref())?;
    let periodic = matches!(
        fields,
        Fields::Tets { .. }
            | Fields::Particles {
                periodic: Some(_),
                ..
            }
    );
    let view = slice_view(&slice.plane, space.bounds, space.frame, periodic)?;
    let columns = fields.columns(false).len();
    let mut values = Vec::new();
    let mut got = false;
    for rows in row_chunks(h) {
        let end = rows.end;
        let pts = slice_points(&view, (w, h), rows, slice.pixels);
        if let Some(s) = sample(&pts)? {
            got = true;
            values.extend(pixel_values(&s, columns, column, slice.pixels));
        }
        progress(end as u64, h as u64);
    }
    Ok((view, name, got.then_some(values)))
}

/// The sample points of rows `rows` of a `w`×`h` slice through `view`: one
/// per pixel centre, or 16 per pixel (row-major pixels, each pixel's
/// points consecutive) for [`SlicePixels::Area`].
pub fn slice_points(
    view: &ProjectionView,
    (w, h): (u32, u32),
    rows: std::ops::Range<u32>,
    pixels: SlicePixels,
) -> Vec<[f64; 3]> {
    let mut pts = Vec::new();
    for i in rows {
        for j in 0..w {
            match pixels {
                SlicePixels::Centre => pts.push(view.pixel_center(i, j, w, h)),
                SlicePixels::Area => {
                    let (pw, ph) = (view.width[0] / w as f64, view.width[1] / h as f64);
                    let c = view.pixel_center(i, j, w, h);
                    for (dy, _) in GAUSS4 {
                        for (dx, _) in GAUSS4 {
                            pts.push(std::array::from_fn(|a| {
                                c[a] + dx * pw * view.right[a] + dy * ph * view.up[a]
                            }));
                        }
                    }
                }
            }
        }
    }
    pts
}

/// Collapses one chunk's sampled rows (`columns` values per point) to the
/// pixel values of `column`: the value itself, or the Gauss–Legendre mean
/// of each pixel's 16 points (NaN where any point is outside AMR cells).
pub(crate) fn pixel_values(
    sampled: &[f32],
    columns: usize,
    column: usize,
    pixels: SlicePixels,
) -> Vec<f32> {
    let value = |p: usize| sampled[p * columns + column];
    match pixels {
        SlicePixels::Centre => (0..sampled.len() / columns).map(value).collect(),
        SlicePixels::Area => {
            let per = GAUSS4.len() * GAUSS4.len();
            (0..sampled.len() / columns / per)
                .map(|px| {
                    let mut sum = 0.0f64;
                    for (qy, (_, wy)) in GAUSS4.iter().enumerate() {
                        for (qx, (_, wx)) in GAUSS4.iter().enumerate() {
                            sum += wy * wx * value(px * per + qy * 4 + qx) as f64;
                        }
                    }
                    sum as f32
                })
                .collect()
        }
    }
}

/// The row chunks a `h`-row slice is sampled in.
pub(crate) fn row_chunks(h: u32) -> impl Iterator<Item = std::ops::Range<u32>> {
    (0..h)
        .step_by(ROWS_PER_CHUNK as usize)
        .map(move |r| r..(r + ROWS_PER_CHUNK).min(h))
}

/// How a slice looks as a picture: log or linear scale (default:
/// [`prefers_log`]), the value range (default: the values', at most
/// [`LOG_DECADES`] in log scale), a colour bar.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SliceLook {
    pub log: Option<bool>,
    pub range: Option<[f32; 2]>,
    pub colorbar: bool,
}

/// Whether slice `values` are best seen in log scale (see [`SliceLook`]):
/// none is negative and the maximum is more than two decades above the
/// positive values' median — clumpy fields (the cosmic web), not a fluid
/// whose kernel tails fade at its surface (the median, not the minimum,
/// so the fringe does not decide).
pub fn prefers_log(values: &[f32]) -> bool {
    if values.iter().any(|&v| v < 0.0) {
        return false;
    }
    let mut positive: Vec<f32> = values.iter().copied().filter(|&v| v > 0.0).collect();
    if positive.len() < 2 {
        return false;
    }
    positive.sort_unstable_by(f32::total_cmp);
    let at = |q: f64| positive[((positive.len() - 1) as f64 * q).round() as usize];
    at(1.0) > 100.0 * at(0.5)
}

/// Log-scale ranges reach at most this many decades below the maximum.
const LOG_DECADES: f32 = 6.0;

/// The picture of slice `values` (`w`×`h`) of the quantity `name`: colours
/// from the scene's transfer function's colormap (`transfer`, files
/// relative to `base`), as `look` says, with the colour bar drawn by the
/// library (so every front-end has the same). A `range` is in the values'
/// units (log scale maps its log10).
pub fn picture(
    values: &[f32],
    size: (u32, u32),
    transfer: &voxless_scene::TransferDesc,
    base: &std::path::Path,
    name: &str,
    look: &SliceLook,
) -> Result<voxless_core::Image, SceneError> {
    let log = look.log.unwrap_or_else(|| prefers_log(values));
    let range = match look.range {
        Some(r) if log => {
            if !(r[0] > 0.0 && r[1] > r[0]) {
                return Err(SceneError::setting(
                    "value range",
                    format!("{r:?}: a log-scale range must be positive and increasing"),
                ));
            }
            r.map(f32::log10)
        }
        Some(r) if !(r[1] > r[0] && r.iter().all(|v| v.is_finite())) => {
            return Err(SceneError::setting(
                "value range",
                format!("{r:?} must be finite and increasing"),
            ));
        }
        Some(r) => r,
        None => default_range(values, log)?,
    };
    let mut transfer = transfer.clone();
    // Slices are opaque: the colour bar shows colours only.
    transfer.opacity = Some("constant".into());
    transfer.opacity_points = None;
    let tf = crate::transfer_function_at(&transfer, base, &mut Vec::new())?;
    let mut image = colormapped(values, size, tf.colormap(), range, log);
    if look.colorbar {
        let spec = voxless_render::colorbar::ColorbarSpec {
            lo: range[0],
            hi: range[1],
            log10: log,
            label: Some(name.to_string()),
        };
        voxless_render::colorbar::draw_colorbar(&mut image, &tf, &spec);
    }
    Ok(image)
}

/// The colormapped image of slice `values` (`w`×`h`, row-major): each
/// value through `colormap` over `range` (in log10 of the value when
/// `log`), NaN and, in log scale, values ≤ 0 transparent.
pub fn colormapped(
    values: &[f32],
    (w, h): (u32, u32),
    colormap: &voxless_transfer::Colormap,
    range: [f32; 2],
    log: bool,
) -> voxless_core::Image {
    let mut image = voxless_core::Image::new(w, h);
    let span = range[1] - range[0];
    for (p, &v) in image.pixels.iter_mut().zip(values) {
        let x = if log {
            if v > 0.0 { v.log10() } else { f32::NAN }
        } else {
            v
        };
        if x.is_finite() {
            let t = if span > 0.0 {
                ((x - range[0]) / span).clamp(0.0, 1.0)
            } else {
                0.5
            };
            let c = colormap.linear(t);
            *p = [c.x, c.y, c.z, 1.0];
        }
    }
    image
}

/// The value range a colormapped slice shows by default: the finite
/// values' (in log10 for `log`, over positive values and at most
/// [`LOG_DECADES`] below the maximum), or an error naming what is missing
/// when there is none.
pub fn default_range(values: &[f32], log: bool) -> Result<[f32; 2], SceneError> {
    let mut r = [f32::INFINITY, f32::NEG_INFINITY];
    for &v in values {
        let x = if log { v.log10() } else { v };
        if x.is_finite() {
            r = [r[0].min(x), r[1].max(x)];
        }
    }
    if log {
        r[0] = r[0].max(r[1] - LOG_DECADES);
    }
    if r[0] <= r[1] {
        Ok(r)
    } else {
        Err(SceneError::setting(
            "value range",
            if log {
                "the slice has no positive value to show in log scale; give --linear or a \
                 --value-range"
            } else {
                "the slice has no finite value (it lies outside every AMR cell)"
            },
        ))
    }
}

#[cfg(test)]
#[path = "tests/slice.rs"]
mod tests;
