//! A human-readable listing of any HDF5 file, for `voxless info`.

use std::fmt::{Display, Write};
use std::path::Path;

use hdf5_metno as h5;
use hdf5_metno::types::{
    FixedAscii, FixedUnicode, FloatSize, IntSize, TypeDescriptor, VarLenAscii, VarLenUnicode,
};

use super::{Hdf5File, shape_text, type_name};
use crate::IoError;

/// Datasets with more elements than this are listed without min/max.
const MINMAX_MAX_ELEMENTS: usize = 10_000_000;
/// Elements read for min/max over the whole file before it stops reading.
const MINMAX_BUDGET: usize = 200_000_000;
/// Groups nested deeper than this are not opened.
const MAX_DEPTH: usize = 32;
/// Groups and datasets listed before the listing stops.
const MAX_OBJECTS: usize = 10_000;
/// Attribute arrays longer than this are shown by shape only.
const MAX_ATTR_VALUES: usize = 16;
/// Longest attribute string shown in full.
const MAX_TEXT: usize = 120;
/// Longest fixed-length string read from an attribute.
const FIXED_TEXT: usize = 256;

/// Lists every group and dataset of the HDF5 file at `path` as an indented
/// tree: groups end in `/`; datasets show their shape and dtype and, when
/// numeric with at most 10 million elements, their min and max (NaNs left
/// out and counted); attributes (`@name = value`) show their values, arrays
/// up to 16 values and strings up to 120 characters. Soft and external
/// links are named, not followed; a group reached twice through hard links
/// is listed once. At most 10,000 objects are listed.
pub fn describe_hdf5(path: &Path) -> Result<String, IoError> {
    let f = Hdf5File::open(path)?;
    let mut d = Describer {
        f: &f,
        out: String::new(),
        objects: 0,
        budget: MINMAX_BUDGET,
        seen: Vec::new(),
        truncated: false,
    };
    let _ = writeln!(d.out, "{}: HDF5 file, {} bytes", path.display(), f.len);
    d.out.push_str("/\n");
    if let Ok(info) = f.root().loc_info() {
        d.seen.push(info.token);
    }
    d.attributes(f.root(), 1);
    d.group(f.root(), "", 1);
    if d.truncated {
        let _ = writeln!(d.out, "… listing stopped after {MAX_OBJECTS} objects");
    }
    Ok(d.out)
}

struct Describer<'a, 'p> {
    f: &'a Hdf5File<'p>,
    out: String,
    /// Groups and datasets listed so far.
    objects: usize,
    /// Elements min/max may still read.
    budget: usize,
    /// Groups already listed (hard links can make cycles).
    seen: Vec<h5::LocationToken>,
    truncated: bool,
}

impl Describer<'_, '_> {
    fn line(&mut self, depth: usize, text: impl Display) {
        let _ = writeln!(self.out, "{:width$}{text}", "", width = 2 * depth);
    }

    /// Lists the members of `group` (path `prefix`) at indentation `depth`.
    fn group(&mut self, group: &h5::Group, prefix: &str, depth: usize) {
        let links = match group.links(h5::IndexType::Name, h5::IterationOrder::Increasing) {
            Ok(links) => links,
            Err(e) => {
                self.line(depth, format!("(members unreadable: {e})"));
                return;
            }
        };
        for (name, info) in links {
            if self.objects >= MAX_OBJECTS {
                self.truncated = true;
                return;
            }
            self.objects += 1;
            let shown = printable(&name);
            let full = format!("{prefix}/{name}");
            match info.link_type {
                h5::LinkType::Soft => {
                    self.line(depth, format!("{shown} -> soft link (not followed)"));
                    continue;
                }
                h5::LinkType::External => {
                    self.line(depth, format!("{shown} -> external link (not followed)"));
                    continue;
                }
                h5::LinkType::Hard => {}
            }
            match group.loc_type_by_name(&name) {
                Ok(h5::LocationType::Group) => match group.group(&name) {
                    Ok(child) => self.subgroup(&child, &shown, &full, depth),
                    Err(e) => self.line(depth, format!("{shown}/ (unreadable: {e})")),
                },
                Ok(h5::LocationType::Dataset) => match group.dataset(&name) {
                    Ok(ds) => {
                        let text = self.dataset(&ds, &shown, &full);
                        self.line(depth, text);
                        self.attributes(&ds, depth + 1);
                    }
                    Err(e) => self.line(depth, format!("{shown} (unreadable: {e})")),
                },
                Ok(_) => self.line(depth, format!("{shown} (named datatype)")),
                Err(e) => self.line(depth, format!("{shown} (unreadable: {e})")),
            }
        }
    }

