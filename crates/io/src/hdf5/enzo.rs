//! Enzo outputs (packed HDF5, text hierarchy) as AMR leaf cells.
//!
//! An Enzo dump `DD0003/data0003` is three kinds of file:
//!
//! - the parameter file `data0003` (`Key = value` lines): `TopGridDimensions`,
//!   `DomainLeftEdge`, `DomainRightEdge`, `InitialTime` (the dump's time),
//!   `RefineBy`, and `DataLabel[i] = <field name>` for the baryon fields;
//! - the hierarchy `data0003.hierarchy`: one block per grid, starting
//!   `Grid = N`, with `GridRank`, `GridDimension` (zones including ghost
//!   zones), `GridStartIndex` and `GridEndIndex` (the active zones, 0-based,
//!   inclusive), `GridLeftEdge`, `GridRightEdge`, optionally `Level`,
//!   `NumberOfBaryonFields` and `BaryonFileName` (relative to the
//!   hierarchy's directory);
//! - the HDF5 files `data0003.cpuNNNN`, holding for grid N a group
//!   `/Grid%08d` with one (nz, ny, nx) dataset per field, x fastest: the
//!   active zones, or all of `GridDimension` with the ghost zones.
//!
//! Grids of all levels are in the output, properly nested; the cells that
//! grids one level finer cover are dropped, so only leaves remain. Fields
//! are the `DataLabel`s of the parameter file in order (without any, the
//! 3-D datasets of the first grid, except `particle_*`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::amr_blocks::{
    Block, Layout, leaf_masks, on_lattice, push_cells, push_values, same_width,
};
use super::{Hdf5File, shape_text};
use crate::IoError;
use crate::amr::{AmrCellData, MAX_LEVEL};

