//! AMReX/BoxLib plotfiles (Castro, Nyx, WarpX, MAESTROeX, PeleC, …): a
//! directory holding a text `Header` and, per level, `Level_N/Cell_H` (the
//! multi-FAB header: the level's boxes and where each box's data lies) plus
//! `Level_N/Cell_D_NNNNN` data files.
//!
//! The layout read here is AMReX's plotfile writer
//! (`amrex::WriteMultiLevelPlotfile`, header version `HyperCLaw-V1.1`):
//!
//! - `Header`: version line, component count and names, space dimension,
//!   time, finest level, `prob_lo`, `prob_hi`, the refinement ratio per
//!   level jump, each level's domain box, step counts, each level's cell
//!   widths, coordinate system and boundary width, then per level its box
//!   count, time, step, one `lo hi` physical line per box and axis, and the
//!   path of its multi-FAB (`Level_N/Cell`).
//! - `Cell_H` (a `VisMF` header): version, how written, component count,
//!   ghost width, the box array `(n 0 ((lo) (hi) (type)) … )`, then `n` and
//!   one `FabOnDisk: FILE OFFSET` line per box (min/max tables follow).
//! - Each FAB at its offset: a text line `FAB ((8, (64 11 52 0 1 12 0
//!   1023)),(8, (8 7 6 5 4 3 2 1)))((lo) (hi) (type)) ncomp` — the real
//!   descriptor (bytes per value, its bit layout, its byte order: 8…1 is
//!   little-endian, 1…8 big-endian) and the box — then the values,
//!   component after component, x fastest.
//!
//! Cells of a level that the next finer level covers are dropped (every
//! AMReX level is written whole), so the result holds only leaf cells.
//! Refinement ratios must be powers of two (cell widths in finest units
//! are then powers of two, the ExaBricks convention).

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufRead, BufReader, Cursor, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use super::{AmrCellData, MAX_LEVEL};
use crate::IoError;

/// The longest text header accepted (the box lists of a large run are
/// long, but text).
const MAX_HEADER: u64 = 1 << 30;

/// One box: inclusive lower and upper cell indices on its level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct IBox {
    lo: [i64; 3],
    hi: [i64; 3],
}

impl IBox {
    fn size(&self) -> [i64; 3] {
        [0, 1, 2].map(|a| self.hi[a] - self.lo[a] + 1)
    }

    fn cells(&self) -> i64 {
        self.size().iter().product()
    }

    /// The cell count, `None` when it does not fit 64 bits.
    fn checked_cells(&self) -> Option<u64> {
        self.size()
            .iter()
            .try_fold(1u64, |n, &s| n.checked_mul(u64::try_from(s).ok()?))
    }

    fn coarsen(&self, r: i64) -> IBox {
        IBox {
            lo: self.lo.map(|v| v.div_euclid(r)),
            hi: self.hi.map(|v| v.div_euclid(r)),
        }
    }

    fn overlap(&self, o: &IBox) -> Option<IBox> {
        let lo = [0, 1, 2].map(|a| self.lo[a].max(o.lo[a]));
        let hi = [0, 1, 2].map(|a| self.hi[a].min(o.hi[a]));
        (0..3).all(|a| lo[a] <= hi[a]).then_some(IBox { lo, hi })
    }
}

/// A file of a plotfile, read in order and at offsets.
trait Source: BufRead + Seek {}
impl<T: BufRead + Seek> Source for T {}

/// Where a plotfile's files come from: a directory on disk, or named byte
/// slices in memory (the same parsing and checks for both).
trait Files {
    /// The name errors give file `rel` (relative to the plotfile).
    fn label(&self, rel: &Path) -> PathBuf;
    /// File `rel` to read, and its length.
    fn open(&self, rel: &Path) -> Result<(Box<dyn Source + '_>, u64), IoError>;
}

/// A plotfile directory.
struct Dir<'a>(&'a Path);

