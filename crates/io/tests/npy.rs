//! `.npy` reading and writing, with files built byte by byte in the tests.

mod common;

use common::TempFile;
use voxless_io::{IoError, read_npy, write_npy_f32};

/// Builds a `.npy` file: magic, version, header length (u16 for 1.x, u32
/// otherwise), the dict padded like NumPy pads it, then `data`.
fn npy_bytes(major: u8, dict: &str, data: &[u8]) -> Vec<u8> {
    let len_bytes = if major == 1 { 2 } else { 4 };
    let prefix = 6 + 2 + len_bytes;
    let hlen = dict.len() + 1;
    let pad = 64 - (prefix + hlen) % 64;
    let total = hlen + pad;
    let mut out = b"\x93NUMPY".to_vec();
    out.extend_from_slice(&[major, 0]);
    if major == 1 {
        out.extend_from_slice(&(total as u16).to_le_bytes());
    } else {
        out.extend_from_slice(&(total as u32).to_le_bytes());
    }
    out.extend_from_slice(dict.as_bytes());
    out.extend(std::iter::repeat_n(b' ', pad));
    out.push(b'\n');
    out.extend_from_slice(data);
    out
}

fn dict(descr: &str, fortran: bool, shape: &str) -> String {
    let order = if fortran { "True" } else { "False" };
    format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape}, }}")
}

/// Writes the bytes to a temp file and reads them back.
fn read_bytes(name: &str, bytes: &[u8]) -> (TempFile, Result<voxless_io::NpyArray, IoError>) {
    let file = TempFile::with_bytes(name, bytes);
    let result = read_npy(file.path());
    (file, result)
}

/// The Format message of an error, checking that it names the file.
fn format_message(file: &TempFile, result: Result<voxless_io::NpyArray, IoError>) -> String {
    let err = result.expect_err("expected an error");
    let text = err.to_string();
    assert!(
        text.contains(&file.path().display().to_string()),
        "message does not name the file: {text}"
    );
    match err {
        IoError::Format { message, .. } => message,
        other => panic!("expected a Format error, got {other:?}"),
    }
}

#[test]
fn f32_round_trip() {
    let data: Vec<f32> = (0..30).map(|i| i as f32 * 0.5 - 3.0).collect();
    let file = TempFile::new("rt.npy");
    write_npy_f32(file.path(), &[10, 3], &data).unwrap();
    let bytes = std::fs::read(file.path()).unwrap();
    assert_eq!(bytes.len(), 128 + 30 * 4, "data must start at byte 128");
    let arr = read_npy(file.path()).unwrap();
    assert_eq!(arr.shape, [10, 3]);
    assert_eq!(arr.dtype, "<f4");
    let expected: Vec<f64> = data.iter().map(|&v| f64::from(v)).collect();
    assert_eq!(arr.data, expected);
}

#[test]
fn written_header_is_numpys() {
    let file = TempFile::new("hdr.npy");
    write_npy_f32(file.path(), &[4], &[1.0, 2.0, 3.0, 4.0]).unwrap();
    let bytes = std::fs::read(file.path()).unwrap();
    let expected = npy_bytes(1, &dict("<f4", false, "(4,)"), &[]);
    let n = expected.len();
    assert_eq!(n, 128);
    assert_eq!(&bytes[..n], &expected[..]);
    assert_eq!(&bytes[n..n + 4], &1.0f32.to_le_bytes());
}

#[test]
fn scalar_and_empty_round_trip() {
    let file = TempFile::new("scalar.npy");
    write_npy_f32(file.path(), &[], &[7.25]).unwrap();
    let arr = read_npy(file.path()).unwrap();
    assert!(arr.shape.is_empty());
    assert_eq!(arr.data, [7.25]);

    let file = TempFile::new("empty.npy");
    write_npy_f32(file.path(), &[0, 3], &[]).unwrap();
    let arr = read_npy(file.path()).unwrap();
    assert_eq!(arr.shape, [0, 3]);
    assert!(arr.data.is_empty());
}

#[test]
fn write_rejects_shape_mismatch() {
    let file = TempFile::new("mismatch.npy");
    let err = write_npy_f32(file.path(), &[2, 3], &[1.0; 5]).unwrap_err();
    assert!(matches!(err, IoError::Format { .. }));
    assert!(err.to_string().contains("(2, 3)"), "{err}");
    let err = write_npy_f32(file.path(), &[usize::MAX, 2], &[1.0; 5]).unwrap_err();
    assert!(matches!(err, IoError::Format { .. }));
}

#[test]
fn f8_big_endian() {
    let values = [1.5f64, -2.25, 1e300, f64::NEG_INFINITY];
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
    let (_f, arr) = read_bytes("be.npy", &npy_bytes(1, &dict(">f8", false, "(4,)"), &data));
    let arr = arr.unwrap();
    assert_eq!(arr.dtype, ">f8");
    assert_eq!(arr.data, values);
}

