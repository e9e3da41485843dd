//! The fort.q reader's fast paths against the slow ones they replace.

use super::scan::header_starts_in;
use super::{FrameHeader, parse_fortran, read_grids_in, read_grids_text};
use crate::amr::FieldPick;
use crate::decimal::{fast_decimal, fast_decimal_prefix};
use std::path::Path;

/// `n` coarse grids side by side along x and a fine one in the first,
/// with blank lines between grids, as AMRClaw writes them.
fn grids_text(n: usize) -> String {
    let mut t = String::new();
    let mut grid = |number: usize, level: usize, low: [f64; 3], dx: f64, m: usize| {
        t += &format!(
            "{number:6}                 grid_number\n{level:6}                 AMR_level\n"
        );
        for name in ["mx", "my", "mz"] {
            t += &format!("{m:6}                 {name}\n");
        }
        for (v, name) in low.iter().zip(["xlow", "ylow", "zlow"]) {
            t += &format!("{v:26.16E}    {name}\n");
        }
        for name in ["dx", "dy", "dz"] {
            t += &format!("{dx:26.16E}    {name}\n");
        }
        t += "\n";
        for c in 0..m * m * m {
            let v = (number * 1000 + c) as f64 * 0.001 + 0.5;
            t += &format!("{v:26.16E}{:26.16E}\n", -v);
        }
        t += "\n";
    };
    for g in 0..n {
        grid(g + 1, 1, [g as f64, 0.0, 0.0], 0.25, 4);
    }
    grid(n + 1, 2, [0.25, 0.25, 0.25], 0.125, 2);
    t
}

/// Any window — a byte, a few lines, the whole file — reads the same
/// cells and values, and a fault names the same line.
#[test]
fn windows_read_the_grids_the_whole_text_reads() {
    let text = grids_text(9);
    let path = Path::new("fort.q0000");
    let read = |text: &str, window: u64, ngrids: usize| {
        let header = FrameHeader {
            time: 0.0,
            meqn: 2,
            ngrids,
        };
        read_grids_in(
            text.as_bytes(),
            text.len() as u64,
            path,
            Some(header),
            window,
            &FieldPick::All,
        )
    };
    let whole = read(&text, u64::MAX, 10).unwrap();
    assert_eq!(whole.fields.len(), 2);
    for window in [1, 37, 500, 4096] {
        let got = read(&text, window, 10).unwrap();
        assert_eq!(got.cells, whole.cells, "window {window}");
        assert_eq!(got.fields, whole.fields, "window {window}");
    }
    let error = |text: &str, window: u64, ngrids: usize| match read(text, window, ngrids) {
        Ok(_) => panic!("window {window}: no error"),
        Err(e) => e.to_string(),
    };
    let broken = text.replacen("1.5060000000000000E0", "x", 1);
    assert_ne!(broken, text);
    let e = error(&broken, u64::MAX, 10);
    for window in [1, 37, 500] {
        assert_eq!(error(&broken, window, 10), e);
    }
    let at = text.find("1.5060000000000000E0").unwrap();
    let line = text[..at].matches('\n').count() + 1;
    assert!(
        e.contains("`x` is not a number") && e.contains("grid 1 "),
        "{e}"
    );
    assert!(e.contains(&format!("line {line}:")), "line {line}: {e}");
    let e = error(&text, 100, 9);
    assert!(e.contains("grid 10 after the last of the 9 grids"), "{e}");
    let e = error(&text, 100, 11);
    assert!(e.contains("after 10 grids, but fort.t declares 11"), "{e}");
    // The whole text at once (a mapped file) says the same.
    let whole = |text: &str, ngrids: usize| {
        let header = FrameHeader {
            time: 0.0,
            meqn: 2,
            ngrids,
        };
        match read_grids_text(text.as_bytes(), path, Some(header), &FieldPick::All) {
            Ok(_) => panic!("no error"),
            Err(e) => e.to_string(),
        }
    };
    assert_eq!(whole(&broken, 10), error(&broken, 1, 10));
    for ngrids in [9, 11] {
        assert_eq!(whole(&text, ngrids), error(&text, 100, ngrids));
    }
    let late = text.replacen("2.5060000000000002E0", "y", 1);
    assert_ne!(late, text);
    assert_eq!(whole(&late, 10), error(&late, 37, 10));
}