impl Files for Dir<'_> {
    fn label(&self, rel: &Path) -> PathBuf {
        self.0.join(rel)
    }
    fn open(&self, rel: &Path) -> Result<(Box<dyn Source + '_>, u64), IoError> {
        let path = self.label(rel);
        let f = File::open(&path).map_err(|e| IoError::io(&path, e))?;
        let len = f.metadata().map_err(|e| IoError::io(&path, e))?.len();
        Ok((Box::new(BufReader::with_capacity(1 << 20, f)), len))
    }
}

/// A plotfile in memory: each file's path relative to the plotfile
/// (`Header`, `Level_0/Cell_H`, …) with its bytes; `root` names it.
struct Memory<'a> {
    root: &'a Path,
    files: &'a [(&'a str, &'a [u8])],
}

impl Files for Memory<'_> {
    fn label(&self, rel: &Path) -> PathBuf {
        self.root.join(rel)
    }
    fn open(&self, rel: &Path) -> Result<(Box<dyn Source + '_>, u64), IoError> {
        match self.files.iter().find(|(n, _)| Path::new(n) == rel) {
            Some((_, bytes)) => Ok((Box::new(Cursor::new(*bytes)), bytes.len() as u64)),
            None => Err(IoError::io(
                &self.label(rel),
                std::io::Error::new(std::io::ErrorKind::NotFound, "No such file"),
            )),
        }
    }
}

/// Whitespace-separated tokens of a text file, with the line of each
/// (errors name the file and line).
struct Tokens {
    path: PathBuf,
    /// Each token with its line number (from 1).
    items: Vec<(String, usize)>,
    next: usize,
}

impl Tokens {
    /// The text file `rel` of the plotfile.
    fn read(files: &dyn Files, rel: &Path) -> Result<Tokens, IoError> {
        let path = files.label(rel);
        let (mut reader, len) = files.open(rel)?;
        if len > MAX_HEADER {
            return Err(IoError::format(
                &path,
                format!("{len} bytes is too long for a plotfile header"),
            ));
        }
        let mut text = String::new();
        reader
            .read_to_string(&mut text)
            .map_err(|e| match e.kind() {
                std::io::ErrorKind::InvalidData => {
                    IoError::format(&path, "is not text (invalid UTF-8)")
                }
                _ => IoError::io(&path, e),
            })?;
        Ok(Tokens::from_text(&text, &path))
    }

    fn from_text(text: &str, path: &Path) -> Tokens {
        // Box syntax `((0,0,0) (15,15,15) (0,0,0))` splits into numbers:
        // parentheses and commas are separators too.
        let items = text
            .lines()
            .enumerate()
            .flat_map(|(i, l)| {
                l.split(|c: char| c.is_ascii_whitespace() || c == '(' || c == ')' || c == ',')
                    .filter(|t| !t.is_empty())
                    .map(move |t| (t.to_string(), i + 1))
            })
            .collect();
        Tokens {
            path: path.to_path_buf(),
            items,
            next: 0,
        }
    }

    fn error(&self, message: impl std::fmt::Display) -> IoError {
        let line = self
            .items
            .get(self.next.saturating_sub(1))
            .map_or(0, |t| t.1);
        IoError::format(&self.path, format!("line {line}: {message}"))
    }

    fn word(&mut self, what: &str) -> Result<&str, IoError> {
        match self.items.get(self.next) {
            Some(_) => {
                self.next += 1;
                Ok(&self.items[self.next - 1].0)
            }
            None => Err(IoError::format(&self.path, format!("ends before {what}"))),
        }
    }

    /// Whether the next token is on the line of the last one read.
    fn on_same_line(&self) -> bool {
        self.next > 0
            && self
                .items
                .get(self.next)
                .is_some_and(|t| t.1 == self.items[self.next - 1].1)
    }

    fn int(&mut self, what: &str) -> Result<i64, IoError> {
        let w = self.word(what)?.to_string();
        w.parse()
            .map_err(|_| self.error(format!("{what}: `{w}` is not an integer")))
    }

