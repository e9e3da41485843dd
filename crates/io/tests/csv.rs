//! CSV reading.

mod common;

use common::TempFile;
use voxless_io::{CsvTable, IoError, read_csv};

fn read_text(name: &str, text: &str) -> (TempFile, Result<CsvTable, IoError>) {
    let file = TempFile::with_bytes(name, text.as_bytes());
    let result = read_csv(file.path());
    (file, result)
}

/// The Format message of an error, checking that the error names the file.
fn format_message(file: &TempFile, result: Result<CsvTable, IoError>) -> String {
    let err = result.expect_err("expected an error");
    assert!(
        err.to_string().contains(&file.path().display().to_string()),
        "{err}"
    );
    match err {
        IoError::Format { message, .. } => message,
        other => panic!("expected a Format error, got {other:?}"),
    }
}

#[test]
fn header_comments_and_blank_lines() {
    let text = "# particles\n\nx, y ,z,Mass\n1,2,3,4\n# a comment\n\n  5.5 , -6e2, nan, inf\n";
    let (_f, table) = read_text("basic.csv", text);
    let table = table.unwrap();
    assert_eq!(table.columns, ["x", "y", "z", "Mass"]);
    assert_eq!(table.rows(), 2);
    assert_eq!(table.column("X").unwrap(), [1.0, 5.5]);
    assert_eq!(table.column(" mass ").unwrap()[1], f64::INFINITY);
    assert!(table.column("z").unwrap()[1].is_nan());
    assert_eq!(table.column("y").unwrap(), [2.0, -600.0]);
    assert!(table.column("w").is_none());
}

#[test]
fn bom_and_crlf() {
    let text = "\u{feff}x,y\r\n1,2\r\n\r\n3,4\r\n";
    let (_f, table) = read_text("crlf.csv", text);
    let table = table.unwrap();
    assert_eq!(table.columns, ["x", "y"]);
    assert_eq!(table.data, [vec![1.0, 3.0], vec![2.0, 4.0]]);
}

#[test]
fn whitespace_and_tab_separated() {
    let text = "x   y\tdensity\n1 2\t3\n  4\t\t5    6  \n";
    let (_f, table) = read_text("ws.txt", text);
    let table = table.unwrap();
    assert_eq!(table.columns, ["x", "y", "density"]);
    assert_eq!(table.column("density").unwrap(), [3.0, 6.0]);
}

#[test]
fn quoted_names() {
    let (_f, table) = read_text("quoted.csv", "\"x\",\"y\"\n1,2\n");
    assert_eq!(table.unwrap().columns, ["x", "y"]);
}

#[test]
fn header_only_is_an_empty_table() {
    let (_f, table) = read_text("empty.csv", "# nothing yet\nx,y,z\n\n");
    let table = table.unwrap();
    assert_eq!(table.rows(), 0);
    assert_eq!(table.data.len(), 3);
}

#[test]
fn bad_number_names_line_and_column() {
    let (file, result) = read_text("bad.csv", "x,y\n1,2\n# c\n3,abc\n");
    let message = format_message(&file, result);
    assert_eq!(
        message,
        "line 4: column 'y': cannot parse 'abc' as a number"
    );
}

#[test]
fn wrong_field_counts() {
    let (file, result) = read_text("short.csv", "x,y,z\n1,2,3\n1,2\n");
    let message = format_message(&file, result);
    assert!(message.starts_with("line 3:"), "{message}");
    assert!(message.contains("'z'"), "{message}");

    let (file, result) = read_text("long.csv", "x y\n1 2 3\n");
    let message = format_message(&file, result);
    assert!(
        message.starts_with("line 2:") && message.contains("found 3"),
        "{message}"
    );

    let (file, result) = read_text("emptyfield.csv", "x,y\n1,\n");
    let message = format_message(&file, result);
    assert_eq!(message, "line 2: column 'y' is empty");
}

#[test]
fn duplicate_columns() {
    let (file, result) = read_text("dup.csv", "x,y,X\n1,2,3\n");
    let message = format_message(&file, result);
    assert!(message.contains("duplicate column name 'X'"), "{message}");
}

#[test]
fn missing_header() {
    let (file, result) = read_text("nohead.csv", "# only a comment\n\n");
    assert!(format_message(&file, result).contains("no header"));

    let (file, result) = read_text("numbers.csv", "1,2\n3,4\n");
    assert!(format_message(&file, result).contains("header"));
}

#[test]
fn invalid_utf8() {
    let file = TempFile::with_bytes("latin1.csv", b"x,y\n1,2\n\xff,3\n");
    let message = format_message(&file, read_csv(file.path()));
    assert!(message.starts_with("line 3:"), "{message}");
}

#[test]
fn missing_file() {
    let file = TempFile::new("missing.csv");
    let err = read_csv(file.path()).unwrap_err();
    assert!(matches!(err, IoError::Io { .. }));
    assert!(err.to_string().contains(&file.path().display().to_string()));
}
