//! Numeric CSV tables with a header line.
//!
//! The first line that is neither empty nor a `#` comment names the columns.
//! If that line contains a comma, every line is split at commas; otherwise
//! every line is split at runs of whitespace (spaces or tabs). All later lines
//! are rows of numbers (anything Rust's `f64` parser accepts, including
//! `nan`, `inf` and `-inf`). Empty lines and `#` comment lines are skipped
//! anywhere. A UTF-8 byte order mark and CRLF line endings are accepted, and
//! names or values wrapped in double quotes are unquoted.
//!
//! The file is streamed line by line; only the parsed numbers are kept.
//! [`read_csv_from`] reads the same text from any reader (bytes in memory,
//! a socket); [`read_csv`] opens the file and calls it.

use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use crate::IoError;

/// A table of numbers stored column by column.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CsvTable {
    /// Column names from the header line, trimmed, in file order.
    pub columns: Vec<String>,
    /// One vector per column, all of the same length.
    pub data: Vec<Vec<f64>>,
}

impl CsvTable {
    /// The values of the column called `name`, compared case-insensitively
    /// after trimming whitespace; `None` if there is no such column.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        let wanted = name.trim().to_lowercase();
        let index = self
            .columns
            .iter()
            .position(|c| c.to_lowercase() == wanted)?;
        self.data.get(index).map(Vec::as_slice)
    }

    /// Number of data rows (0 for a table with only a header).
    pub fn rows(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }
}

/// How the fields of a line are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Separator {
    Comma,
    Whitespace,
}

/// Splits a (trimmed) line into fields, unquoting `"..."` fields.
fn fields(line: &str, sep: Separator) -> impl Iterator<Item = &str> + Clone {
    let is_sep = move |c: char| match sep {
        Separator::Comma => c == ',',
        Separator::Whitespace => c.is_whitespace(),
    };
    line.split(is_sep)
        // Runs of whitespace make empty pieces; empty comma fields are kept.
        .filter(move |field| sep == Separator::Comma || !field.is_empty())
        .map(|field| {
            let field = field.trim();
            field
                .strip_prefix('"')
                .and_then(|f| f.strip_suffix('"'))
                .unwrap_or(field)
        })
}

/// Reads a numeric CSV table (see the module docs for the accepted layout).
///
/// A file with a header but no rows gives an empty table. Fails with
/// [`IoError::Format`] if there is no header line, a column name is empty or
/// repeated, or a row has the wrong number of fields or a field that is not a
/// number; the message gives the line number and the column name.
pub fn read_csv(path: &Path) -> Result<CsvTable, IoError> {
    let file = File::open(path).map_err(|e| IoError::io(path, e))?;
    read_csv_from(file, path)
}

/// [`read_csv`] over the text `reader` yields (e.g. a byte slice); `name`
/// only labels errors, which read exactly as [`read_csv`]'s for a file of
/// that name. Only the parsed numbers are kept, so no allocation depends on
/// a size the input declares.
pub fn read_csv_from<R: Read>(reader: R, name: &Path) -> Result<CsvTable, IoError> {
    let mut reader = BufReader::new(reader);
    let fmt =
        |line: usize, message: String| IoError::format(name, format!("line {line}: {message}"));

    let mut table = CsvTable::default();
    let mut separator = None;
    let mut buf = Vec::new();
    let mut line_no = 0usize;
    loop {
        buf.clear();
        if reader
            .read_until(b'\n', &mut buf)
            .map_err(|e| IoError::io(name, e))?
            == 0
        {
            break;
        }
        line_no += 1;
        let text = std::str::from_utf8(&buf).map_err(|e| {
            fmt(
                line_no,
                format!(
                    "not valid UTF-8 text (bad byte at column {})",
                    e.valid_up_to() + 1
                ),
            )
        })?;
        let text = if line_no == 1 {
            text.strip_prefix('\u{feff}').unwrap_or(text)
        } else {
            text
        };
        // `trim` also removes the "\r\n" or "\n" line ending.
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        match separator {
            None => {
                let sep = if text.contains(',') {
                    Separator::Comma
                } else {
                    Separator::Whitespace
                };
                table.columns = parse_header(text, sep).map_err(|m| fmt(line_no, m))?;
                table.data = vec![Vec::new(); table.columns.len()];
                separator = Some(sep);
            }
            Some(sep) => parse_row(text, sep, &mut table).map_err(|m| fmt(line_no, m))?,
        }
    }
    if separator.is_none() {
        return Err(IoError::format(
            name,
            "no header line with column names (the file is empty or holds only comments)",
        ));
    }
    Ok(table)
}