    fn count(&mut self, what: &str, max: i64) -> Result<usize, IoError> {
        let n = self.int(what)?;
        if !(0..=max).contains(&n) {
            return Err(self.error(format!("{what} {n} is out of range (0..={max})")));
        }
        Ok(n as usize)
    }

    fn real(&mut self, what: &str) -> Result<f64, IoError> {
        let w = self.word(what)?.to_string();
        match w.replace(['d', 'D'], "e").parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.error(format!("{what}: `{w}` is not a finite number"))),
        }
    }

    fn reals3(&mut self, what: &str) -> Result<[f64; 3], IoError> {
        Ok([self.real(what)?, self.real(what)?, self.real(what)?])
    }

    /// A box `((lo) (hi) (type))`, as its nine numbers.
    fn ibox(&mut self, what: &str) -> Result<IBox, IoError> {
        let mut v = [0i64; 9];
        for x in &mut v {
            *x = self.int(what)?;
        }
        let b = IBox {
            lo: [v[0], v[1], v[2]],
            hi: [v[3], v[4], v[5]],
        };
        const LIMIT: i64 = 1 << 31;
        if (0..3).any(|a| b.hi[a] < b.lo[a] || b.lo[a].abs() > LIMIT || b.hi[a].abs() > LIMIT)
            || v[6..].iter().any(|&t| t != 0)
        {
            return Err(self.error(format!(
                "{what}: box {:?}..{:?} type {:?} is not a cell-centred box with lo ≤ hi \
                 within ±2^31",
                b.lo,
                b.hi,
                &v[6..]
            )));
        }
        Ok(b)
    }
}

/// One level's multi-FAB: its boxes, and per box the data file and offset.
struct Level {
    boxes: Vec<IBox>,
    fabs: Vec<(PathBuf, u64)>,
    /// Domain lower corner on this level (cell indices count from it).
    domain_lo: [i64; 3],
    /// Width of one of this level's cells in finest cells.
    width: i64,
}

/// Reads the plotfile directory `dir` (the one holding `Header`) into leaf
/// cells, every component a field named as the header names it.
pub fn read_amrex(dir: &Path) -> Result<AmrCellData, IoError> {
    if !dir.join("Header").is_file() {
        return Err(IoError::format(
            dir,
            "is not an AMReX plotfile: it has no `Header` file",
        ));
    }
    read_plotfile(&Dir(dir))
}

/// [`read_amrex`] from memory: `files` names each file of the plotfile by
/// its path inside it (`Header`, `Level_0/Cell_H`, `Level_0/Cell_D_00000`,
/// …) with its bytes; errors name them under `root`, as the files of a
/// directory `root` would be named. The same checks and messages, every
/// allocation bounded by the slices' lengths.
pub fn read_amrex_files(root: &Path, files: &[(&str, &[u8])]) -> Result<AmrCellData, IoError> {
    read_plotfile(&Memory { root, files })
}