/// The fast path gives the bits the general parser (`str::parse`, with
/// Fortran's exponent letters) gives, or defers to it.
#[test]
fn fast_decimals_equal_the_general_parser() {
    let mut state = 0x9e3779b97f4a7c15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut fast = 0;
    let mut tokens: Vec<String> = [
        "0",
        "-0.0",
        "+1",
        "1.",
        ".5",
        "1e5",
        "1E-22",
        "1e23",
        "0.1D+01",
        "9007199254740993",
        "9007199254740992",
        "123456789012345678",
        "0.0000000000000000E+00",
        "1e",
        "1e+",
        ".",
        "-",
        "1.5-100",
        "inf",
        "nan",
        "1e00001",
        "00000000000000000000001",
        "12345678",
        "0.12345678",
        "00000000.00000001",
        "1234567812345678",
        "12345678123456789",
        "0.00000000",
        "1234567.8",
        "12345678e1",
        "1.2345678x",
        "9999999999999999.E+6",
        "-0.000000001234567812345678",
        "1.5E+0001",
    ]
    .map(String::from)
    .to_vec();
    for _ in 0..200_000 {
        let r = next();
        let digits = 1 + (r % 17) as usize;
        let mantissa: String = (0..digits)
            .map(|k| char::from(b'0' + ((next() >> (k % 8)) % 10) as u8))
            .collect();
        let e = (next() % 61) as i32 - 30;
        let sign = if r & 1 == 0 { "-" } else { "" };
        tokens.push(format!(
            "{sign}{}.{}E{e:+03}",
            &mantissa[..1],
            &mantissa[1..]
        ));
        tokens.push(format!("{sign}0.{mantissa}E{e:+03}"));
    }
    for t in &tokens {
        let general = parse_fortran(t);
        // The one-pass reader takes the token wherever it ends (whitespace
        // or the text's end) with the same bits, or leaves it.
        let one = fast_decimal(t.as_bytes());
        for end in ["", " ", "\n", "\t0.5"] {
            let text = format!("{t}{end}");
            let got = fast_decimal_prefix(text.as_bytes());
            assert_eq!(
                got.map(|(v, _)| v.to_bits()),
                one.map(f64::to_bits),
                "`{t}`"
            );
            assert!(got.is_none_or(|(_, n)| n == t.len()), "`{t}`: {got:?}");
        }
        if let Some(v) = one {
            fast += 1;
            let g = general.unwrap_or_else(|| panic!("`{t}`: fast {v}, general none"));
            assert_eq!(v.to_bits(), g.to_bits(), "`{t}`");
        }
    }
    // Most of AMRClaw-like tokens take the fast path.
    assert!(fast > tokens.len() / 2, "{fast} of {}", tokens.len());
}

/// Grids of one AMR level with two cell sizes, and a finer AMR level with
/// larger cells, are errors naming both grids.
#[test]
fn inconsistent_levels_name_the_grids() {
    let text = grids_text(2);
    let path = Path::new("fort.q0000");
    let read = |text: &str| {
        let header = FrameHeader {
            time: 0.0,
            meqn: 2,
            ngrids: 3,
        };
        match read_grids_in(
            text.as_bytes(),
            text.len() as u64,
            path,
            Some(header),
            1 << 20,
            &FieldPick::All,
        ) {
            Ok(_) => panic!("no error"),
            Err(e) => e.to_string(),
        }
    };
    // The fine grid (AMR level 2) with cells twice the coarse ones.
    let coarser = ["dx", "dy", "dz"].iter().fold(text.clone(), |t, d| {
        t.replace(
            &format!("1.2500000000000000E-1    {d}"),
            &format!("5.0000000000000000E-1    {d}"),
        )
    });
    let e = read(&coarser);
    assert!(
        e.contains("grid 3") && e.contains("inconsistent with grid 1"),
        "{e}"
    );
    // The second coarse grid (AMR level 1) with the fine grid's cells.
    let second = text.match_indices("grid_number").nth(1).unwrap().0;
    let (head, tail) = text.split_at(second);
    let tail = ["dx", "dy", "dz"].iter().fold(tail.to_string(), |t, d| {
        t.replacen(
            &format!("2.5000000000000000E-1    {d}"),
            &format!("1.2500000000000000E-1    {d}"),
            1,
        )
    });
    let e = read(&format!("{head}{tail}"));
    assert!(
        e.contains("grid 2") && e.contains("inconsistent with grid 1"),
        "{e}"
    );
}

