//! Time series: a data path that names many frames.
//!
//! A path is a sequence when it is
//! - a printf-style pattern, `frame_%04d.npy` or `frame_%d.npy`: every file
//!   in that directory whose name is the prefix, a number, then the suffix;
//! - a glob in the file name, `frames/step_*.npy` (`*` and `?`);
//! - a directory: every particle file in it (`.npy`, `.csv`, `.hdf5`/`.h5`,
//!   `.vtp`, `.vtu`, `.xyz`, `.extxyz`, `.lammpstrj`, `.dump`, `.particles`),
//!   which must all have the same extension — a directory of PySPH outputs,
//!   say.
//!
//! A file's **frame number** is the last number in its name
//! (`step_0007.npy` is frame 7, `dam_break_3d_01750.hdf5` frame 1750), and
//! frames are ordered by it: frame N of a sequence is the file numbered N,
//! never the N-th file, so a missing file is a missing frame, not a shift of
//! every later one. Sequences that go together (positions and a
//! per-particle attribute, say) pair files of the same number, and a number
//! one of them lacks is an error naming it. Any other path is a single
//! frame (which may itself hold several frames, numbered 0, 1, …; see
//! `frame_numbers`). Each file of a sequence is one frame: its first, for
//! multi-frame formats.

use std::path::{Path, PathBuf};

use crate::SceneError;

/// Decides whether a file name belongs to a sequence.
type NameMatcher = Box<dyn Fn(&str) -> bool>;

/// Whether `spec` names a sequence rather than one file.
pub fn is_sequence(spec: &str, base: &Path) -> bool {
    let name = Path::new(spec)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let full = base.join(spec);
    // A directory holding one snapshot's files (snapdir_033/) is one frame,
    // as is an AMReX plotfile (a directory with a `Header`).
    name.contains('%')
        || name.contains('*')
        || name.contains('?')
        || (full.is_dir()
            && voxless_io::snapshot::snapshot_files(&full).is_none()
            && !full.join("Header").is_file())
}

/// The files of `spec` in frame order (one file when it is not a sequence).
pub fn expand(spec: &str, base: &Path) -> Result<Vec<PathBuf>, SceneError> {
    let full = base.join(spec);
    if !is_sequence(spec, base) {
        return Ok(vec![full]);
    }
    let (dir, matcher): (PathBuf, NameMatcher) = if full.is_dir() {
        let m = |n: &str| dir_extension(n).is_some();
        (full.clone(), Box::new(m))
    } else {
        let dir = full
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        let name = full
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if let Some(at) = name.find('%') {
            // %d, %4d, %04d: prefix, digits, suffix.
            let rest = &name[at + 1..];
            let spec_len = rest.find('d').ok_or_else(|| {
                SceneError::data(
                    &full,
                    "a frame pattern needs a %d (or %04d) for the frame number",
                )
            })?;
            let (prefix, suffix) = (name[..at].to_string(), rest[spec_len + 1..].to_string());
            let m = move |n: &str| {
                n.len() > prefix.len() + suffix.len()
                    && n.starts_with(&prefix)
                    && n.ends_with(&suffix)
                    && n[prefix.len()..n.len() - suffix.len()]
                        .bytes()
                        .all(|b| b.is_ascii_digit())
            };
            (dir, Box::new(m))
        } else {
            let pattern = name.clone();
            (dir, Box::new(move |n: &str| wildcard(&pattern, n)))
        }
    };
    let entries = std::fs::read_dir(&dir).map_err(|source| voxless_io::IoError::Io {
        path: dir.clone(),
        source,
    })?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| {
            // Files, and under a pattern also AMReX plotfiles (directories
            // with a Header: plt00000, plt00100, …).
            let frame = p.is_file() || (!full.is_dir() && p.join("Header").is_file());
            frame && p.file_name().is_some_and(|n| matcher(&n.to_string_lossy()))
        })
        .collect();
    files.sort_by_key(|p| {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        (last_number(&name).unwrap_or(0), name)
    });
    if files.is_empty() {
        let what = if full.is_dir() {
            "the directory holds no particle files (.npy, .csv, .hdf5, .h5, .vtp, .vtu, .xyz, \
             .extxyz, .lammpstrj, .dump, .particles)"
        } else {
            "no files match this frame pattern"
        };
        return Err(SceneError::data(&full, what));
    }
    if full.is_dir() {
        let mut exts: Vec<String> = files
            .iter()
            .filter_map(|p| {
                p.file_name()
                    .and_then(|n| dir_extension(&n.to_string_lossy()))
            })
            .collect();
        exts.sort();
        exts.dedup();
        if exts.len() > 1 {
            return Err(SceneError::data(
                &full,
                format!(
                    "the directory holds particle files of several kinds (.{}); give a pattern \
                     such as {}/*.{} to pick one",
                    exts.join(", ."),
                    full.display(),
                    exts[0]
                ),
            ));
        }
    }
    Ok(files)
}

