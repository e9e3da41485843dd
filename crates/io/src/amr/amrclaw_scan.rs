//! A `fort.q`'s text cut into whole grids that parse on every core, and
//! a grid's rows read for some of their columns (see
//! [`super::read_amrclaw_picked`]).

use std::path::Path;

use super::{
    AmrCellData, FieldPick, FrameHeader, GRID_NUMBER, Grid, grids_to_cells, not_a_number,
    parse_fortran, read_piece, value_fault, values_end,
};
use crate::IoError;
use crate::decimal::fast_decimal_prefix;

/// A grid's rows read for some of their columns: one row per line, the
/// columns after the last picked one skipped to the line's end unparsed.
pub(super) struct Rows<'a> {
    pub text: &'a [u8],
    pub meqn: usize,
    /// Picked columns, ascending.
    pub cols: &'a [usize],
    pub ends_at_header: bool,
}

impl Rows<'_> {
    /// Reads `cells` rows from `text[*at..]` (`*line` the line number
    /// there), pushing the picked values; on error, the message and
    /// `*line` at the fault.
    pub fn read(
        &self,
        cells: usize,
        at: &mut usize,
        line: &mut usize,
        values: &mut Vec<f32>,
    ) -> Result<(), String> {
        let text = self.text;
        let (meqn, count) = (self.meqn, cells * self.meqn);
        let last = self.cols.last().copied().unwrap_or(0);
        let fault =
            |line: usize, problem: &str, done: usize| value_fault(line, problem, done, count);
        let inline = |c: u8| c == b' ' || c == b'\t' || c == b'\r';
        for cell in 0..cells {
            while *at < text.len() && text[*at].is_ascii_whitespace() {
                *line += usize::from(text[*at] == b'\n');
                *at += 1;
            }
            if *at == text.len() {
                let message = values_end(self.ends_at_header, *line, cell * meqn, count);
                *line -= 1;
                return Err(message);
            }
            let mut next = 0;
            for col in 0..=last {
                if col > 0 {
                    while *at < text.len() && inline(text[*at]) {
                        *at += 1;
                    }
                    if *at == text.len() || text[*at] == b'\n' {
                        let problem = format!("a row holds {col} values, but meqn is {meqn}");
                        return Err(fault(*line, &problem, cell * meqn + col));
                    }
                }
                let start = *at;
                let picked = self.cols.get(next) == Some(&col);
                if picked {
                    next += 1;
                    // One pass over the number where the fast path takes it.
                    if let Some((v, n)) = fast_decimal_prefix(&text[start..]) {
                        values.push(v as f32);
                        *at += n;
                        continue;
                    }
                }
                while *at < text.len() && !text[*at].is_ascii_whitespace() {
                    *at += 1;
                }
                if picked {
                    let token = &text[start..*at];
                    let value = std::str::from_utf8(token).ok().and_then(parse_fortran);
                    let Some(v) = value else {
                        return Err(fault(*line, &not_a_number(token), cell * meqn + col));
                    };
                    values.push(v as f32);
                }
            }
            let end = memchr::memchr(b'\n', &text[*at..]).map_or(text.len(), |i| *at + i);
            // The first row shows the grid's row length: meqn values.
            if cell == 0 {
                let more = text[*at..end]
                    .split(u8::is_ascii_whitespace)
                    .filter(|t| !t.is_empty())
                    .count();
                if last + 1 + more != meqn {
                    let problem =
                        format!("a row holds {} values, but meqn is {meqn}", last + 1 + more);
                    return Err(fault(*line, &problem, (last + 1 + more).min(meqn)));
                }
            }
            *at = end;
        }
        Ok(())
    }
}

/// The grids of a `fort.q` read so far, and what reading the rest needs.
pub(super) struct Scan<'a> {
    fort_q: &'a Path,
    file_len: u64,
    pick: &'a FieldPick,
    meqn: Option<usize>,
    grids: Vec<Grid>,
    /// Lines before the text `grids_of` gets next.
    line: usize,
}