fn read_plotfile(files: &dyn Files) -> Result<AmrCellData, IoError> {
    let header_path = files.label(Path::new("Header"));
    let mut t = Tokens::read(files, Path::new("Header"))?;
    let version = t.word("the version line")?.to_string();
    if !version.starts_with("HyperCLaw") && !version.starts_with("NavierStokes") {
        return Err(t.error(format!(
            "version `{version}` is not a plotfile header (expected HyperCLaw-V1.1)"
        )));
    }
    let ncomp = t.count("the number of components", 1 << 16)?;
    if ncomp == 0 {
        return Err(t.error("the plotfile has no components"));
    }
    let names: Vec<String> = (0..ncomp)
        .map(|_| t.word("a component name").map(str::to_string))
        .collect::<Result<_, _>>()?;
    let dim = t.int("the space dimension")?;
    if dim != 3 {
        return Err(t.error(format!(
            "space dimension {dim}: only 3-D plotfiles are supported"
        )));
    }
    let time = t.real("the time")?;
    let finest = t.count("the finest level", MAX_LEVEL as i64)?;
    let prob_lo = t.reals3("prob_lo")?;
    let _prob_hi = t.reals3("prob_hi")?;
    let mut ratios = Vec::with_capacity(finest);
    for l in 0..finest {
        let r = t.int("a refinement ratio")?;
        if r < 2 || r & (r - 1) != 0 {
            return Err(t.error(format!(
                "refinement ratio {r} from level {l} to {} is not a power of two \
                 (cells must be power-of-two multiples of the finest)",
                l + 1
            )));
        }
        ratios.push(r);
    }
    let domains: Vec<IBox> = (0..=finest)
        .map(|_| t.ibox("a level's domain box"))
        .collect::<Result<_, _>>()?;
    for _ in 0..=finest {
        t.int("a level's step count")?;
    }
    let mut dx = Vec::with_capacity(finest + 1);
    for _ in 0..=finest {
        dx.push(t.reals3("a level's cell size")?);
    }
    let coord = t.int("the coordinate system")?;
    if coord != 0 {
        return Err(t.error(format!(
            "coordinate system {coord}: only Cartesian (0) plotfiles are supported"
        )));
    }
    t.int("the boundary width")?;
    // Widths in finest cells: the product of the ratios below each level.
    let mut widths = vec![1i64; finest + 1];
    for l in (0..finest).rev() {
        widths[l] = widths[l + 1]
            .checked_mul(ratios[l])
            .filter(|&w| w <= 1 << MAX_LEVEL)
            .ok_or_else(|| t.error("the levels' refinement exceeds 2^30"))?;
    }
    let h = dx[finest][0];
    for (l, d) in dx.iter().enumerate() {
        for a in 0..3 {
            let want = h * widths[l] as f64;
            if !(d[a] > 0.0) || ((d[a] - want) / want).abs() > 1e-6 {
                return Err(t.error(format!(
                    "level {l}'s cell size {:?} is not cubic or does not match the finest level's \
                     {h} times {} (non-cubic cells are not supported)",
                    d, widths[l]
                )));
            }
        }
    }
    let mut levels = Vec::with_capacity(finest + 1);
    for l in 0..=finest {
        let lev = t.int("a level number")?;
        if lev != l as i64 {
            return Err(t.error(format!("expected level {l}, found {lev}")));
        }
        let nboxes = t.count("a level's box count", 1 << 31)?;
        t.real("a level's time")?;
        t.int("a level's step")?;
        for _ in 0..nboxes * 3 {
            t.real("a box's physical extent")?;
            t.real("a box's physical extent")?;
        }
        let prefix = t.word("the level's multi-FAB path")?.to_string();
        levels.push(read_level(files, &prefix, ncomp, domains[l].lo, widths[l])?);
        if levels[l].boxes.len() != nboxes {
            return Err(IoError::format(
                &header_path,
                format!(
                    "level {l} has {nboxes} boxes in the header but {} in {prefix}_H",
                    levels[l].boxes.len()
                ),
            ));
        }
    }
    let mut fields: Vec<(String, Vec<f32>)> = names.into_iter().map(|n| (n, Vec::new())).collect();
    let mut cells = Vec::new();
    for l in 0..=finest {
        let covered = levels.get(l + 1).map(|f| (f, ratios[l]));
        read_leaf_cells(
            files,
            &levels[l],
            covered,
            widths[l].trailing_zeros() as usize,
            &mut cells,
            &mut fields,
        )?;
    }
    let origin = prob_lo;
    Ok(AmrCellData {
        cells,
        fields,
        origin,
        finest_cell_size: h,
        time: Some(time),
    })
}

