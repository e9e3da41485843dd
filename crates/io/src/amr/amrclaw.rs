//! AMRClaw's native ASCII output (`fort.qNNNN` plus `fort.tNNNN`), from
//! disk or from memory.
//!
//! [`read_amrclaw`] finds the `fort.t` beside the `fort.q` and reads both
//! files; [`read_amrclaw_from`] takes the `fort.q` text from a reader and
//! the `fort.t` text as bytes. Both parse with the same code.

use std::io::{BufRead, Read, Seek};
use std::path::{Path, PathBuf};

use super::{AmrCellData, FieldPick, MAX_LEVEL};
use crate::decimal::fast_decimal_prefix;
use crate::{IoError, checked_product, open_with_len, remaining_len};

/// The longest `fort.t` accepted: a header is a few short lines.
const MAX_FORT_T: u64 = 1 << 16;

fn read_all(path: &Path) -> Result<Vec<u8>, IoError> {
    std::fs::read(path).map_err(|e| IoError::io(path, e))
}

/// Text read line by line, counting lines (from 1); `path` labels errors.
struct Lines<R> {
    reader: R,
    path: PathBuf,
    buf: Vec<u8>,
    /// Number of the line in `buf`.
    line: usize,
    /// `next_nonblank` returns `buf` again instead of reading.
    replay: bool,
    /// The text ends where the next grid's header starts (not at the end
    /// of the file).
    ends_at_header: bool,
}

impl<R: BufRead> Lines<R> {
    fn new(reader: R, path: &Path) -> Lines<R> {
        Lines {
            reader,
            path: path.to_path_buf(),
            buf: Vec::with_capacity(256),
            line: 0,
            replay: false,
            ends_at_header: false,
        }
    }

    /// The next line that is not blank, trimmed; `None` at the end.
    fn next_nonblank(&mut self) -> Result<Option<&str>, IoError> {
        if !std::mem::take(&mut self.replay) {
            loop {
                self.buf.clear();
                let n = self
                    .reader
                    .read_until(b'\n', &mut self.buf)
                    .map_err(|e| IoError::io(&self.path, e))?;
                if n == 0 {
                    return Ok(None);
                }
                self.line += 1;
                if !self.buf.trim_ascii().is_empty() {
                    break;
                }
            }
        }
        match std::str::from_utf8(self.buf.trim_ascii()) {
            Ok(s) => Ok(Some(s)),
            Err(_) => Err(IoError::format(
                &self.path,
                format!("line {} is not text (invalid UTF-8)", self.line),
            )),
        }
    }

    /// Makes the next `next_nonblank` return the current line again.
    fn unread(&mut self) {
        self.replay = true;
    }

    fn error(&self, message: impl std::fmt::Display) -> IoError {
        IoError::format(&self.path, format!("line {}: {message}", self.line))
    }

    /// A `value name` line whose name (if present) must be `name`; returns
    /// the value token. `context` says what is being read, for errors.
    fn named_value(&mut self, name: &str, context: &str) -> Result<String, IoError> {
        let Some(line) = self.next_nonblank()? else {
            let line = self.line;
            return Err(IoError::format(
                &self.path,
                format!("file ends at line {line} in {context}, before `{name}`"),
            ));
        };
        let mut tokens = line.split_ascii_whitespace();
        let value = tokens.next().unwrap_or_default().to_string();
        if let Some(found) = tokens.next()
            && !found.eq_ignore_ascii_case(name)
        {
            let found = found.to_string();
            return Err(self.error(format!("expected `{name}` in {context}, found `{found}`")));
        }
        Ok(value)
    }

    /// A `value name` line parsed with `parse`; `what` describes a valid
    /// value, for errors.
    fn named<T>(
        &mut self,
        name: &str,
        context: &str,
        what: &str,
        parse: impl Fn(&str) -> Option<T>,
    ) -> Result<T, IoError> {
        let token = self.named_value(name, context)?;
        parse(&token)
            .ok_or_else(|| self.error(format!("{name} `{token}` is not {what} ({context})")))
    }
}

