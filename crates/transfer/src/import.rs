//! Colormaps read from JSON files.
//!
//! Two layouts are understood:
//!
//! - **ParaView presets**, as ParaView's "Export preset" writes them: an array
//!   of objects (or a file holding one object) with `Name`, `RGBPoints`
//!   (`[x, r, g, b, x, r, g, b, …]`, x in data units over any range), and
//!   optionally `ColorSpace`, `Points` (opacity quads `[x, o, midpoint,
//!   sharpness, …]`) and `NanColor`. A preset is picked by name (exact, else
//!   ignoring case); without a name, the first preset that has `RGBPoints`.
//!   Other keys (`Creator`, `NanOpacity`, `IndexedColors`, …) are ignored.
//! - **matplotlib-style lists**: an array of `[r, g, b]` (evenly spaced over
//!   `[0, 1]`) or of `[x, r, g, b]`.
//!
//! The x coordinates are normalised to `[0, 1]` (their first value becomes 0,
//! their last 1); the value range the colour map is applied to comes from the
//! scene, as for the built-in presets. The opacity `Points` are normalised
//! with the `RGBPoints` range, so both keep their relative placement.
//!
//! Colours are sRGB components in `[0, 1]`, the same convention as the
//! scene's `colormap_points` and the built-in tables (ParaView and matplotlib
//! do no colour management, so their numbers are display values). They are
//! interpolated in sRGB and converted to linear RGB for compositing, so a
//! colour at a control point comes out exactly as the file gives it.
//!
//! `ColorSpace` decides how colours blend between control points: `RGB`
//! (also the default) interpolates the given components linearly; `Lab`
//! (and `Lab/CIEDE2000`) in CIELAB; `Diverging` in Moreland's Msh space
//! (saturated ends of distant hue pass through a near-white middle, as
//! ParaView's "Cool to Warm" does); `HSV` along the shorter way round the hue
//! circle; `Step` holds each colour until the next point. Every space but RGB
//! and Step is baked by inserting 31 interpolated sRGB points into each
//! segment. Opacity segments with a non-default midpoint or sharpness are
//! baked the same way, following ParaView's piecewise-function curve.
//!
//! `NanColor` is read and validated (and returned), but the renderers have
//! no NaN colour: values that are NaN are not drawn.
//!
//! Every problem is an [`ImportError`] naming the file and what is wrong:
//! malformed JSON, an unknown preset name (listing the names the file has),
//! components outside `[0, 1]`, x coordinates that decrease, lists of the
//! wrong length.

use std::path::{Path, PathBuf};

use serde_json::Value;

pub use crate::colorspace::ColorSpace;
use crate::{Colormap, OpacityMap};

/// Segments are baked into this many pieces when they are not straight lines.
const SUBDIVISIONS: usize = 32;

#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{path}: cannot read the colormap file: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: not valid JSON: {message}")]
    Json { path: PathBuf, message: String },
    #[error("{path}: no colormap named '{name}' in the file (it has: {})", names.join(", "))]
    UnknownPreset {
        path: PathBuf,
        name: String,
        names: Vec<String>,
    },
    #[error("{path}: {what}: {message}")]
    Invalid {
        path: PathBuf,
        what: String,
        message: String,
    },
}

/// A colormap read from a file.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedColormap {
    /// The preset's `Name`, or the file stem for a list.
    pub name: String,
    /// Colours over `[0, 1]`.
    pub colormap: Colormap,
    /// Opacity from the preset's `Points`, when it has them.
    pub opacity: Option<OpacityMap>,
    /// The preset's `NanColor` (sRGB), when it has one.
    pub nan_color: Option<[f32; 3]>,
    pub color_space: ColorSpace,
    /// The x range of the file's colour points before normalisation.
    pub data_range: [f64; 2],
}