/// A level's `Cell_H`: its boxes and where each box's FAB lies.
fn read_level(
    files: &dyn Files,
    prefix: &str,
    ncomp: usize,
    domain_lo: [i64; 3],
    width: i64,
) -> Result<Level, IoError> {
    let rel = Path::new(prefix);
    if rel.is_absolute()
        || rel
            .components()
            .any(|c| c == std::path::Component::ParentDir)
    {
        return Err(IoError::format(
            files.label(Path::new("Header")),
            format!("multi-FAB path `{prefix}` leaves the plotfile directory"),
        ));
    }
    let mut t = Tokens::read(files, Path::new(&format!("{prefix}_H")))?;
    t.int("the VisMF version")?;
    t.int("how it was written")?;
    let n = t.count("the component count", 1 << 16)?;
    if n != ncomp {
        return Err(t.error(format!(
            "{n} components where the plotfile header has {ncomp}"
        )));
    }
    // Ghost width: a number, or an IntVect `(0,0,0)` in newer versions
    // (the rest of its line).
    let g = t.int("the ghost width")?;
    let mut g_max = g;
    while t.on_same_line() {
        g_max = g_max.max(t.int("the ghost width")?);
    }
    let g = g_max;
    if g != 0 {
        // Plotfiles carry no ghost cells; a FAB with them would be read
        // shifted.
        return Err(t.error(format!("ghost width {g}: plotfile data has no ghost cells")));
    }
    let nboxes = t.count("the box count", 1 << 31)?;
    t.int("the box array's type")?;
    let boxes: Vec<IBox> = (0..nboxes)
        .map(|_| t.ibox("a box"))
        .collect::<Result<_, _>>()?;
    let nfabs = t.count("the FAB count", 1 << 31)?;
    if nfabs != nboxes {
        return Err(t.error(format!("{nfabs} FABs for {nboxes} boxes")));
    }
    let level_dir = rel.parent().unwrap_or(Path::new("")).to_path_buf();
    // Data files' lengths bound every box: a box needs at least 4 bytes a
    // value in its file, so no size below is larger than the input.
    let mut lengths: Vec<(PathBuf, u64)> = Vec::new();
    let mut fabs = Vec::with_capacity(nfabs);
    for _ in 0..nfabs {
        let tag = t.word("a FabOnDisk line")?.to_string();
        if tag != "FabOnDisk:" {
            return Err(t.error(format!("expected `FabOnDisk:`, found `{tag}`")));
        }
        let file = t.word("a FAB's data file")?.to_string();
        if file.contains('/') || file.contains('\\') || file == ".." {
            return Err(t.error(format!(
                "data file `{file}` is not a file in the level's directory"
            )));
        }
        let offset = t.int("a FAB's offset")?;
        if offset < 0 {
            return Err(t.error(format!("negative offset {offset}")));
        }
        let rel = level_dir.join(&file);
        let len = match lengths.iter().find(|(p, _)| *p == rel) {
            Some(&(_, len)) => len,
            None => {
                let len = files.open(&rel)?.1;
                lengths.push((rel.clone(), len));
                len
            }
        };
        let b = &boxes[fabs.len()];
        let need = b
            .checked_cells()
            .and_then(|c| c.checked_mul(4 * ncomp as u64))
            .and_then(|c| c.checked_add(offset as u64));
        if need.is_none_or(|n| n > len) {
            return Err(IoError::format(
                files.label(&rel),
                format!(
                    "box {:?}..{:?} of {prefix}_H needs {} bytes at offset {offset}, but the \
                     file has {len}",
                    b.lo,
                    b.hi,
                    need.map_or("more than 2^64".into(), |n| (n - offset as u64).to_string())
                ),
            ));
        }
        fabs.push((rel, offset as u64));
    }
    Ok(Level {
        boxes,
        fabs,
        domain_lo,
        width,
    })
}