/// Parses a number as Fortran writes it: also accepts `D`/`Q` exponent
/// letters (`0.1D+01`) and the exponent letter left out for three-digit
/// exponents (`0.1234-100`).
pub(crate) fn parse_fortran(token: &str) -> Option<f64> {
    if let Ok(v) = token.parse::<f64>() {
        return Some(v);
    }
    let bytes = token.as_bytes();
    let mut fixed = String::with_capacity(token.len() + 1);
    for (i, c) in token.char_indices() {
        match c {
            'd' | 'D' | 'q' | 'Q' => fixed.push('e'),
            '+' | '-'
                if i > 0 && !matches!(bytes[i - 1], b'e' | b'E' | b'd' | b'D' | b'q' | b'Q') =>
            {
                fixed.push('e');
                fixed.push(c);
            }
            _ => fixed.push(c),
        }
    }
    fixed.parse().ok()
}

fn int(token: &str) -> Option<i64> {
    token.parse().ok()
}

fn finite(token: &str) -> Option<f64> {
    parse_fortran(token).filter(|v| v.is_finite())
}

/// What `fort.tNNNN` says about a frame.
struct FrameHeader {
    time: f64,
    meqn: usize,
    ngrids: usize,
}

/// The `fort.tNNNN` file that belongs to `fort.qNNNN`, if the name fits.
fn fort_t_path(fort_q: &Path) -> Option<PathBuf> {
    let name = fort_q.file_name()?.to_str()?;
    let number = name.strip_prefix("fort.q")?;
    Some(fort_q.with_file_name(format!("fort.t{number}")))
}

/// The label of the `fort.t` text that goes with `fort_q` in memory: the
/// name the file would have on disk.
fn fort_t_label(fort_q: &Path) -> PathBuf {
    fort_t_path(fort_q).unwrap_or_else(|| fort_q.with_file_name("fort.t"))
}

/// Error for a `fort.t` of `len` bytes, more than a header can be.
fn fort_t_too_long(path: &Path, len: u64) -> IoError {
    IoError::format(
        path,
        format!("{len} bytes is far too long for an AMRClaw fort.t header"),
    )
}

/// The simulation time of the AMRClaw frame `fort_q`, from the `fort.t`
/// beside it (`None` when there is none).
pub fn amrclaw_time(fort_q: &Path) -> Result<Option<f64>, IoError> {
    match fort_t_path(fort_q).filter(|t| t.is_file()) {
        Some(t) => Ok(Some(read_fort_t(&t)?.time)),
        None => Ok(None),
    }
}

/// Reads the file `fort.tNNNN` (see [`parse_fort_t`]).
fn read_fort_t(path: &Path) -> Result<FrameHeader, IoError> {
    // Check the size before reading so a wrong, huge file is not loaded.
    let len = std::fs::metadata(path)
        .map_err(|e| IoError::io(path, e))?
        .len();
    if len > MAX_FORT_T {
        return Err(fort_t_too_long(path, len));
    }
    parse_fort_t(&read_all(path)?, path)
}

/// Parses `fort.tNNNN`: lines `value name` giving time, meqn, ngrids, naux
/// and ndim (in that order when the names are missing). `path` labels
/// errors.
fn parse_fort_t(bytes: &[u8], path: &Path) -> Result<FrameHeader, IoError> {
    let len = bytes.len() as u64;
    if len > MAX_FORT_T {
        return Err(fort_t_too_long(path, len));
    }
    let text = std::str::from_utf8(bytes)
        .map_err(|_| IoError::format(path, "not text (invalid UTF-8)"))?;
    let entries: Vec<(usize, &str, Option<&str>)> = text
        .lines()
        .enumerate()
        .filter_map(|(i, l)| {
            let mut t = l.split_ascii_whitespace();
            t.next().map(|v| (i + 1, v, t.next()))
        })
        .collect();
    let named = entries.iter().any(|e| e.2.is_some());
    let get = |name: &str, position: usize| {
        let entry = if named {
            entries
                .iter()
                .find(|e| e.2.is_some_and(|n| n.eq_ignore_ascii_case(name)))
        } else {
            entries.get(position)
        };
        entry.ok_or_else(|| IoError::format(path, format!("no `{name}` line")))
    };
    let number = |name: &str, position: usize, min: f64| -> Result<f64, IoError> {
        let (line, token, _) = get(name, position)?;
        parse_fortran(token)
            .filter(|v| v.is_finite() && *v >= min && (min == f64::MIN || v.fract() == 0.0))
            .ok_or_else(|| {
                let what = if min == f64::MIN {
                    "a number"
                } else {
                    "a count"
                };
                IoError::format(path, format!("line {line}: {name} `{token}` is not {what}"))
            })
    };
    let time = number("time", 0, f64::MIN)?;
    let meqn = number("meqn", 1, 1.0)?;
    let ngrids = number("ngrids", 2, 0.0)?;
    let ndim = number("ndim", 4, 0.0)?;
    if ndim != 3.0 {
        return Err(IoError::format(
            path,
            format!("ndim is {ndim}; only 3D AMRClaw output is supported"),
        ));
    }
    Ok(FrameHeader {
        time,
        // Saturating casts; the grid reader checks sizes against the file.
        meqn: meqn as usize,
        ngrids: ngrids as usize,
    })
}