    fn subgroup(&mut self, child: &h5::Group, shown: &str, full: &str, depth: usize) {
        if let Ok(info) = child.loc_info() {
            if self.seen.contains(&info.token) {
                self.line(
                    depth,
                    format!("{shown}/ (hard link to a group listed above)"),
                );
                return;
            }
            self.seen.push(info.token);
        }
        self.line(depth, format!("{shown}/"));
        self.attributes(child, depth + 1);
        if depth >= MAX_DEPTH {
            self.line(depth + 1, "(nested too deeply; not listed)");
        } else {
            self.group(child, full, depth + 1);
        }
    }

    /// One line for a dataset: name, shape, dtype, storage, min/max.
    fn dataset(&mut self, ds: &h5::Dataset, shown: &str, full: &str) -> String {
        let shape = ds.shape();
        let mut text = format!("{shown}  {} {}", shape_text(&shape), type_name(ds));
        let filters = ds.filters();
        if !filters.is_empty() {
            let names: Vec<String> = filters.iter().map(|f| format!("{f:?}")).collect();
            let _ = write!(text, "  [{}]", names.join(", ").to_lowercase());
        }
        let count = ds.size();
        if count == 0 {
            text.push_str("  empty");
            return text;
        }
        if !super::is_numeric(ds) {
            return text;
        }
        if count > MINMAX_MAX_ELEMENTS || count > self.budget {
            text.push_str("  (min/max not computed: too many elements)");
            return text;
        }
        self.budget -= count;
        let stats = match ds.dtype().and_then(|t| t.to_descriptor()) {
            Ok(TypeDescriptor::Float(size)) => {
                let single = size == FloatSize::U4;
                self.f
                    .read_f64(ds, full)
                    .map(|(_, v)| float_stats(&v, single))
            }
            Ok(TypeDescriptor::Unsigned(IntSize::U8)) => ds
                .read_raw::<u64>()
                .map(|v| int_stats(&v))
                .map_err(|e| self.f.h5err(full, e)),
            _ => self.f.read_i64(ds, full).map(|(_, v)| int_stats(&v)),
        };
        match stats {
            Ok(s) => {
                text.push_str("  ");
                text.push_str(&s);
            }
            Err(e) => {
                let _ = write!(text, "  (unreadable: {})", error_message(&e));
            }
        }
        text
    }

    /// One line per attribute of `loc`.
    fn attributes(&mut self, loc: &h5::Location, depth: usize) {
        let names = match loc.attr_names() {
            Ok(names) => names,
            Err(e) => {
                self.line(depth, format!("(attributes unreadable: {e})"));
                return;
            }
        };
        for name in names {
            let value = match loc.attr(&name) {
                Ok(attr) => self.attr_value(&attr, &name),
                Err(e) => format!("(unreadable: {e})"),
            };
            self.line(depth, format!("@{} = {value}", printable(&name)));
        }
    }