/// Reads a colormap file; `name` picks a preset in a ParaView file.
pub fn read_colormap_file(
    path: &Path,
    name: Option<&str>,
) -> Result<ImportedColormap, ImportError> {
    let read = |source| ImportError::Read {
        path: path.to_path_buf(),
        source,
    };
    // A device or FIFO (/dev/zero) would never end; a colormap is a small
    // file, read up to a bound.
    let meta = std::fs::metadata(path).map_err(read)?;
    if !meta.is_file() {
        return Err(ImportError::Invalid {
            path: path.to_path_buf(),
            what: "colormap file".into(),
            message: "not a regular file (a directory, device or FIFO)".into(),
        });
    }
    const MAX_LEN: u64 = 64 << 20;
    if meta.len() > MAX_LEN {
        return Err(ImportError::Invalid {
            path: path.to_path_buf(),
            what: "colormap file".into(),
            message: format!(
                "{} bytes; a colormap file holds at most {MAX_LEN}",
                meta.len()
            ),
        });
    }
    let text = std::fs::read_to_string(path).map_err(read)?;
    parse_colormap_json(&text, name, path)
}

/// [`read_colormap_file`] on text already read; `path` is for messages (and
/// names a list's colormap).
pub fn parse_colormap_json(
    text: &str,
    name: Option<&str>,
    path: &Path,
) -> Result<ImportedColormap, ImportError> {
    let value: Value = serde_json::from_str(text).map_err(|e| ImportError::Json {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let file = File { path };
    match &value {
        Value::Object(_) => file.pick(std::slice::from_ref(&value), name),
        Value::Array(items) if items.is_empty() => {
            Err(file.invalid("file", "the array is empty: no colormaps"))
        }
        Value::Array(items) if items.iter().all(Value::is_object) => file.pick(items, name),
        Value::Array(items) if items.iter().all(Value::is_array) => match name {
            Some(n) => Err(file.invalid(
                "file",
                format!(
                    "it holds one colour list, which has no preset names, so '{n}' cannot be picked from it"
                ),
            )),
            None => file.list(items),
        },
        Value::Array(_) => Err(file.invalid(
            "file",
            "the array must hold either preset objects or [r, g, b] / [x, r, g, b] lists, not a mix",
        )),
        _ => Err(file.invalid(
            "file",
            "expected a ParaView preset (an object, or an array of objects) or an array of [r, g, b] colours",
        )),
    }
}

struct File<'a> {
    path: &'a Path,
}

/// The display name of preset `i`.
fn preset_name(v: &Value, i: usize) -> String {
    v.get("Name")
        .and_then(Value::as_str)
        .map(str::to_string)
        .unwrap_or_else(|| format!("#{i}"))
}

impl File<'_> {
    fn invalid(&self, what: impl Into<String>, message: impl Into<String>) -> ImportError {
        ImportError::Invalid {
            path: self.path.to_path_buf(),
            what: what.into(),
            message: message.into(),
        }
    }

    /// Chooses a preset by name, or the first with colours.
    fn pick(&self, items: &[Value], name: Option<&str>) -> Result<ImportedColormap, ImportError> {
        let names: Vec<String> = items
            .iter()
            .enumerate()
            .map(|(i, v)| preset_name(v, i))
            .collect();
        let index = match name {
            Some(want) => names
                .iter()
                .position(|n| n == want)
                .or_else(|| names.iter().position(|n| n.eq_ignore_ascii_case(want)))
                .ok_or_else(|| ImportError::UnknownPreset {
                    path: self.path.to_path_buf(),
                    name: want.to_string(),
                    names: names.clone(),
                })?,
            None => items
                .iter()
                .position(|v| v.get("RGBPoints").is_some())
                .ok_or_else(|| {
                    self.invalid(
                        "file",
                        "no preset has RGBPoints (indexed-colour and opacity-only presets are not supported)",
                    )
                })?,
        };
        self.preset(&items[index], &names[index])
    }

    /// An array of numbers.
    fn numbers(&self, v: &Value, what: &str) -> Result<Vec<f64>, ImportError> {
        let items = v
            .as_array()
            .ok_or_else(|| self.invalid(what, "expected an array of numbers"))?;
        items
            .iter()
            .enumerate()
            .map(|(i, x)| {
                x.as_f64()
                    .ok_or_else(|| self.invalid(what, format!("entry {i} ({x}) is not a number")))
            })
            .collect()
    }

    /// x coordinates mapped to `[0, 1]`, and their original range.
    fn normalise(&self, xs: &[f64], what: &str) -> Result<(Vec<f64>, [f64; 2]), ImportError> {
        for i in 1..xs.len() {
            if xs[i] < xs[i - 1] {
                return Err(self.invalid(
                    what,
                    format!(
                        "x must not decrease: point {i} has x = {} after {}",
                        xs[i],
                        xs[i - 1]
                    ),
                ));
            }
        }
        let (lo, hi) = (xs[0], xs[xs.len() - 1]);
        if xs.len() == 1 {
            return Ok((vec![0.0], [lo, hi]));
        }
        if !(hi > lo) {
            return Err(self.invalid(
                what,
                format!(
                    "all {} points have x = {lo}: there is no range to spread them over",
                    xs.len()
                ),
            ));
        }
        Ok((xs.iter().map(|x| (x - lo) / (hi - lo)).collect(), [lo, hi]))
    }

    /// Checks that every component is in `[0, 1]`.
    fn unit_colour(&self, c: [f64; 3], i: usize, what: &str) -> Result<(), ImportError> {
        if c.iter().all(|v| (0.0..=1.0).contains(v)) {
            return Ok(());
        }
        let hint = if c.iter().all(|v| (0.0..=255.0).contains(v)) {
            " (0–255 values? divide them by 255)"
        } else {
            ""
        };
        Err(self.invalid(
            what,
            format!(
                "colour {i} ({}, {}, {}) is outside [0, 1]{hint}",
                c[0], c[1], c[2]
            ),
        ))
    }

    fn preset(&self, v: &Value, name: &str) -> Result<ImportedColormap, ImportError> {
        let what = format!("preset '{name}'");
        let at = |key: &str| format!("{what} {key}");
        if let Some(n) = v.get("Name")
            && !n.is_string()
        {
            return Err(self.invalid(&what, "Name must be a string"));
        }
        let rgb = v
            .get("RGBPoints")
            .ok_or_else(|| self.invalid(&what, "has no RGBPoints"))?;
        let rgb = self.numbers(rgb, &at("RGBPoints"))?;
        if rgb.is_empty() || !rgb.len().is_multiple_of(4) {
            return Err(self.invalid(
                at("RGBPoints"),
                format!(
                    "expected x, r, g, b quadruples, found {} numbers",
                    rgb.len()
                ),
            ));
        }
        let space = match v.get("ColorSpace") {
            None => ColorSpace::Rgb,
            Some(s) => s.as_str().and_then(ColorSpace::parse).ok_or_else(|| {
                self.invalid(
                    at("ColorSpace"),
                    format!("{s} is not one of {}", ColorSpace::NAMES.join(", ")),
                )
            })?,
        };
        let xs: Vec<f64> = rgb.chunks_exact(4).map(|q| q[0]).collect();
        let colours: Vec<[f64; 3]> = rgb.chunks_exact(4).map(|q| [q[1], q[2], q[3]]).collect();
        for (i, c) in colours.iter().enumerate() {
            self.unit_colour(*c, i, &at("RGBPoints"))?;
        }
        let (xs, range) = self.normalise(&xs, &at("RGBPoints"))?;
        let colormap = self.colormap(name, &bake_colours(&xs, &colours, space))?;

        let opacity = match v.get("Points") {
            None => None,
            Some(p) => {
                Some(self.opacity(&self.numbers(p, &at("Points"))?, range, &at("Points"))?)
            }
        };
        let nan_color = match v.get("NanColor") {
            None => None,
            Some(c) => {
                let c = self.numbers(c, &at("NanColor"))?;
                if c.len() != 3 {
                    return Err(self.invalid(
                        at("NanColor"),
                        format!("expected [r, g, b], found {} numbers", c.len()),
                    ));
                }
                self.unit_colour([c[0], c[1], c[2]], 0, &at("NanColor"))?;
                Some([c[0] as f32, c[1] as f32, c[2] as f32])
            }
        };
        Ok(ImportedColormap {
            name: name.to_string(),
            colormap,
            opacity,
            nan_color,
            color_space: space,
            data_range: range,
        })
    }

    /// Opacity quads `[x, o, midpoint, sharpness]`, x normalised with the
    /// colour points' `range`.
    fn opacity(&self, q: &[f64], range: [f64; 2], what: &str) -> Result<OpacityMap, ImportError> {
        if q.is_empty() || !q.len().is_multiple_of(4) {
            return Err(self.invalid(
                what,
                format!(
                    "expected x, opacity, midpoint, sharpness quadruples, found {} numbers",
                    q.len()
                ),
            ));
        }
        let quads: Vec<&[f64]> = q.chunks_exact(4).collect();
        for (i, p) in quads.iter().enumerate() {
            for (k, label) in [(1, "opacity"), (2, "midpoint"), (3, "sharpness")] {
                if !(0.0..=1.0).contains(&p[k]) {
                    return Err(self.invalid(
                        what,
                        format!("point {i}: {label} {} is outside [0, 1]", p[k]),
                    ));
                }
            }
            if i > 0 && p[0] < quads[i - 1][0] {
                return Err(self.invalid(
                    what,
                    format!(
                        "x must not decrease: point {i} has x = {} after {}",
                        p[0],
                        quads[i - 1][0]
                    ),
                ));
            }
        }
        // One point, or colour points without a range: use the opacity
        // points' own range.
        let (lo, hi) = if range[1] > range[0] {
            (range[0], range[1])
        } else {
            let xs: Vec<f64> = quads.iter().map(|p| p[0]).collect();
            let (_, r) = self.normalise(&xs, what)?;
            (r[0], r[1])
        };
        let norm = |x: f64| if hi > lo { (x - lo) / (hi - lo) } else { 0.0 };
        let mut pts: Vec<(f32, f32)> = Vec::new();
        for (i, p) in quads.iter().enumerate() {
            let (x0, y0, mid, sharp) = (norm(p[0]), p[1], p[2], p[3]);
            pts.push((x0 as f32, y0 as f32));
            let Some(next) = quads.get(i + 1) else {
                continue;
            };
            let (x1, y1) = (norm(next[0]), next[1]);
            if !(x1 > x0) || (mid == 0.5 && sharp == 0.0) {
                continue;
            }
            if sharp >= 0.99 {
                // A step at the midpoint.
                let xm = (x0 + mid * (x1 - x0)) as f32;
                pts.push((xm, y0 as f32));
                pts.push((xm, y1 as f32));
                continue;
            }
            for k in 1..SUBDIVISIONS {
                let t = k as f64 / SUBDIVISIONS as f64;
                let y = piecewise_curve(y0, y1, mid, sharp, t);
                pts.push(((x0 + t * (x1 - x0)) as f32, y as f32));
            }
        }
        OpacityMap::from_points(&pts).map_err(|e| self.invalid(what, e.to_string()))
    }

    /// A matplotlib-style list of `[r, g, b]` or `[x, r, g, b]`.
    fn list(&self, items: &[Value]) -> Result<ImportedColormap, ImportError> {
        let rows: Vec<Vec<f64>> = items
            .iter()
            .enumerate()
            .map(|(i, v)| self.numbers(v, &format!("colour {i}")))
            .collect::<Result<_, _>>()?;
        let width = rows[0].len();
        if !(width == 3 || width == 4) {
            return Err(self.invalid(
                "colour list",
                format!("entries must be [r, g, b] or [x, r, g, b], the first has {width} numbers"),
            ));
        }
        if let Some(i) = rows.iter().position(|r| r.len() != width) {
            return Err(self.invalid(
                "colour list",
                format!(
                    "entry {i} has {} numbers but the first has {width}; use one form throughout",
                    rows[i].len()
                ),
            ));
        }
        let colours: Vec<[f64; 3]> = rows
            .iter()
            .map(|r| [r[width - 3], r[width - 2], r[width - 1]])
            .collect();
        for (i, c) in colours.iter().enumerate() {
            self.unit_colour(*c, i, "colour list")?;
        }
        let n = rows.len();
        let (xs, range) = if width == 4 {
            let xs: Vec<f64> = rows.iter().map(|r| r[0]).collect();
            self.normalise(&xs, "colour list")?
        } else {
            let xs = (0..n)
                .map(|i| {
                    if n > 1 {
                        i as f64 / (n - 1) as f64
                    } else {
                        0.0
                    }
                })
                .collect();
            (xs, [0.0, 1.0])
        };
        let name = self
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "custom".into());
        let colormap = self.colormap(&name, &bake_colours(&xs, &colours, ColorSpace::Rgb))?;
        Ok(ImportedColormap {
            name,
            colormap,
            opacity: None,
            nan_color: None,
            color_space: ColorSpace::Rgb,
            data_range: range,
        })
    }

    fn colormap(&self, name: &str, points: &[(f32, [f32; 3])]) -> Result<Colormap, ImportError> {
        let mut cm = Colormap::from_points(points)
            .map_err(|e| self.invalid(format!("colormap '{name}'"), e.to_string()))?;
        cm.name = name.to_string();
        Ok(cm)
    }
}