/// One grid (patch) of a `fort.q` file.
struct Grid {
    number: i64,
    amr_level: i64,
    /// Line of the `grid_number` header line.
    line: usize,
    size: [usize; 3],
    low: [f64; 3],
    d: [f64; 3],
    /// `meqn` values per cell, cells x fastest, then y, then z.
    values: Vec<f32>,
}

/// Reads AMRClaw's native ASCII output and converts it to leaf cells.
///
/// `fort_q` is a `fort.qNNNN` file: per grid eleven `value name` lines
/// (`grid_number`, `AMR_level` (1 = coarsest), `mx`, `my`, `mz`, `xlow`,
/// `ylow`, `zlow`, `dx`, `dy`, `dz`), then `mx·my·mz` rows of `meqn` values,
/// x fastest, then y, then z. Blank lines anywhere are skipped, and numbers
/// may use Fortran's `D` exponents. The header `fort.tNNNN` in the same
/// directory gives the time, `meqn`, the number of grids and `ndim` (which
/// must be 3). If there is no such file, `meqn` is taken from the number of
/// values on the first data row, the grids are read to the end of the file,
/// and `time` is `None`.
///
/// Conversion: the finest cell size is the smallest `dx` of any grid; every
/// grid must have `dx == dy == dz`, equal to the finest size times a power of
/// two `2^level`, and the same for all grids of an AMR level (finer AMR
/// levels having smaller cells). The origin is the smallest `xlow`, `ylow`,
/// `zlow` of the coarsest AMR level's grids, and a grid's lower corner is
/// `round((xlow - origin) / dx_finest)` (it must lie on that lattice). A
/// cell is dropped when one grid of a finer AMR level contains its whole box,
/// which is how AMRClaw stores the coarse values under refined regions.
/// Cells come grid by grid in file order, x fastest within a grid. Fields are
/// named `q0`, `q1`, …; the `f64` text values are rounded to `f32`.
///
/// Fails with the grid number and line number if a grid holds fewer values
/// than its header declares, and on any malformed header or number.
pub fn read_amrclaw(fort_q: &Path) -> Result<AmrCellData, IoError> {
    read_amrclaw_picked(fort_q, &FieldPick::All)
}