/// Reads the Enzo output whose parameter file is `path` (e.g.
/// `DD0003/data0003`; the hierarchy is `path` + `.hierarchy`) as leaf
/// cells, one field per baryon field, named as Enzo names it (`Density`,
/// `TotalEnergy`, …).
///
/// Fails, naming the file (and the line, for text), when the parameter file
/// or hierarchy lacks an entry it needs or holds a malformed one, when the
/// output is not 3-D with refinement factor 2, when cells are not cubic or a
/// grid's width does not match its level, when grids of one level overlap
/// or a grid is not properly nested, when a grid's HDF5 file is missing
/// (naming it), and when a grid's group or field dataset is missing or has
/// the wrong shape (naming the file and dataset).
pub fn read_enzo(path: &Path) -> Result<AmrCellData, IoError> {
    let params = Params::parse(path, &read_text(path)?)?;
    let mut hname = path.as_os_str().to_owned();
    hname.push(".hierarchy");
    let hpath = PathBuf::from(hname);
    let grids = parse_hierarchy(&hpath, &read_text(&hpath)?)?;
    let herr = |m: String| IoError::format(&hpath, m);
    if grids.is_empty() {
        return Err(herr("no grids (no `Grid = N` lines)".into()));
    }

    // Levels and cell widths against the root grid's.
    let root_dx: [f64; 3] =
        std::array::from_fn(|d| (params.right[d] - params.left[d]) / params.top[d] as f64);
    if !root_dx.iter().all(|w| w.is_finite() && *w > 0.0) {
        return Err(IoError::format(
            path,
            "DomainLeftEdge, DomainRightEdge and TopGridDimensions do not give positive cell \
             widths",
        ));
    }
    if !(same_width(root_dx[0], root_dx[1]) && same_width(root_dx[0], root_dx[2])) {
        return Err(IoError::format(
            path,
            format!(
                "root cells are {} × {} × {}: non-cubic cells are not supported",
                root_dx[0], root_dx[1], root_dx[2]
            ),
        ));
    }
    let mut levels = Vec::with_capacity(grids.len());
    for g in &grids {
        let dx: [f64; 3] = std::array::from_fn(|d| (g.right[d] - g.left[d]) / g.active(d) as f64);
        for (d, w) in dx.iter().enumerate() {
            if !(w.is_finite() && *w > 0.0 && g.left[d].is_finite()) {
                return Err(herr(format!(
                    "grid {} (line {}): GridLeftEdge and GridRightEdge do not give a positive \
                     width along axis {d}",
                    g.id, g.line
                )));
            }
        }
        if !(same_width(dx[0], dx[1]) && same_width(dx[0], dx[2])) {
            return Err(herr(format!(
                "grid {} (line {}) has cells of {} × {} × {}: non-cubic cells are not supported",
                g.id, g.line, dx[0], dx[1], dx[2]
            )));
        }
        let ratio = root_dx[0] / dx[0];
        let level = match g.level {
            Some(l) => l,
            None => ratio.log2().round() as i64,
        };
        if !(0..=i64::from(MAX_LEVEL)).contains(&level) {
            return Err(herr(format!(
                "grid {} (line {}): level {level} is outside 0..={MAX_LEVEL}",
                g.id, g.line
            )));
        }
        if !same_width(ratio, (1u64 << level) as f64) {
            return Err(herr(format!(
                "grid {} (line {}) has cells {} wide, which is not the root cell width {} over \
                 2^{level}{}",
                g.id,
                g.line,
                dx[0],
                root_dx[0],
                if g.level.is_some() {
                    " (its Level)"
                } else {
                    " for any level"
                }
            )));
        }
        levels.push(level);
    }
    let max_level = levels.iter().copied().max().unwrap_or(0);
    let finest = root_dx[0] / (1u64 << max_level) as f64;
    let origin = params.left;
    let mut blocks = Vec::with_capacity(grids.len());
    for (g, &level) in grids.iter().zip(&levels) {
        let mut lo = [0i64; 3];
        for d in 0..3 {
            lo[d] = on_lattice(g.left[d], origin[d], finest).ok_or_else(|| {
                herr(format!(
                    "grid {} (line {}): GridLeftEdge {} along axis {d} is not on the finest cell \
                     lattice (domain edge {}, finest cell {finest})",
                    g.id, g.line, g.left[d], origin[d]
                ))
            })?;
        }
        let dims = std::array::from_fn(|d| g.active(d) as usize);
        let block = Block::new(lo, dims, (max_level - level) as u32).map_err(|m| {
            herr(format!(
                "grid {} (line {}, level {level}) {m}",
                g.id, g.line
            ))
        })?;
        blocks.push(block);
    }

    // The grid files, in order of first appearance, and their grids.
    let dir = hpath
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut files: Vec<PathBuf> = Vec::new();
    let mut by_file: Vec<Vec<usize>> = Vec::new();
    let mut file_slot: HashMap<PathBuf, usize> = HashMap::new();
    for (k, g) in grids.iter().enumerate() {
        let rel = Path::new(&g.file);
        let direct = dir.join(rel.strip_prefix(".").unwrap_or(rel));
        let file = if direct.exists() {
            direct
        } else {
            // Enzo often names the files relative to the run's directory
            // (./DD0003/data0003.cpu0000); yt looks next to the hierarchy.
            match Path::new(&g.file).file_name().map(|n| dir.join(n)) {
                Some(beside) if beside.exists() => beside,
                _ => {
                    return Err(IoError::format(
                        &direct,
                        format!(
                            "grid file is missing (BaryonFileName of grid {} in {})",
                            g.id,
                            hpath.display()
                        ),
                    ));
                }
            }
        };
        let slot = *file_slot.entry(file.clone()).or_insert_with(|| {
            files.push(file);
            by_file.push(Vec::new());
            files.len() - 1
        });
        by_file[slot].push(k);
    }

    // Check every grid's group and datasets before allocating anything.
    let mut labels = params.labels.clone();
    for (file, members) in files.iter().zip(&by_file) {
        let f = Hdf5File::open(file)?;
        for &k in members {
            let g = &grids[k];
            let gname = format!("Grid{:08}", g.id);
            let group = f.child_group(f.root(), &gname).ok_or_else(|| {
                f.err(format!(
                    "group /{gname} is missing (grid {} of {})",
                    g.id,
                    hpath.display()
                ))
            })?;
            if labels.is_empty() {
                labels = f
                    .member_names(&group, &gname)?
                    .into_iter()
                    .filter(|n| {
                        !n.starts_with("particle")
                            && f.child_dataset(&group, n).is_some_and(|d| d.ndim() == 3)
                    })
                    .collect();
                if labels.is_empty() {
                    return Err(f.err(format!(
                        "group /{gname} holds no 3-D field datasets, and the parameter file \
                         names no fields (DataLabel)"
                    )));
                }
            }
            for name in &labels {
                let full = format!("/{gname}/{name}");
                let ds = f.child_dataset(&group, name).ok_or_else(|| {
                    f.err(format!(
                        "dataset {full} is missing (field {name} of grid {})",
                        g.id
                    ))
                })?;
                let shape = ds.shape();
                g.layout(&shape).ok_or_else(|| {
                    f.err(format!(
                        "dataset {full}: expected shape {} (active zones) or {} (with ghost \
                         zones), found {}",
                        shape_text(&g.active_shape()),
                        shape_text(&g.full_shape()),
                        shape_text(&shape)
                    ))
                })?;
                f.checked_count(
                    &ds,
                    &shape,
                    !ds.filters().is_empty(),
                    &format!("dataset {full}"),
                )?;
            }
        }
    }

    let masks = leaf_masks(&blocks, Layout::Nested, &|k| {
        format!("grid {} (level {})", grids[k].id, levels[k])
    })
    .map_err(herr)?;

    let kept: usize = blocks
        .iter()
        .zip(&masks)
        .map(|(b, m)| match m {
            None => b.cell_count(),
            Some(m) => m.iter().filter(|k| **k).count(),
        })
        .sum();
    let mut cells = Vec::with_capacity(kept);
    let mut values: Vec<Vec<f32>> = labels.iter().map(|_| Vec::with_capacity(kept)).collect();
    for (file, members) in files.iter().zip(&by_file) {
        let f = Hdf5File::open(file)?;
        for &k in members {
            let g = &grids[k];
            let mask = masks[k].as_deref();
            push_cells(&mut cells, &blocks[k], mask);
            let gname = format!("Grid{:08}", g.id);
            let group = f
                .child_group(f.root(), &gname)
                .ok_or_else(|| f.err(format!("group /{gname} is missing")))?;
            for (name, out) in labels.iter().zip(values.iter_mut()) {
                let full = format!("/{gname}/{name}");
                let ds = f.required_dataset(&group, name, &full)?;
                let data = f.read_f32(&ds, &full)?;
                let active = match g.layout(&data.shape) {
                    Some(false) => data.data,
                    Some(true) => g.cut_active(&data.data),
                    None => return Err(f.err(format!("dataset {full} changed shape"))),
                };
                push_values(out, &active, mask);
            }
        }
    }
    Ok(AmrCellData {
        cells,
        fields: labels.into_iter().zip(values).collect(),
        origin,
        finest_cell_size: finest,
        time: params.time,
    })
}

