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
//!
//! **From memory.** A series is several files, so its memory variant
//! [`read_particles_from`] takes the index text from a reader and a closure
//! that opens the data of a named timestep (from a map of byte buffers, an
//! archive, a network store); [`read_particles_file`] passes one that finds
//! the file as described above. [`particles_frames_from`] counts the
//! timesteps of an index text, and [`read_particles_timestep_from`] reads
//! one timestep's data on its own.

use std::fs::File;
use std::io::{BufRead, Read, Seek};
use std::path::{Path, PathBuf};

use crate::{IoError, LineReader, ParticleTable, remaining_len};

/// Bytes per particle record: four `f32`.
const RECORD: u64 = 16;

/// Number of timesteps listed in a `.particles` index file.
///
/// Fails with [`IoError::Format`] if the index is not text or lists no
/// timestep. The timestep files themselves are not opened.
pub fn particles_frames(path: &Path) -> Result<usize, IoError> {
    let names = timestep_names(LineReader::open(path)?)?;
    Ok(names.len())
}

/// [`particles_frames`] of the index text `index` yields; `name` only
/// labels errors, which read as [`particles_frames`]'s for a file of that
/// name.
pub fn particles_frames_from<R: Read>(index: R, name: &Path) -> Result<usize, IoError> {
    let names = timestep_names(LineReader::from_read(index, name))?;
    Ok(names.len())
}

/// Reads timestep `frame` (0-based, in index order) of a `.particles` series;
/// see the module docs for the layout.
///
/// Fails with [`IoError::Format`] if the frame is past the end of the index
/// (the message says how many there are), the timestep file is missing (the
/// message names the paths tried), or its size does not match its count.
pub fn read_particles_file(path: &Path, frame: usize) -> Result<ParticleTable, IoError> {
    read_particles_from(
        File::open(path).map_err(|e| IoError::io(path, e))?,
        path,
        frame,
        |name| {
            let data = timestep_path(path, name)?;
            let file = File::open(&data).map_err(|e| IoError::io(&data, e))?;
            Ok((data, file))
        },
    )
}

/// [`read_particles_file`] with the index text from `index` (`name` labels
/// its errors) and the timestep data from `open_timestep`, which gets the
/// timestep's name as the index lists it and returns a label for the data's
/// errors (e.g. the file name it would have) with a reader over the data.
/// It is called once, for the timestep asked for, after the index is read.
///
/// The data's size is checked against the count it declares before
/// anything is allocated, as for a file. Errors read as
/// [`read_particles_file`]'s for files with those names; errors returned by
/// `open_timestep` are passed on as they are.
pub fn read_particles_from<R, T, F>(
    index: R,
    name: &Path,
    frame: usize,
    open_timestep: F,
) -> Result<ParticleTable, IoError>
where
    R: Read,
    T: Read + Seek,
    F: FnOnce(&str) -> Result<(PathBuf, T), IoError>,
{
    let names = timestep_names(LineReader::from_read(index, name))?;
    let Some(step) = names.get(frame) else {
        return Err(IoError::format(
            name,
            format!(
                "frame {frame} requested but the index lists {} timestep{} (numbered from 0)",
                names.len(),
                if names.len() == 1 { "" } else { "s" }
            ),
        ));
    };
    let (label, data) = open_timestep(step)?;
    let mut table = read_particles_timestep_from(data, &label)?;
    table.time = step.parse::<f64>().ok().filter(|t| t.is_finite());
    Ok(table)
}

/// The timestep names listed in the index.
fn timestep_names<R: BufRead>(mut lines: LineReader<R>) -> Result<Vec<String>, IoError> {
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
            lines.path(),
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

/// Reads the data of one timestep (a `u64` count, then four `f32` per
/// particle; see the module docs) from `reader`'s position to its end;
/// `name` labels errors. The table has no time: that comes from the index.
///
/// Fails with [`IoError::Format`] if the length is not `8 + 16 n` for the
/// count `n` in either byte order; nothing is allocated before that check.
pub fn read_particles_timestep_from<R: Read + Seek>(
    mut reader: R,
    name: &Path,
) -> Result<ParticleTable, IoError> {
    let len = remaining_len(&mut reader, name)?;
    if len < 8 {
        return Err(IoError::format(
            name,
            format!("only {len} bytes long, too short for the u64 particle count"),
        ));
    }
    let mut head = [0u8; 8];
    reader
        .read_exact(&mut head)
        .map_err(|e| IoError::io(name, e))?;
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
            name,
            format!(
                "the header declares {little} particles ({declared} bytes of records) but \
                 {} bytes follow it; a timestep file is a u64 count and 16 bytes per particle",
                len - 8
            ),
        ));
    };
    // `count * 16 + 8 == len`, so the buffer is exactly the rest of the file.
    let n = usize::try_from(count)
        .map_err(|_| IoError::format(name, format!("{count} particles is too many")))?;
    let mut bytes = vec![0u8; n * RECORD as usize];
    reader
        .read_exact(&mut bytes)
        .map_err(|e| IoError::io(name, e))?;
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
        positions.push([v[0] as f64, v[1] as f64, v[2] as f64]);
        attribute.push(v[3]);
    }
    Ok(ParticleTable {
        positions,
        columns: vec![("attribute".to_string(), attribute)],
        time: None,
        domain: None,
        periodic: false,
        rows: None,
        sph: None,
        ..Default::default()
    })
}