/// [`read_amrclaw`] parsing only the fields `pick` names (the others'
/// numbers are skipped unread; see [`FieldPick`]). Rows are then taken one
/// per line, as AMRClaw writes them: the first row of each grid is checked
/// to hold `meqn` values, and a malformed number in a field not picked goes
/// unnoticed.
pub fn read_amrclaw_picked(fort_q: &Path, pick: &FieldPick) -> Result<AmrCellData, IoError> {
    // A device, FIFO or socket (a pipe, /dev/stdin) has no length to check
    // sizes against and no fort.t beside it.
    if let Ok(meta) = std::fs::metadata(fort_q)
        && !meta.is_file()
    {
        return Err(IoError::format(
            fort_q,
            "not a regular file (a device, FIFO or socket): AMRClaw output is read from its \
             fort.qNNNN file (with fort.tNNNN beside it)",
        ));
    }
    let header = match fort_t_path(fort_q) {
        Some(t) if t.is_file() => Some(read_fort_t(&t)?),
        _ => None,
    };
    let (file, len) = open_with_len(fort_q)?;
    // The file's pages in place (no copy of the text, no fresh memory);
    // where the file cannot be mapped (a pipe), read it a window at a time.
    // SAFETY: the map is only read; a file truncated by another process
    // meanwhile is outside what any reader can guard against (as with
    // output files still being written).
    match (len > 0).then(|| unsafe { memmap2::Mmap::map(&file) }) {
        Some(Ok(map)) => {
            let data = read_grids_text(&map, fort_q, header, pick);
            // Unmapping a large file's pages takes milliseconds (2 for 32
            // MB): done on a thread of its own while the caller goes on.
            if len > 1 << 24 {
                std::thread::spawn(move || drop(map));
            }
            data
        }
        _ => read_grids(file, len, fort_q, header, pick),
    }
}

/// [`read_amrclaw`] from memory: `fort_q` yields the `fort.qNNNN` text
/// (from its position to its end) and `fort_t` is the `fort.tNNNN` text,
/// when there is one; without it `meqn` comes from the first data row and
/// the grids run to the end, as for a `fort.q` without its `fort.t`.
///
/// `name` labels errors as the `fort.q` path does for [`read_amrclaw`], and
/// errors in `fort_t` name the `fort.tNNNN` beside it (`fort.t` when `name`
/// is not a `fort.qNNNN`). The checks are those of the files: the length of
/// `fort_q` bounds what a grid header may declare.
pub fn read_amrclaw_from<R: Read + Seek>(
    mut fort_q: R,
    name: &Path,
    fort_t: Option<&[u8]>,
) -> Result<AmrCellData, IoError> {
    let header = match fort_t {
        Some(bytes) => Some(parse_fort_t(bytes, &fort_t_label(name))?),
        None => None,
    };
    let len = remaining_len(&mut fort_q, name)?;
    read_grids(fort_q, len, name, header, &FieldPick::All)
}

/// [`read_amrclaw_from`] over text in memory (`fort_q` whole), decoding
/// only the fields `pick` names as [`read_amrclaw_picked`] does: the path
/// a mapped `fort.q` takes.
pub fn read_amrclaw_text(
    fort_q: &[u8],
    name: &Path,
    fort_t: Option<&[u8]>,
    pick: &FieldPick,
) -> Result<AmrCellData, IoError> {
    let header = match fort_t {
        Some(bytes) => Some(parse_fort_t(bytes, &fort_t_label(name))?),
        None => None,
    };
    read_grids_text(fort_q, name, header, pick)
}

/// Text read at a time: the grids a window holds parse in parallel, and
/// memory stays a window of text beside the values (a grid longer than a
/// window widens it to that grid).
const WINDOW: u64 = 16 << 20;

/// The marker of a grid's first header line.
const GRID_NUMBER: &[u8] = b"grid_number";

/// The grids of a `fort.q` (`reader`, `file_len` bytes, labelled `fort_q`)
/// converted to leaf cells, with the `fort.t` header when there is one.
///
/// The text is read a window at a time and cut at the lines that name
/// `grid_number`, so each piece holds whole grids; pieces parse on every
/// core, each knowing its first line's number for errors. Grids come out
/// in file order, and the first error in file order is the one reported.
fn read_grids(
    reader: impl Read,
    file_len: u64,
    fort_q: &Path,
    header: Option<FrameHeader>,
    pick: &FieldPick,
) -> Result<AmrCellData, IoError> {
    read_grids_in(reader, file_len, fort_q, header, WINDOW, pick)
}

/// [`read_grids`] a `window` of bytes at a time.
fn read_grids_in(
    mut reader: impl Read,
    file_len: u64,
    fort_q: &Path,
    header: Option<FrameHeader>,
    window: u64,
    pick: &FieldPick,
) -> Result<AmrCellData, IoError> {
    let mut scan = Scan::new(fort_q, file_len, &header, pick);
    let mut text: Vec<u8> = Vec::new();
    loop {
        // Room for the window at once (and no more than the file holds).
        text.reserve(window.min(file_len) as usize);
        let read = (&mut reader)
            .take(window)
            .read_to_end(&mut text)
            .map_err(|e| IoError::io(fort_q, e))?;
        let end = read == 0;
        if let Some(cut) = scan.grids_of(&text, end)? {
            text.drain(..cut);
        }
        if end {
            break;
        }
    }
    scan.finish(header)
}