/// A text file's contents (invalid UTF-8 replaced).
fn read_text(path: &Path) -> Result<String, IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// `Key = value` lines: (line number, key, value), comments (`#`, `//`)
/// and other lines left out.
fn entries(text: &str) -> impl Iterator<Item = (usize, &str, &str)> {
    text.lines().enumerate().filter_map(|(k, line)| {
        let line = line.split("//").next().unwrap_or("");
        let line = line.split('#').next().unwrap_or("");
        let (key, value) = line.split_once('=')?;
        Some((k + 1, key.trim(), value.trim()))
    })
}

/// `N` whitespace-separated numbers of `value`, or an error message.
fn numbers<T: std::str::FromStr, const N: usize>(key: &str, value: &str) -> Result<[T; N], String> {
    let words: Vec<&str> = value.split_whitespace().collect();
    let bad = || format!("{key} = {value}: expected {N} number(s)");
    if words.len() < N {
        return Err(bad());
    }
    let mut out = Vec::with_capacity(N);
    for w in &words[..N] {
        out.push(w.parse::<T>().map_err(|_| bad())?);
    }
    out.try_into().map_err(|_| bad())
}

/// What the reader needs from the parameter file.
struct Params {
    left: [f64; 3],
    right: [f64; 3],
    top: [u64; 3],
    time: Option<f64>,
    labels: Vec<String>,
}