/// sRGB control points, with the segments of a non-RGB colour space baked
/// into short straight pieces.
fn bake_colours(xs: &[f64], colours: &[[f64; 3]], space: ColorSpace) -> Vec<(f32, [f32; 3])> {
    let f = |c: [f64; 3]| c.map(|v| v as f32);
    let mut out = Vec::with_capacity(xs.len() * SUBDIVISIONS);
    for i in 0..xs.len() {
        out.push((xs[i] as f32, f(colours[i])));
        let Some(&x1) = xs.get(i + 1) else {
            continue;
        };
        let x0 = xs[i];
        if !(x1 > x0) {
            continue;
        }
        match space {
            ColorSpace::Rgb => {}
            ColorSpace::Step => out.push((x1 as f32, f(colours[i]))),
            _ => {
                for k in 1..SUBDIVISIONS {
                    let t = k as f64 / SUBDIVISIONS as f64;
                    let c = space.mix(colours[i], colours[i + 1], t);
                    out.push(((x0 + t * (x1 - x0)) as f32, f(c)));
                }
            }
        }
    }
    out
}

/// ParaView's opacity curve between two points, at fraction `t`: the
/// midpoint moves where the value is halfway, the sharpness bends the
/// straight line towards a step (0 = linear, 1 = step).
fn piecewise_curve(y0: f64, y1: f64, mid: f64, sharp: f64, t: f64) -> f64 {
    let mid = mid.clamp(1e-5, 1.0 - 1e-5);
    let s = if t < mid {
        0.5 * t / mid
    } else {
        0.5 + 0.5 * (t - mid) / (1.0 - mid)
    };
    if sharp < 0.01 {
        return y0 + s * (y1 - y0);
    }
    let e = 1.0 + 10.0 * sharp;
    let s = if s < 0.5 {
        0.5 * (2.0 * s).powf(e)
    } else if s > 0.5 {
        1.0 - 0.5 * (2.0 * (1.0 - s)).powf(e)
    } else {
        s
    };
    // Cubic Hermite with both tangents flattened by the sharpness.
    let (s2, s3) = (s * s, s * s * s);
    let slope = (y1 - y0) * (1.0 - sharp);
    let y = (2.0 * s3 - 3.0 * s2 + 1.0) * y0
        + (-2.0 * s3 + 3.0 * s2) * y1
        + (s3 - 2.0 * s2 + s) * slope
        + (s3 - s2) * slope;
    y.clamp(0.0, 1.0)
}

#[cfg(test)]
#[path = "import_tests.rs"]
mod tests;