    /// An attribute's value as text: numbers and strings in full when short,
    /// otherwise its shape and dtype.
    fn attr_value(&self, attr: &h5::Attribute, name: &str) -> String {
        let shape = attr.shape();
        let count = attr.size();
        let summary = || format!("{} {}", shape_text(&shape), type_name(attr));
        if count > MAX_ATTR_VALUES || count == 0 {
            return summary();
        }
        let Ok(desc) = attr.dtype().and_then(|t| t.to_descriptor()) else {
            return summary();
        };
        let texts: Result<Vec<String>, h5::Error> = match desc {
            TypeDescriptor::Float(size) => attr.read_raw::<f64>().map(|v| {
                v.iter()
                    .map(|&x| float_text(x, size == FloatSize::U4))
                    .collect()
            }),
            TypeDescriptor::Unsigned(IntSize::U8) => attr
                .read_raw::<u64>()
                .map(|v| v.iter().map(|x| x.to_string()).collect()),
            TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) => attr
                .read_raw::<i64>()
                .map(|v| v.iter().map(|x| x.to_string()).collect()),
            TypeDescriptor::Boolean => attr
                .read_raw::<u8>()
                .map(|v| v.iter().map(|&b| (b != 0).to_string()).collect()),
            TypeDescriptor::VarLenUnicode => attr
                .read_raw::<VarLenUnicode>()
                .map(|v| v.iter().map(|s| quoted(s.as_bytes())).collect()),
            TypeDescriptor::VarLenAscii => attr
                .read_raw::<VarLenAscii>()
                .map(|v| v.iter().map(|s| quoted(s.as_bytes())).collect()),
            TypeDescriptor::FixedAscii(_) => attr
                .read_raw::<FixedAscii<FIXED_TEXT>>()
                .map(|v| v.iter().map(|s| quoted(s.as_bytes())).collect()),
            TypeDescriptor::FixedUnicode(_) => attr
                .read_raw::<FixedUnicode<FIXED_TEXT>>()
                .map(|v| v.iter().map(|s| quoted(s.as_bytes())).collect()),
            _ => return summary(),
        };
        match texts {
            Ok(texts) if shape.is_empty() && texts.len() == 1 => texts[0].clone(),
            Ok(texts) => format!("[{}]", texts.join(", ")),
            Err(e) => format!("{} (unreadable: {})", summary(), self.f.h5err(name, e)),
        }
    }
}

/// "min A  max B" of integers.
fn int_stats<T: Copy + Ord + Display>(values: &[T]) -> String {
    match (values.iter().min(), values.iter().max()) {
        (Some(lo), Some(hi)) => format!("min {lo}  max {hi}"),
        _ => "empty".to_string(),
    }
}

/// A float in its shortest round-trip form (as `f32` when the file stores
/// single precision), with an exponent when very large or small.
fn float_text(v: f64, single: bool) -> String {
    let magnitude = v.abs();
    let exponent = v != 0.0 && v.is_finite() && !(1e-4..1e16).contains(&magnitude);
    match (single, exponent) {
        (true, false) => format!("{}", v as f32),
        (true, true) => format!("{:e}", v as f32),
        (false, false) => format!("{v}"),
        (false, true) => format!("{v:e}"),
    }
}

/// "min A  max B" of floats, NaNs left out and counted; `single` when the
/// file stores them as `f32`.
fn float_stats(values: &[f64], single: bool) -> String {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut nans = 0usize;
    for &v in values {
        if v.is_nan() {
            nans += 1;
        } else {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if nans == values.len() {
        return "all NaN".to_string();
    }
    let mut text = format!(
        "min {}  max {}",
        float_text(lo, single),
        float_text(hi, single)
    );
    if nans > 0 {
        let _ = write!(text, "  ({nans} NaN)");
    }
    text
}

/// A string value in double quotes, cut at [`MAX_TEXT`] characters.
fn quoted(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    let text = text.trim_end_matches(['\0', ' ']);
    let mut shown: String = text.chars().take(MAX_TEXT).collect();
    if shown.len() < text.len() {
        shown.push('…');
    }
    format!("{shown:?}")
}

/// A name with control characters escaped, so a hostile name cannot break
/// the layout.
fn printable(name: &str) -> String {
    if name.chars().any(char::is_control) {
        name.escape_debug().to_string()
    } else {
        name.to_string()
    }
}

/// The message of an error without the file name (the listing names it once).
fn error_message(e: &IoError) -> String {
    match e {
        IoError::Format { message, .. } => message.clone(),
        other => other.to_string(),
    }
}