/// A field picked alone reads the values the whole read gives for it,
/// through windows and over the whole text (a mapped file) alike, and a
/// malformed row in a picked read names its line.
#[test]
fn picked_fields_read_what_the_whole_read_gives() {
    let text = grids_text(9);
    let path = Path::new("fort.q0000");
    let header = || {
        Some(FrameHeader {
            time: 0.0,
            meqn: 2,
            ngrids: 10,
        })
    };
    let whole = read_grids_in(
        text.as_bytes(),
        text.len() as u64,
        path,
        header(),
        1 << 20,
        &FieldPick::All,
    )
    .unwrap();
    let pick = |name: &str| FieldPick::Named {
        names: vec![name.into()],
        first: false,
    };
    for (name, column) in [("q0", 0), ("q1", 1), ("Q1", 1)] {
        for window in [37, 4096, u64::MAX] {
            let got = read_grids_in(
                text.as_bytes(),
                text.len() as u64,
                path,
                header(),
                window,
                &pick(name),
            )
            .unwrap();
            assert_eq!(got.cells, whole.cells, "{name}, window {window}");
            assert_eq!(
                got.fields,
                vec![whole.fields[column].clone()],
                "{name}, window {window}"
            );
        }
        let mapped = read_grids_text(text.as_bytes(), path, header(), &pick(name)).unwrap();
        assert_eq!(mapped.fields, vec![whole.fields[column].clone()], "{name}");
    }
    // Without fort.t (meqn from the first row) and with the first field.
    let first = FieldPick::Named {
        names: Vec::new(),
        first: true,
    };
    let got = read_grids_text(text.as_bytes(), path, None, &first).unwrap();
    assert_eq!(got.fields, vec![whole.fields[0].clone()]);
    // A name the file lacks reads every field (the error lists them).
    let got = read_grids_text(text.as_bytes(), path, header(), &pick("density")).unwrap();
    assert_eq!(got.fields, whole.fields);
    // A row short of meqn values, and one with an extra value on a grid's
    // first row: errors naming the line.
    let row = "-1.5000000000000000E0\n";
    for to in ["\n", "-1.5000000000000000E0 7\n"] {
        let broken = text.replacen(row, to, 1);
        assert_ne!(broken, text, "{to}");
        let line = text[..text.find(row).unwrap()].matches('\n').count() + 1;
        let e = read_grids_text(broken.as_bytes(), path, header(), &pick("q0"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("but meqn is 2") && e.contains(&format!("line {line}:")),
            "line {line}: {e}"
        );
    }
}

/// Header lines found in chunks, on every core, are the ones a single
/// search finds, whatever the chunk size (markers straddling chunks).
#[test]
fn header_search_in_chunks_finds_every_grid() {
    let text = grids_text(30);
    let one = header_starts_in(text.as_bytes(), usize::MAX);
    assert_eq!(one.len(), 31);
    for chunk in [1, 5, 11, 64, 1000, 4096] {
        assert_eq!(
            header_starts_in(text.as_bytes(), chunk),
            one,
            "chunk {chunk}"
        );
    }
}

/// A device or pipe given as a fort.q is refused by name, not read as an
/// empty file.
#[test]
fn special_files_are_refused() {
    #[cfg(unix)]
    {
        let e = super::read_amrclaw(Path::new("/dev/null"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("/dev/null") && e.contains("not a regular file"),
            "{e}"
        );
    }
}