impl<'a> Scan<'a> {
    pub fn new(
        fort_q: &'a Path,
        file_len: u64,
        header: &Option<FrameHeader>,
        pick: &'a FieldPick,
    ) -> Scan<'a> {
        Scan {
            fort_q,
            file_len,
            pick,
            meqn: header.as_ref().map(|h| h.meqn),
            grids: Vec::new(),
            line: 0,
        }
    }

    /// Parses the whole grids at the start of `text` (all of it when `end`,
    /// the end of the file) and returns how many bytes they took; `None`
    /// when `text` holds no whole grid yet.
    pub fn grids_of(&mut self, text: &[u8], end: bool) -> Result<Option<usize>, IoError> {
        use rayon::prelude::*;
        // Whole grids: up to the last header line, or all of it at the end.
        let mut starts = header_starts(text);
        let cut = match (end, starts.last()) {
            (true, _) => text.len(),
            (false, Some(&c)) if c > 0 => c,
            (false, _) => return Ok(None),
        };
        starts.retain(|&s| s < cut);
        if starts.first() != Some(&0) {
            starts.insert(0, 0);
        }
        starts.push(cut);
        let pieces: Vec<(&[u8], bool)> = starts
            .windows(2)
            .map(|w| (&text[w[0]..w[1]], w[1] < text.len()))
            .collect();
        // Each piece's first line: its lines counted on every core.
        let counts: Vec<usize> = pieces
            .par_iter()
            .map(|p| memchr::memchr_iter(b'\n', p.0).count())
            .collect();
        let mut firsts = Vec::with_capacity(pieces.len());
        for n in counts {
            firsts.push(self.line);
            self.line += n;
        }
        let (fort_q, file_len, pick) = (self.fort_q, self.file_len, self.pick);
        // Without fort.t the first data row gives meqn: the pieces up to
        // the first grid parse alone.
        let mut k = 0;
        while self.meqn.is_none() && k < pieces.len() {
            let piece = read_piece(pieces[k], firsts[k], fort_q, &mut self.meqn, file_len, pick)?;
            self.grids.extend(piece);
            k += 1;
        }
        let meqn = self.meqn;
        let parsed: Vec<Result<Vec<Grid>, IoError>> = pieces[k..]
            .par_iter()
            .zip(&firsts[k..])
            .map(|(&p, &first)| read_piece(p, first, fort_q, &mut meqn.clone(), file_len, pick))
            .collect();
        for piece in parsed {
            self.grids.extend(piece?);
        }
        Ok(Some(cut))
    }

    /// The cells of the grids read, checked against the `fort.t` header.
    pub fn finish(self, header: Option<FrameHeader>) -> Result<AmrCellData, IoError> {
        let Scan {
            fort_q,
            pick,
            meqn,
            grids,
            line,
            ..
        } = self;
        if let Some(h) = &header {
            if let Some(extra) = grids.get(h.ngrids) {
                return Err(IoError::format(
                    fort_q,
                    format!(
                        "line {}: unexpected grid {} after the last of the {} grids fort.t declares",
                        extra.line, extra.number, h.ngrids
                    ),
                ));
            }
            if grids.len() < h.ngrids {
                return Err(IoError::format(
                    fort_q,
                    format!(
                        "file ends at line {line} after {} grids, but fort.t declares {}",
                        grids.len(),
                        h.ngrids
                    ),
                ));
            }
        }
        let meqn = meqn.unwrap_or(0);
        if grids.is_empty() {
            return Err(IoError::format(fort_q, "no grids in the file"));
        }
        let mut data = grids_to_cells(fort_q, grids, meqn, pick)?;
        data.time = header.map(|h| h.time);
        Ok(data)
    }
}

/// Where the lines of `text` that name `grid_number` start.
fn header_starts(text: &[u8]) -> Vec<usize> {
    header_starts_in(text, 1 << 20)
}

/// [`header_starts`] searching chunks of `chunk` bytes on every core; a
/// match is found in the chunk it starts in (each chunk's search runs past
/// its end by the marker's length).
pub(super) fn header_starts_in(text: &[u8], chunk: usize) -> Vec<usize> {
    use rayon::prelude::*;
    let finder = memchr::memmem::Finder::new(GRID_NUMBER);
    let chunk = chunk.max(1);
    let mut starts: Vec<usize> = (0..text.len().div_ceil(chunk))
        .into_par_iter()
        .flat_map_iter(|c| {
            let (lo, hi) = (c * chunk, ((c + 1) * chunk).min(text.len()));
            let end = (hi + GRID_NUMBER.len() - 1).min(text.len());
            let found: Vec<usize> = finder
                .find_iter(&text[lo..end])
                .map(|at| lo + at)
                .filter(|&at| at < hi)
                .collect();
            found
        })
        .map(|at| memchr::memrchr(b'\n', &text[..at]).map_or(0, |nl| nl + 1))
        .collect();
    // Two markers on one line start it once.
    starts.dedup();
    starts
}