/// The lower-case extension of a file name when it is a particle format a
/// directory sequence takes.
fn dir_extension(name: &str) -> Option<String> {
    const EXTS: [&str; 11] = [
        "npy",
        "csv",
        "hdf5",
        "h5",
        "vtp",
        "vtu",
        "xyz",
        "extxyz",
        "lammpstrj",
        "dump",
        "particles",
    ];
    let ext = Path::new(name)
        .extension()?
        .to_string_lossy()
        .to_ascii_lowercase();
    EXTS.contains(&ext.as_str()).then_some(ext)
}

/// `*` matches any run, `?` one character.
fn wildcard(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    // Classic two-pointer match with backtracking to the last `*`.
    let (mut i, mut j, mut star, mut mark) = (0, 0, None, 0);
    while j < n.len() {
        if i < p.len() && (p[i] == '?' || p[i] == n[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some(i);
            mark = j;
            i += 1;
        } else if let Some(s) = star {
            i = s + 1;
            mark += 1;
            j = mark;
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

/// The last run of digits in a file name before its extension (the `5` of
/// `.hdf5` is no frame number): its frame number. An "extension" that is
/// a frame number itself — at most one letter, then two or more digits, as
/// AMRClaw's `fort.q0002` — counts when the stem has none.
fn last_number(name: &str) -> Option<usize> {
    let (stem, ext) = match name.rfind('.') {
        Some(dot) if dot > 0 => (&name[..dot], &name[dot + 1..]),
        _ => (name, ""),
    };
    let numbered_ext = {
        let digits = ext.trim_start_matches(|c: char| c.is_ascii_alphabetic());
        ext.len() - digits.len() <= 1
            && digits.len() >= 2
            && digits.bytes().all(|b| b.is_ascii_digit())
    };
    let stem = if numbered_ext && !stem.bytes().any(|b| b.is_ascii_digit()) {
        name
    } else {
        stem
    };
    let digits: String = stem
        .chars()
        .rev()
        .skip_while(|c| !c.is_ascii_digit())
        .take_while(|c| c.is_ascii_digit())
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    digits.parse().ok()
}

/// The frame number of a file of a sequence: the last number in its name
/// (`step_0007.npy` → 7, `dam_break_3d_01750.hdf5` → 1750).
pub fn number_of(path: &Path) -> Option<usize> {
    last_number(&path.file_name()?.to_string_lossy())
}

/// The files of sequence `spec` with their frame numbers (see
/// [`number_of`]), in order. A file without a number, or two files with
/// one number, is an error naming them.
pub fn numbered(spec: &str, base: &Path) -> Result<Vec<(usize, PathBuf)>, SceneError> {
    let mut out: Vec<(usize, PathBuf)> = Vec::new();
    for f in expand(spec, base)? {
        let n = number_of(&f).ok_or_else(|| {
            SceneError::data(
                &f,
                format!(
                    "is part of the sequence {spec} but has no number in its name, so it is no \
                     numbered frame; give a pattern that leaves it out"
                ),
            )
        })?;
        if let Some((_, other)) = out.iter().find(|(m, _)| *m == n) {
            return Err(SceneError::data(
                &f,
                format!(
                    "has frame number {n}, like {} in the same sequence {spec}; give a pattern \
                     that matches one of them",
                    other.display()
                ),
            ));
        }
        out.push((n, f));
    }
    Ok(out)
}

/// The file of sequence `spec` numbered `n`; an error naming the file
/// expected (for a printf pattern) or the pattern, and the numbers there are.
pub fn file_numbered(spec: &str, base: &Path, n: usize) -> Result<PathBuf, SceneError> {
    let files = numbered(spec, base)?;
    if let Some((_, f)) = files.iter().find(|(m, _)| *m == n) {
        return Ok(f.clone());
    }
    let expected = fill_pattern(&base.join(spec), n);
    Err(SceneError::data(
        expected.unwrap_or_else(|| base.join(spec)),
        format!(
            "frame {n} is missing: the sequence {spec} has frames {}",
            list_numbers(&files.iter().map(|f| f.0).collect::<Vec<_>>())
        ),
    ))
}

/// `frame_%04d.npy` with `n` filled in; `None` when `path` is no printf
/// pattern.
pub fn fill_pattern(path: &Path, n: usize) -> Option<PathBuf> {
    let name = path.file_name()?.to_string_lossy().into_owned();
    let at = name.find('%')?;
    let rest = &name[at + 1..];
    let d = rest.find('d')?;
    let spec = &rest[..d];
    if !spec.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let width: usize = spec.trim_start_matches('0').parse().unwrap_or(0);
    Some(path.with_file_name(format!("{}{:0width$}{}", &name[..at], n, &rest[d + 1..])))
}

/// `0, 1, 2, 4, …, 9` for messages.
pub fn list_numbers(v: &[usize]) -> String {
    let show: Vec<String> = if v.len() <= 8 {
        v.iter().map(|n| n.to_string()).collect()
    } else {
        let mut s: Vec<String> = v[..4].iter().map(|n| n.to_string()).collect();
        s.push("…".into());
        s.extend(v[v.len() - 2..].iter().map(|n| n.to_string()));
        s
    };
    if show.is_empty() {
        "none".into()
    } else {
        show.join(", ")
    }
}

/// Parses `A..B` (inclusive) into a frame range.
pub fn parse_range(s: &str) -> Result<std::ops::RangeInclusive<usize>, SceneError> {
    let bad = || {
        SceneError::setting(
            "--frames",
            format!("'{s}' is not A..B (two frame numbers, A ≤ B)"),
        )
    };
    let (a, b) = s.split_once("..").ok_or_else(bad)?;
    let (a, b): (usize, usize) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if a > b {
        return Err(bad());
    }
    Ok(a..=b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plotfile_directories_are_frames_of_a_pattern() {
        let dir = std::env::temp_dir().join(format!("voxless-plt-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for d in ["plt00010", "plt00002", "plt_empty"] {
            std::fs::create_dir_all(dir.join(d)).unwrap();
        }
        std::fs::write(dir.join("plt00010/Header"), b"HyperCLaw-V1.1\n").unwrap();
        std::fs::write(dir.join("plt00002/Header"), b"HyperCLaw-V1.1\n").unwrap();
        let spec = dir.join("plt*").to_string_lossy().into_owned();
        let got: Vec<(usize, String)> = numbered(&spec, Path::new(""))
            .unwrap()
            .into_iter()
            .map(|(n, p)| (n, p.file_name().unwrap().to_string_lossy().into_owned()))
            .collect();
        // Numeric order; a directory without a Header is no plotfile.
        assert_eq!(got, vec![(2, "plt00002".into()), (10, "plt00010".into())]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn frame_numbers_come_from_the_name() {
        assert_eq!(last_number("step_0007.npy"), Some(7));
        assert_eq!(last_number("dam_break_3d_01750.hdf5"), Some(1750));
        assert_eq!(last_number("fort.q0002"), Some(2));
        assert_eq!(last_number("plt00100"), Some(100));
        assert_eq!(last_number("run.hdf5"), None);
        assert_eq!(last_number("snap.h5"), None);
        assert_eq!(last_number("a1.q0002"), Some(1));
    }

    #[test]
    fn patterns_globs_and_directories_expand_in_numeric_order() {
        let dir = std::env::temp_dir().join(format!("voxless-frames-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        for n in [
            "step_10.npy",
            "step_2.npy",
            "step_1.npy",
            "other.txt",
            "run.info",
        ] {
            std::fs::write(dir.join(n), b"x").unwrap();
        }
        let names = |v: Vec<PathBuf>| -> Vec<String> {
            v.iter()
                .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
                .collect()
        };
        let want = vec!["step_1.npy", "step_2.npy", "step_10.npy"];
        assert_eq!(names(expand("step_%d.npy", &dir).unwrap()), want);
        assert_eq!(names(expand("step_*.npy", &dir).unwrap()), want);
        assert_eq!(names(expand(".", &dir).unwrap()), want);
        assert_eq!(
            expand("single.npy", &dir).unwrap(),
            vec![dir.join("single.npy")]
        );
        assert!(expand("none_%04d.npy", &dir).is_err());
        // A directory of one other kind; a mixed directory is an error.
        let sub = dir.join("h5");
        std::fs::create_dir_all(&sub).unwrap();
        for n in ["run_00250.hdf5", "run_00000.HDF5", "run.info"] {
            std::fs::write(sub.join(n), b"x").unwrap();
        }
        assert_eq!(
            names(expand("h5", &dir).unwrap()),
            ["run_00000.HDF5", "run_00250.hdf5"]
        );
        std::fs::write(sub.join("extra.npy"), b"x").unwrap();
        let e = expand("h5", &dir).unwrap_err().to_string();
        assert!(e.contains(".hdf5") && e.contains(".npy"), "{e}");
        assert!(wildcard("a?c*", "abcdef") && !wildcard("a?c", "abcd"));
        assert_eq!(number_of(Path::new("dam_break_3d_00250.hdf5")), Some(250));
        assert_eq!(number_of(Path::new("run.0007.h5")), Some(7));
        assert_eq!(number_of(Path::new("final.npy")), None);
        assert_eq!(
            fill_pattern(Path::new("d/f_%04d.png"), 12),
            Some(PathBuf::from("d/f_0012.png"))
        );
        assert_eq!(parse_range("3..7").unwrap(), 3..=7);
        assert!(parse_range("7..3").is_err() && parse_range("x").is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