#[test]
fn fortran_order_2d_is_transposed() {
    // The 2x3 matrix [[1, 2, 3], [4, 5, 6]] stored column by column.
    let column_major = [1.0f32, 4.0, 2.0, 5.0, 3.0, 6.0];
    let data: Vec<u8> = column_major.iter().flat_map(|v| v.to_le_bytes()).collect();
    let (_f, arr) = read_bytes(
        "fortran.npy",
        &npy_bytes(1, &dict("<f4", true, "(2, 3)"), &data),
    );
    let arr = arr.unwrap();
    assert_eq!(arr.shape, [2, 3]);
    assert_eq!(arr.data, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);

    // Fortran order changes nothing for 1-D arrays.
    let (_f, arr) = read_bytes(
        "fortran1d.npy",
        &npy_bytes(1, &dict("<f4", true, "(6,)"), &data),
    );
    assert_eq!(arr.unwrap().data, [1.0, 4.0, 2.0, 5.0, 3.0, 6.0]);
}

#[test]
fn versions_2_and_3() {
    let data: Vec<u8> = [3.0f32, 4.0].iter().flat_map(|v| v.to_le_bytes()).collect();
    for major in [2, 3] {
        let bytes = npy_bytes(major, &dict("<f4", false, "(2,)"), &data);
        assert_eq!((bytes.len() - data.len()) % 64, 0);
        let (_f, arr) = read_bytes("v2.npy", &bytes);
        assert_eq!(arr.unwrap().data, [3.0, 4.0], "version {major}.0");
    }
}

#[test]
fn integer_and_bool_dtypes() {
    let i4: Vec<u8> = [-1i32, 0, 7, i32::MIN]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let (_f, arr) = read_bytes("i4.npy", &npy_bytes(1, &dict("<i4", false, "(2, 2)"), &i4));
    let arr = arr.unwrap();
    assert_eq!(arr.shape, [2, 2]);
    assert_eq!(arr.data, [-1.0, 0.0, 7.0, f64::from(i32::MIN)]);

    let cases: [(&str, Vec<u8>, Vec<f64>); 7] = [
        ("|i1", vec![0x80, 0x7f], vec![-128.0, 127.0]),
        ("|u1", vec![0, 255], vec![0.0, 255.0]),
        (">i2", vec![0xff, 0xfe, 0x01, 0x00], vec![-2.0, 256.0]),
        ("<u2", vec![0xff, 0xff, 0x01, 0x00], vec![65535.0, 1.0]),
        (
            ">u4",
            [7u32, 1 << 31]
                .iter()
                .flat_map(|v| v.to_be_bytes())
                .collect(),
            vec![7.0, 2147483648.0],
        ),
        (
            "<i8",
            [-5i64, 1 << 40]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
            vec![-5.0, 1099511627776.0],
        ),
        ("|b1", vec![0, 1], vec![0.0, 1.0]),
    ];
    for (descr, data, expected) in cases {
        let (_f, arr) = read_bytes(
            "ints.npy",
            &npy_bytes(1, &dict(descr, false, "(2,)"), &data),
        );
        let arr = arr.unwrap_or_else(|e| panic!("{descr}: {e}"));
        assert_eq!(arr.data, expected, "{descr}");
    }
    let u8s: Vec<u8> = [u64::MAX].iter().flat_map(|v| v.to_le_bytes()).collect();
    let (_f, arr) = read_bytes("u8.npy", &npy_bytes(1, &dict("<u8", false, "(1,)"), &u8s));
    assert_eq!(arr.unwrap().data, [u64::MAX as f64]);
}

#[test]
fn half_floats() {
    let data = [0x00, 0x3c, 0x00, 0xc0]; // 1.0, -2.0 little-endian
    let (_f, arr) = read_bytes("f2.npy", &npy_bytes(1, &dict("<f2", false, "(2,)"), &data));
    assert_eq!(arr.unwrap().data, [1.0, -2.0]);
}