impl Params {
    fn parse(path: &Path, text: &str) -> Result<Params, IoError> {
        let err = |line: usize, m: String| IoError::format(path, format!("line {line}: {m}"));
        let (mut left, mut right, mut top, mut time) = (None, None, None, None);
        let mut labels: Vec<(usize, String)> = Vec::new();
        for (line, key, value) in entries(text) {
            match key {
                "TopGridRank" => {
                    let [rank] = numbers::<i64, 1>(key, value).map_err(|m| err(line, m))?;
                    if rank != 3 {
                        return Err(err(
                            line,
                            format!("TopGridRank is {rank}; only 3-D outputs are supported"),
                        ));
                    }
                }
                "RefineBy" => {
                    let [by] = numbers::<f64, 1>(key, value).map_err(|m| err(line, m))?;
                    if by != 2.0 {
                        return Err(err(
                            line,
                            format!("RefineBy is {by}; only refinement by 2 is supported"),
                        ));
                    }
                }
                "DomainLeftEdge" => left = Some(numbers(key, value).map_err(|m| err(line, m))?),
                "DomainRightEdge" => right = Some(numbers(key, value).map_err(|m| err(line, m))?),
                "TopGridDimensions" => {
                    let dims: [u64; 3] = numbers(key, value).map_err(|m| err(line, m))?;
                    if dims.iter().any(|&n| n == 0 || n > 1 << 31) {
                        return Err(err(
                            line,
                            format!("TopGridDimensions = {value}: not grid sizes"),
                        ));
                    }
                    top = Some(dims);
                }
                "InitialTime" => {
                    let [t] = numbers::<f64, 1>(key, value).map_err(|m| err(line, m))?;
                    time = Some(t);
                }
                _ => {
                    if let Some(index) = key
                        .strip_prefix("DataLabel[")
                        .and_then(|r| r.strip_suffix(']'))
                    {
                        let index: usize = index
                            .trim()
                            .parse()
                            .map_err(|_| err(line, format!("{key}: not an index")))?;
                        let name = value.split_whitespace().next().unwrap_or("");
                        if name.is_empty() {
                            return Err(err(line, format!("{key} is empty")));
                        }
                        labels.retain(|(i, _)| *i != index);
                        labels.push((index, name.to_string()));
                    }
                }
            }
        }
        let missing = |key: &str| IoError::format(path, format!("{key} is missing"));
        labels.sort_by_key(|(i, _)| *i);
        Ok(Params {
            left: left.ok_or_else(|| missing("DomainLeftEdge"))?,
            right: right.ok_or_else(|| missing("DomainRightEdge"))?,
            top: top.ok_or_else(|| missing("TopGridDimensions"))?,
            time,
            labels: labels.into_iter().map(|(_, n)| n).collect(),
        })
    }
}

/// One grid of the hierarchy.
struct Grid {
    id: u64,
    /// Line of its `Grid = N`.
    line: usize,
    dim: [i64; 3],
    start: [i64; 3],
    end: [i64; 3],
    left: [f64; 3],
    right: [f64; 3],
    level: Option<i64>,
    file: String,
}

impl Grid {
    /// Active zones along axis `d`.
    fn active(&self, d: usize) -> i64 {
        self.end[d] - self.start[d] + 1
    }

    /// (nz, ny, nx) of the active zones.
    fn active_shape(&self) -> [usize; 3] {
        std::array::from_fn(|k| self.active(2 - k) as usize)
    }

    /// (nz, ny, nx) of all zones.
    fn full_shape(&self) -> [usize; 3] {
        std::array::from_fn(|k| self.dim[2 - k] as usize)
    }

    /// Whether a dataset of `shape` holds the ghost zones (`Some(true)`),
    /// only the active ones (`Some(false)`), or neither (`None`).
    fn layout(&self, shape: &[usize]) -> Option<bool> {
        if shape == self.active_shape() {
            Some(false)
        } else if shape == self.full_shape() {
            Some(true)
        } else {
            None
        }
    }

    /// The active zones of data with ghost zones.
    fn cut_active(&self, data: &[f32]) -> Vec<f32> {
        let [_, fy, fx] = self.full_shape();
        let [nz, ny, nx] = self.active_shape();
        let [sx, sy, sz] = self.start.map(|s| s as usize);
        let mut out = Vec::with_capacity(nx * ny * nz);
        for z in sz..sz + nz {
            for y in sy..sy + ny {
                let row = (z * fy + y) * fx + sx;
                out.extend_from_slice(&data[row..row + nx]);
            }
        }
        out
    }
}