/// Per box of `level`, a mask of the cells the next finer level covers
/// (`fine` with ratio `r`); `None` where nothing covers the box. Boxes are
/// binned on a coarse grid so each fine box meets only its neighbours.
fn covered_masks(level: &Level, fine: Option<(&Level, i64)>) -> Vec<Option<Vec<bool>>> {
    let mut masks: Vec<Option<Vec<bool>>> = vec![None; level.boxes.len()];
    let Some((fine, r)) = fine else {
        return masks;
    };
    const BIN: i64 = 32;
    let mut bins: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    for (i, b) in level.boxes.iter().enumerate() {
        let (lo, hi) = (
            b.lo.map(|v| v.div_euclid(BIN)),
            b.hi.map(|v| v.div_euclid(BIN)),
        );
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    bins.entry([x, y, z]).or_default().push(i as u32);
                }
            }
        }
    }
    let mut seen = Vec::new();
    for fb in &fine.boxes {
        let c = fb.coarsen(r);
        let (lo, hi) = (
            c.lo.map(|v| v.div_euclid(BIN)),
            c.hi.map(|v| v.div_euclid(BIN)),
        );
        seen.clear();
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    if let Some(ids) = bins.get(&[x, y, z]) {
                        seen.extend_from_slice(ids);
                    }
                }
            }
        }
        seen.sort_unstable();
        seen.dedup();
        for &i in &seen {
            let b = &level.boxes[i as usize];
            let Some(o) = b.overlap(&c) else { continue };
            let s = b.size();
            let mask = masks[i as usize].get_or_insert_with(|| vec![false; b.cells() as usize]);
            for z in o.lo[2]..=o.hi[2] {
                for y in o.lo[1]..=o.hi[1] {
                    let row = ((z - b.lo[2]) * s[1] + (y - b.lo[1])) * s[0] - b.lo[0];
                    for x in o.lo[0]..=o.hi[0] {
                        mask[(row + x) as usize] = true;
                    }
                }
            }
        }
    }
    masks
}