#[test]
fn header_with_double_quotes_and_odd_spacing() {
    let d = "{ \"shape\" : ( 3 , ) ,\"descr\":\"<f8\" , \"fortran_order\":False}";
    let data: Vec<u8> = [1.0f64, 2.0, 3.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let (_f, arr) = read_bytes("quotes.npy", &npy_bytes(1, d, &data));
    assert_eq!(arr.unwrap().data, [1.0, 2.0, 3.0]);
}

#[test]
fn truncated_data_names_path_and_sizes() {
    let bytes = npy_bytes(1, &dict("<f4", false, "(1000000, 3)"), &[0u8; 400]);
    let (file, result) = read_bytes("trunc.npy", &bytes);
    let message = format_message(&file, result);
    assert_eq!(
        message,
        "header declares 1000000 x 3 float32 values (12000000 bytes) but only 400 bytes follow"
    );
}

#[test]
fn trailing_bytes_are_an_error() {
    let bytes = npy_bytes(1, &dict("<f4", false, "(2,)"), &[0u8; 12]);
    let (file, result) = read_bytes("trailing.npy", &bytes);
    let message = format_message(&file, result);
    assert!(message.contains("4 unexpected trailing bytes"), "{message}");
}

#[test]
fn bad_magic() {
    let mut bytes = npy_bytes(1, &dict("<f4", false, "(1,)"), &[0u8; 4]);
    bytes[1] = b'X';
    let (file, result) = read_bytes("magic.npy", &bytes);
    assert!(format_message(&file, result).contains("magic"));

    let (file, result) = read_bytes("short.npy", b"\x93NUM");
    assert!(format_message(&file, result).contains("too short"));
}

#[test]
fn unsupported_version() {
    let mut bytes = npy_bytes(1, &dict("<f4", false, "(1,)"), &[0u8; 4]);
    bytes[6] = 4;
    let (file, result) = read_bytes("version.npy", &bytes);
    assert!(format_message(&file, result).contains("version 4.0"));
}

#[test]
fn absurd_shapes_do_not_allocate() {
    let bytes = npy_bytes(1, &dict("<f8", false, "(99999999999, 3)"), &[0u8; 24]);
    let (file, result) = read_bytes("absurd.npy", &bytes);
    let message = format_message(&file, result);
    assert!(message.contains("99999999999 x 3 float64"), "{message}");
    assert!(message.contains("but only 24 bytes follow"), "{message}");

    // The element count overflows usize.
    let shape = "(4294967296, 4294967296, 4294967296)";
    let (file, result) = read_bytes(
        "overflow.npy",
        &npy_bytes(1, &dict("<f8", false, shape), &[]),
    );
    assert!(format_message(&file, result).contains("too large"));

    // A dimension that does not even fit in usize.
    let shape = "(123456789012345678901234567890,)";
    let (file, result) = read_bytes("huge.npy", &npy_bytes(1, &dict("<f8", false, shape), &[]));
    assert!(format_message(&file, result).contains("too large"));
}

#[test]
fn header_length_beyond_file() {
    let mut bytes = npy_bytes(2, &dict("<f4", false, "(1,)"), &[0u8; 4]);
    bytes[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    let (file, result) = read_bytes("hlen.npy", &bytes);
    assert!(format_message(&file, result).contains("header length"));
}

#[test]
fn unsupported_dtypes_are_named() {
    let (file, result) = read_bytes(
        "c8.npy",
        &npy_bytes(1, &dict("<c8", false, "(1,)"), &[0u8; 8]),
    );
    assert_eq!(
        format_message(&file, result),
        "unsupported dtype '<c8' (expected float32, float64 or an integer type)"
    );
    let (file, result) = read_bytes(
        "obj.npy",
        &npy_bytes(1, &dict("|O", false, "(1,)"), &[0u8; 8]),
    );
    assert!(format_message(&file, result).contains("'|O'"));

    let d = "{'descr': [('x', '<f4'), ('y', '<f4')], 'fortran_order': False, 'shape': (1,), }";
    let (file, result) = read_bytes("struct.npy", &npy_bytes(1, d, &[0u8; 8]));
    assert!(format_message(&file, result).contains("[('x', '<f4'), ('y', '<f4')]"));
}

#[test]
fn corrupt_header_text() {
    for (i, d) in [
        "{'descr': '<f4', 'fortran_order': False}",
        "{'descr': '<f4', 'fortran_order': False, 'shape': (1,), 'extra': 1}",
        "not a dict at all",
        "{'descr': '<f4', 'fortran_order': Maybe, 'shape': (1,)}",
        "{'descr': '<f4', 'fortran_order': False, 'shape': ('a',)}",
    ]
    .iter()
    .enumerate()
    {
        let (file, result) = read_bytes("corrupt.npy", &npy_bytes(1, d, &[0u8; 4]));
        let message = format_message(&file, result);
        assert!(message.contains("header"), "case {i}: {message}");
    }
}

#[test]
fn missing_file_is_an_io_error_naming_the_path() {
    let file = TempFile::new("does-not-exist.npy");
    let err = read_npy(file.path()).unwrap_err();
    assert!(matches!(err, IoError::Io { .. }), "{err:?}");
    let text = err.to_string();
    assert!(text.contains(&file.path().display().to_string()), "{text}");
    assert!(std::error::Error::source(&err).is_some());
}