/// [`read_grids`] over the whole text at once (a mapped file).
fn read_grids_text(
    text: &[u8],
    fort_q: &Path,
    header: Option<FrameHeader>,
    pick: &FieldPick,
) -> Result<AmrCellData, IoError> {
    let mut scan = Scan::new(fort_q, text.len() as u64, &header, pick);
    scan.grids_of(text, true)?;
    scan.finish(header)
}

/// The grids of one piece of text whose first line is line `first + 1`
/// (`at_header`: the next grid's header follows it).
fn read_piece(
    (piece, at_header): (&[u8], bool),
    first: usize,
    fort_q: &Path,
    meqn: &mut Option<usize>,
    file_len: u64,
    pick: &FieldPick,
) -> Result<Vec<Grid>, IoError> {
    let mut lines = Lines::new(piece, fort_q);
    lines.line = first;
    lines.ends_at_header = at_header;
    let mut grids = Vec::new();
    while lines.next_nonblank()?.is_some() {
        lines.unread();
        grids.push(read_grid(&mut lines, meqn, file_len, pick)?);
    }
    Ok(grids)
}

/// `token` quoted for an error (its first 40 characters).
fn not_a_number(token: &[u8]) -> String {
    let token: String = String::from_utf8_lossy(token).chars().take(40).collect();
    format!("`{token}` is not a number")
}

