//! The `.particles` time series of the attribute-aware RBF volume renderer
//! (gprt-org/attribute-aware-rbfs).
//!
//! A series is an index file plus one binary file per timestep:
//!
//! - The index (`name.particles`) is text, one timestep name per line
//!   (usually the step number). Surrounding whitespace and blank lines are
//!   ignored.
//! - The timestep called `T` is stored in the file named like the index with
//!   `_T` appended (`name.particles_T`): that is how the renderer's importer
//!   finds it. If no such file exists, `T` is taken as a path relative to the
//!   index's directory instead.
//! - A timestep file is a `u64` particle count `n`, then `n` records of four
//!   `f32`: `x`, `y`, `z` and a scalar attribute. The renderer reads the bytes
//!   in the machine's order, i.e. little-endian on the x86 and ARM machines it
//!   targets; this reader takes little-endian, and accepts a big-endian file
//!   only when its byte-swapped count is the one that matches the file size.
//!   The file must be exactly `8 + 16 n` bytes long.
//!
//! The fourth float becomes the column `attribute`. `time` is the timestep
//! name when it is a number; there is no domain.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use crate::{IoError, LineReader, ParticleTable};

/// Bytes per particle record: four `f32`.
const RECORD: u64 = 16;

/// Number of timesteps listed in a `.particles` index file.
///
/// Fails with [`IoError::Format`] if the index is not text or lists no
/// timestep. The timestep files themselves are not opened.
pub fn particles_frames(path: &Path) -> Result<usize, IoError> {
    let names = timestep_names(path)?;
    Ok(names.len())
}

/// Reads timestep `frame` (0-based, in index order) of a `.particles` series;
/// see the module docs for the layout.
///
/// Fails with [`IoError::Format`] if the frame is past the end of the index
/// (the message says how many there are), the timestep file is missing (the
/// message names the paths tried), or its size does not match its count.
pub fn read_particles_file(path: &Path, frame: usize) -> Result<ParticleTable, IoError> {
    let names = timestep_names(path)?;
    let Some(name) = names.get(frame) else {
        return Err(IoError::format(
            path,
            format!(
                "frame {frame} requested but the index lists {} timestep{} (numbered from 0)",
                names.len(),
                if names.len() == 1 { "" } else { "s" }
            ),
        ));
    };
    let data_path = timestep_path(path, name)?;
    let mut table = read_timestep(&data_path)?;
    table.time = name.parse::<f64>().ok().filter(|t| t.is_finite());
    Ok(table)
}

/// The timestep names listed in the index file.
fn timestep_names(path: &Path) -> Result<Vec<String>, IoError> {
    let mut lines = LineReader::open(path)?;
    let mut names = Vec::new();
    while let Some(line) = lines.next_line()? {
        if line.is_empty() {
            continue;
        }
        if line.chars().any(char::is_control) {
            return Err(lines.error("a timestep name contains control characters"));
        }
        names.push(line.to_string());
    }
    if names.is_empty() {
        return Err(IoError::format(
            path,
            "the .particles index lists no timestep (expected one name per line)",
        ));
    }
    Ok(names)
}

/// Where the data of timestep `name` lives (see the module docs).
fn timestep_path(index: &Path, name: &str) -> Result<PathBuf, IoError> {
    let mut appended = index.as_os_str().to_os_string();
    appended.push("_");
    appended.push(name);
    let appended = PathBuf::from(appended);
    if appended.is_file() {
        return Ok(appended);
    }
    let relative = index.parent().unwrap_or(Path::new("")).join(name);
    if relative.is_file() {
        return Ok(relative);
    }
    Err(IoError::format(
        index,
        format!(
            "timestep '{name}': no data file (tried {} and {})",
            appended.display(),
            relative.display()
        ),
    ))
}

/// Reads one binary timestep file.
fn read_timestep(path: &Path) -> Result<ParticleTable, IoError> {
    let mut file = File::open(path).map_err(|e| IoError::io(path, e))?;
    let len = file.metadata().map_err(|e| IoError::io(path, e))?.len();
    if len < 8 {
        return Err(IoError::format(
            path,
            format!("only {len} bytes long, too short for the u64 particle count"),
        ));
    }
    let mut head = [0u8; 8];
    file.read_exact(&mut head)
        .map_err(|e| IoError::io(path, e))?;
    let fits = |n: u64| n.checked_mul(RECORD).and_then(|b| b.checked_add(8)) == Some(len);
    let little = u64::from_le_bytes(head);
    let big = u64::from_be_bytes(head);
    let (count, big_endian) = if fits(little) {
        (little, false)
    } else if fits(big) {
        (big, true)
    } else {
        let declared = little
            .checked_mul(RECORD)
            .map_or("more than 2^64".to_string(), |b| b.to_string());
        return Err(IoError::format(
            path,
            format!(
                "the header declares {little} particles ({declared} bytes of records) but \
                 {} bytes follow it; a timestep file is a u64 count and 16 bytes per particle",
                len - 8
            ),
        ));
    };
    // `count * 16 + 8 == len`, so the buffer is exactly the rest of the file.
    let n = usize::try_from(count)
        .map_err(|_| IoError::format(path, format!("{count} particles is too many")))?;
    let mut bytes = vec![0u8; n * RECORD as usize];
    file.read_exact(&mut bytes)
        .map_err(|e| IoError::io(path, e))?;
    let mut positions = Vec::with_capacity(n);
    let mut attribute = Vec::with_capacity(n);
    for record in bytes.chunks_exact(RECORD as usize) {
        let mut v = [0f32; 4];
        for (slot, b) in v.iter_mut().zip(record.chunks_exact(4)) {
            let b = [b[0], b[1], b[2], b[3]];
            *slot = if big_endian {
                f32::from_be_bytes(b)
            } else {
                f32::from_le_bytes(b)
            };
        }
        positions.push([v[0], v[1], v[2]]);
        attribute.push(v[3]);
    }
    Ok(ParticleTable {
        positions,
        columns: vec![("attribute".to_string(), attribute)],
        time: None,
        domain: None,
    })
}