/// The grids of a hierarchy file, checked for completeness and index
/// sanity.
fn parse_hierarchy(path: &Path, text: &str) -> Result<Vec<Grid>, IoError> {
    let err = |line: usize, m: String| IoError::format(path, format!("line {line}: {m}"));

    #[derive(Default)]
    struct Partial {
        id: u64,
        line: usize,
        rank: Option<i64>,
        dim: Option<[i64; 3]>,
        start: Option<[i64; 3]>,
        end: Option<[i64; 3]>,
        left: Option<[f64; 3]>,
        right: Option<[f64; 3]>,
        level: Option<i64>,
        fields: Option<i64>,
        file: Option<String>,
    }
    let mut partial: Vec<Partial> = Vec::new();
    for (line, key, value) in entries(text) {
        if key == "Grid" {
            let [id] = numbers::<u64, 1>(key, value).map_err(|m| err(line, m))?;
            partial.push(Partial {
                id,
                line,
                ..Partial::default()
            });
            continue;
        }
        let Some(g) = partial.last_mut() else {
            continue;
        };
        let e = |m| err(line, m);
        match key {
            "GridRank" => g.rank = Some(numbers::<i64, 1>(key, value).map_err(e)?[0]),
            "GridDimension" => g.dim = Some(numbers(key, value).map_err(e)?),
            "GridStartIndex" => g.start = Some(numbers(key, value).map_err(e)?),
            "GridEndIndex" => g.end = Some(numbers(key, value).map_err(e)?),
            "GridLeftEdge" => g.left = Some(numbers(key, value).map_err(e)?),
            "GridRightEdge" => g.right = Some(numbers(key, value).map_err(e)?),
            "Level" => g.level = Some(numbers::<i64, 1>(key, value).map_err(e)?[0]),
            "NumberOfBaryonFields" => {
                g.fields = Some(numbers::<i64, 1>(key, value).map_err(e)?[0]);
            }
            "BaryonFileName" => {
                let name = value.split_whitespace().next().unwrap_or("");
                if name.is_empty() {
                    return Err(err(line, "BaryonFileName is empty".into()));
                }
                g.file = Some(name.to_string());
            }
            _ => {}
        }
    }

    let mut seen = HashMap::new();
    let mut grids = Vec::with_capacity(partial.len());
    for p in partial {
        let what = format!("grid {} (line {})", p.id, p.line);
        if let Some(first) = seen.insert(p.id, p.line) {
            return Err(IoError::format(
                path,
                format!("{what}: grid {} already appears on line {first}", p.id),
            ));
        }
        let need = |key: &str| IoError::format(path, format!("{what} has no {key}"));
        if let Some(rank) = p.rank
            && rank != 3
        {
            return Err(IoError::format(
                path,
                format!("{what}: GridRank is {rank}; only 3-D outputs are supported"),
            ));
        }
        if p.fields == Some(0) {
            return Err(IoError::format(
                path,
                format!("{what} has no baryon fields (NumberOfBaryonFields = 0)"),
            ));
        }
        let grid = Grid {
            id: p.id,
            line: p.line,
            dim: p.dim.ok_or_else(|| need("GridDimension"))?,
            start: p.start.ok_or_else(|| need("GridStartIndex"))?,
            end: p.end.ok_or_else(|| need("GridEndIndex"))?,
            left: p.left.ok_or_else(|| need("GridLeftEdge"))?,
            right: p.right.ok_or_else(|| need("GridRightEdge"))?,
            level: p.level,
            file: p.file.ok_or_else(|| need("BaryonFileName"))?,
        };
        for d in 0..3 {
            let (s, e, n) = (grid.start[d], grid.end[d], grid.dim[d]);
            if !(0 <= s && s <= e && e < n && n <= 1 << 31) {
                return Err(IoError::format(
                    path,
                    format!(
                        "{what}: GridStartIndex {s} and GridEndIndex {e} along axis {d} are not \
                         inside GridDimension {n}"
                    ),
                ));
            }
        }
        grids.push(grid);
    }
    Ok(grids)
}