/// Parses and checks the column names of the header line.
fn parse_header(text: &str, sep: Separator) -> Result<Vec<String>, String> {
    let names: Vec<String> = fields(text, sep).map(str::to_string).collect();
    if names.iter().all(|n| n.parse::<f64>().is_ok()) {
        return Err(format!(
            "expected a header line with column names but found only numbers: '{text}' \
             (a header commented out with '#' is not read)"
        ));
    }
    // Duplicates by a map of the names seen (linear in the columns: a
    // header of 10⁵ names is checked at once).
    let mut seen = std::collections::HashMap::with_capacity(names.len());
    for (i, name) in names.iter().enumerate() {
        if name.is_empty() {
            return Err(format!("column {} of the header has an empty name", i + 1));
        }
        if let Some(j) = seen.insert(name.to_lowercase(), i) {
            return Err(format!(
                "duplicate column name '{name}' (columns {} and {})",
                j + 1,
                i + 1
            ));
        }
    }
    Ok(names)
}

/// Parses one data row, appending its values to the table's columns.
fn parse_row(text: &str, sep: Separator, table: &mut CsvTable) -> Result<(), String> {
    let expected = table.columns.len();
    let found = fields(text, sep).count();
    if found < expected {
        return Err(format!(
            "expected {expected} values but found {found} (column '{}' is missing)",
            table.columns[found]
        ));
    }
    if found > expected {
        return Err(format!(
            "expected {expected} values but found {found} (extra values after column '{}')",
            table.columns[expected - 1]
        ));
    }
    for ((field, name), column) in fields(text, sep).zip(&table.columns).zip(&mut table.data) {
        let value = field.parse::<f64>().map_err(|_| {
            if field.is_empty() {
                format!("column '{name}' is empty")
            } else {
                format!("column '{name}': cannot parse '{field}' as a number")
            }
        })?;
        column.push(value);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_fields() {
        let v: Vec<&str> = fields(" a , \"b\",c ", Separator::Comma).collect();
        assert_eq!(v, ["a", "b", "c"]);
        let v: Vec<&str> = fields("a\t b  c", Separator::Whitespace).collect();
        assert_eq!(v, ["a", "b", "c"]);
        let v: Vec<&str> = fields("1,,3", Separator::Comma).collect();
        assert_eq!(v, ["1", "", "3"]);
    }

    #[test]
    fn header_checks() {
        assert!(
            parse_header("x,y,X", Separator::Comma)
                .unwrap_err()
                .contains("'X'")
        );
        assert!(
            parse_header("x,,z", Separator::Comma)
                .unwrap_err()
                .contains("column 2")
        );
        assert!(parse_header("1.0 2.0", Separator::Whitespace).is_err());
        assert_eq!(
            parse_header("x 1", Separator::Whitespace).unwrap(),
            ["x", "1"]
        );
    }

    #[test]
    fn special_numbers_parse() {
        for s in ["nan", "NaN", "inf", "-inf", "Infinity", "+1.5", "1e-3"] {
            assert!(s.parse::<f64>().is_ok(), "{s}");
        }
    }

    #[test]
    fn column_lookup() {
        let t = CsvTable {
            columns: vec!["Density".into(), "x".into()],
            data: vec![vec![1.0, 2.0], vec![3.0, 4.0]],
        };
        assert_eq!(t.column("  density ").unwrap(), [1.0, 2.0]);
        assert_eq!(t.column("X").unwrap(), [3.0, 4.0]);
        assert!(t.column("y").is_none());
        assert_eq!(t.rows(), 2);
        assert_eq!(CsvTable::default().rows(), 0);
    }
}