/// Reads one grid's header and values.
fn read_grid(
    lines: &mut Lines<&[u8]>,
    meqn: &mut Option<usize>,
    file_len: u64,
    pick: &FieldPick,
) -> Result<Grid, IoError> {
    let number: i64 = lines.named("grid_number", "a grid header", "an integer", int)?;
    let line = lines.line;
    let header_line = line;
    let context = format!("the header of grid {number} (line {line})");
    let amr_level: i64 = lines.named("AMR_level", &context, "an integer", int)?;
    let mut size = [0usize; 3];
    for (s, name) in size.iter_mut().zip(["mx", "my", "mz"]) {
        *s = lines.named(name, &context, "a positive integer", |t| {
            t.parse().ok().filter(|&n: &usize| n > 0)
        })?;
    }
    let mut low = [0.0; 3];
    for (v, name) in low.iter_mut().zip(["xlow", "ylow", "zlow"]) {
        *v = lines.named(name, &context, "a finite number", finite)?;
    }
    let mut d = [0.0; 3];
    for (v, name) in d.iter_mut().zip(["dx", "dy", "dz"]) {
        *v = lines.named(name, &context, "a positive number", |t| {
            parse_fortran(t).filter(|v| v.is_finite() && *v > 0.0)
        })?;
    }
    let grid_error = |lines: &Lines<&[u8]>, message: String| {
        IoError::format(
            &lines.path,
            format!("grid {number} (header at line {line}): {message}"),
        )
    };

    if meqn.is_none() {
        // No fort.t: the first data row has one value per equation (read
        // ahead, not consumed).
        let rest: &[u8] = lines.reader;
        let Some(start) = rest.iter().position(|c| !c.is_ascii_whitespace()) else {
            let end = lines.line + memchr::memchr_iter(b'\n', rest).count();
            return Err(grid_error(
                lines,
                format!("file ends at line {end} before its data"),
            ));
        };
        let row = &rest[start..];
        let row = &row[..memchr::memchr(b'\n', row).unwrap_or(row.len())];
        *meqn = Some(
            row.split(u8::is_ascii_whitespace)
                .filter(|t| !t.is_empty())
                .count(),
        );
    }
    let meqn = meqn.unwrap_or(1);
    let count = checked_product(&[size[0], size[1], size[2], meqn])
        .filter(|&c| (c as u64).saturating_mul(2) <= file_len)
        .ok_or_else(|| {
            grid_error(
                lines,
                format!(
                    "{}×{}×{} cells × {meqn} values is more than the file's {file_len} bytes can hold",
                    size[0], size[1], size[2]
                ),
            )
        })?;
    let cols = columns(meqn, pick).1;
    let mut values = Vec::with_capacity(count / meqn * cols.as_ref().map_or(meqn, Vec::len));
    let fault = |line: usize, problem: &str, done: usize| value_fault(line, problem, done, count);
    // Values straight from the text: tokens between whitespace, lines
    // counted as they pass (no copy of each line).
    let text: &[u8] = lines.reader;
    let mut at = 0;
    let mut line = lines.line + 1;
    if let Some(cols) = cols {
        let rows = Rows {
            text,
            meqn,
            cols: &cols,
            ends_at_header: lines.ends_at_header,
        };
        if let Err(message) = rows.read(count / meqn, &mut at, &mut line, &mut values) {
            lines.line = line;
            return Err(grid_error(lines, message));
        }
    } else {
        while values.len() < count {
            while at < text.len() && text[at].is_ascii_whitespace() {
                line += usize::from(text[at] == b'\n');
                at += 1;
            }
            if at == text.len() {
                lines.line = line - 1;
                let message = values_end(lines.ends_at_header, line, values.len(), count);
                return Err(grid_error(lines, message));
            }
            let start = at;
            // One pass over the number where the fast path takes it.
            if let Some((v, n)) = fast_decimal_prefix(&text[start..]) {
                values.push(v as f32);
                at += n;
                continue;
            }
            while at < text.len() && !text[at].is_ascii_whitespace() {
                at += 1;
            }
            let token = &text[start..at];
            let value = std::str::from_utf8(token).ok().and_then(parse_fortran);
            match value {
                Some(v) => values.push(v as f32),
                None => {
                    lines.line = line;
                    let problem = not_a_number(token);
                    return Err(grid_error(lines, fault(line, &problem, values.len())));
                }
            }
        }
        // The last value's row must end with it.
        while at < text.len() && text[at] != b'\n' {
            if !text[at].is_ascii_whitespace() {
                lines.line = line;
                let problem = "a row runs past the grid's last value";
                return Err(grid_error(lines, fault(line, problem, count)));
            }
            at += 1;
        }
    }
    lines.reader = &text[at..];
    lines.line = line - 1;
    Ok(Grid {
        number,
        amr_level,
        line: header_line,
        size,
        low,
        d,
        values,
    })
}

/// A fault at line `line` inside a grid's `count` values, after `done`.
fn value_fault(line: usize, problem: &str, done: usize, count: usize) -> String {
    format!(
        "line {line}: {problem}, after {done} of {count} values (mx·my·mz·meqn); the grid is \
         truncated, or its header or meqn is wrong"
    )
}

/// A grid's values that end (at the next grid's header when
/// `ends_at_header`, else at the file's end) before line `line`, after
/// `done` of `count`.
fn values_end(ends_at_header: bool, line: usize, done: usize, count: usize) -> String {
    match ends_at_header {
        true => format!(
            "line {line}: the next grid's header (`grid_number`) comes after {done} of its \
             {count} values (mx·my·mz·meqn); the grid is truncated, or its header or meqn is \
             wrong"
        ),
        false => format!(
            "file ends at line {} after {done} of its {count} values (mx·my·mz·meqn); the file \
             is truncated",
            line - 1
        ),
    }
}

/// The names of `meqn` components (`q0`, `q1`, …) and the columns `pick`
/// keeps (`None`: all).
fn columns(meqn: usize, pick: &FieldPick) -> (Vec<String>, Option<Vec<usize>>) {
    let names: Vec<String> = (0..meqn).map(|q| format!("q{q}")).collect();
    let refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let cols = pick.columns(&refs);
    (names, cols)
}

#[path = "amrclaw_cells.rs"]
mod cells;
#[path = "amrclaw_scan.rs"]
mod scan;
use cells::grids_to_cells;
use scan::{Rows, Scan};

#[cfg(test)]
#[path = "amrclaw_tests.rs"]
mod tests;