/// The cells of `level` that the finer level does not cover, appended with
/// their values; `exa_level` is the ExaBricks level (0 = finest).
fn read_leaf_cells(
    files: &dyn Files,
    level: &Level,
    fine: Option<(&Level, i64)>,
    exa_level: usize,
    cells: &mut Vec<[i32; 4]>,
    fields: &mut [(String, Vec<f32>)],
) -> Result<(), IoError> {
    let masks = covered_masks(level, fine);
    let mut open: Option<(&Path, Box<dyn Source + '_>, u64)> = None;
    let mut values = Vec::new();
    for (i, b) in level.boxes.iter().enumerate() {
        let (rel, offset) = &level.fabs[i];
        if open.as_ref().is_none_or(|o| o.0 != rel.as_path()) {
            let (reader, len) = files.open(rel)?;
            open = Some((rel, reader, len));
        }
        let (_, reader, len) = open.as_mut().expect("opened above");
        let path = files.label(rel);
        read_fab(&path, reader, *len, *offset, b, fields.len(), &mut values)?;
        let path = path.as_path();
        let n = b.cells() as usize;
        let s = b.size();
        let mask = masks[i].as_deref();
        for k in 0..n {
            if mask.is_some_and(|m| m[k]) {
                continue;
            }
            let idx = [
                k as i64 % s[0],
                (k as i64 / s[0]) % s[1],
                k as i64 / (s[0] * s[1]),
            ];
            // Coordinates within ±2^31, widths within 2^30: i128 holds it.
            let corner = [0, 1, 2].map(|a| {
                (b.lo[a] as i128 + idx[a] as i128 - level.domain_lo[a] as i128)
                    * level.width as i128
            });
            if corner
                .iter()
                .any(|&c| c.unsigned_abs() > i32::MAX as u128 / 2)
            {
                return Err(IoError::format(
                    path,
                    format!(
                        "box {:?}..{:?} lies too far out for 32-bit cell coordinates",
                        b.lo, b.hi
                    ),
                ));
            }
            cells.push([
                corner[0] as i32,
                corner[1] as i32,
                corner[2] as i32,
                exa_level as i32,
            ]);
            for (c, f) in fields.iter_mut().enumerate() {
                f.1.push(values[c * n + k]);
            }
        }
    }
    Ok(())
}

/// The FAB of box `b` at `offset`: its header line checked against the box
/// and component count, its values (component after component) into `out`
/// as f32.
fn read_fab(
    path: &Path,
    reader: &mut Box<dyn Source + '_>,
    len: u64,
    offset: u64,
    b: &IBox,
    ncomp: usize,
    out: &mut Vec<f32>,
) -> Result<(), IoError> {
    let err = |m: String| IoError::format(path, format!("FAB at byte {offset}: {m}"));
    if offset >= len {
        return Err(err(format!("lies past the file's end ({len} bytes)")));
    }
    reader
        .seek(SeekFrom::Start(offset))
        .map_err(|e| IoError::io(path, e))?;
    let mut line = Vec::new();
    reader
        .by_ref()
        .take(4096)
        .read_until(b'\n', &mut line)
        .map_err(|e| IoError::io(path, e))?;
    let text = std::str::from_utf8(&line)
        .map_err(|_| err("the header line is not text".into()))?
        .trim();
    let Some(rest) = text.strip_prefix("FAB ") else {
        return Err(err(format!(
            "expected a `FAB ` header line, found `{}`",
            text.chars().take(40).collect::<String>()
        )));
    };
    let mut t = Tokens::from_text(rest, path);
    let nbytes = t
        .int("the real descriptor")
        .map_err(|_| err("bad real descriptor".into()))?;
    let bits: Vec<i64> = (0..8)
        .map(|_| t.int("the real descriptor"))
        .collect::<Result<_, _>>()
        .map_err(|_| err("bad real descriptor".into()))?;
    let order_n = t
        .int("the byte order")
        .map_err(|_| err("bad byte order".into()))?;
    let order: Vec<i64> = (0..order_n.clamp(0, 16))
        .map(|_| t.int("the byte order"))
        .collect::<Result<_, _>>()
        .map_err(|_| err("bad byte order".into()))?;
    let little = order.iter().copied().eq((1..=order_n).rev());
    let big = order.iter().copied().eq(1..=order_n);
    let ieee = match nbytes {
        8 => bits[..3] == [64, 11, 52],
        4 => bits[..3] == [32, 8, 23],
        _ => false,
    };
    if !ieee || order_n != nbytes || !(little || big) {
        return Err(err(format!(
            "real format ({nbytes} bytes, bits {bits:?}, order {order:?}) is not IEEE f32/f64 in a \
             plain byte order"
        )));
    }
    let fb = t.ibox("the FAB's box").map_err(|_| err("bad box".into()))?;
    let nc = t
        .int("the FAB's component count")
        .map_err(|_| err("bad component count".into()))?;
    if fb != *b || nc != ncomp as i64 {
        return Err(err(format!(
            "box {:?}..{:?} with {nc} components where Cell_H has {:?}..{:?} with {ncomp}",
            fb.lo, fb.hi, b.lo, b.hi
        )));
    }
    let count = b.cells() as u64 * ncomp as u64;
    let bytes = count * nbytes as u64;
    let start = offset + line.len() as u64;
    if start + bytes > len {
        return Err(err(format!(
            "needs {bytes} bytes of data but the file ends {} bytes after its header",
            len.saturating_sub(start)
        )));
    }
    let mut raw = vec![0u8; bytes as usize];
    reader
        .read_exact(&mut raw)
        .map_err(|e| IoError::io(path, e))?;
    out.clear();
    out.reserve(count as usize);
    match (nbytes, little) {
        (8, true) => out.extend(
            raw.chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()) as f32),
        ),
        (8, false) => out.extend(
            raw.chunks_exact(8)
                .map(|c| f64::from_be_bytes(c.try_into().unwrap()) as f32),
        ),
        (_, true) => out.extend(
            raw.chunks_exact(4)
                .map(|c| f32::from_le_bytes(c.try_into().unwrap())),
        ),
        (_, false) => out.extend(
            raw.chunks_exact(4)
                .map(|c| f32::from_be_bytes(c.try_into().unwrap())),
        ),
    }
    Ok(())
}
