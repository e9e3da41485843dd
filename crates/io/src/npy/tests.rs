use super::*;

#[test]
fn header_matches_numpy_layout() {
    let h = npy_header("<f4", &[10, 3]);
    assert_eq!(h.len() % ALIGN, 0);
    assert_eq!(&h[..8], b"\x93NUMPY\x01\x00");
    let text = std::str::from_utf8(&h[10..]).unwrap();
    assert!(text.starts_with("{'descr': '<f4', 'fortran_order': False, 'shape': (10, 3), }"));
    assert!(text.ends_with(" \n"));
    assert_eq!(usize::from(u16::from_le_bytes([h[8], h[9]])), h.len() - 10);
}

#[test]
fn shape_repr() {
    assert_eq!(shape_text(&[]), "()");
    assert_eq!(shape_text(&[7]), "(7,)");
    assert_eq!(shape_text(&[2, 3, 4]), "(2, 3, 4)");
}

#[test]
fn parses_header_variants() {
    let h = parse_header("{\"shape\": (4,3,), 'fortran_order':True,'descr':'>f8',}  \n").unwrap();
    assert_eq!(h.shape, vec![4, 3]);
    assert!(h.fortran_order);
    assert_eq!(h.descr, ">f8");
    let h = parse_header("{'descr': '<i4', 'fortran_order': False, 'shape': (), }").unwrap();
    assert!(h.shape.is_empty());
    let h = parse_header("{'descr': '<i8', 'fortran_order': False, 'shape': (5L, 2L)}").unwrap();
    assert_eq!(h.shape, vec![5, 2]);
}

#[test]
fn rejects_bad_headers() {
    let bad = [
        "{'descr': '<f4', 'shape': (3,), }",
        "{'descr': '<f4', 'fortran_order': False, 'shape': (3,), 'x': 1}",
        "{'descr': '<f4', 'fortran_order': False, 'shape': (-3,), }",
        "{'descr': '<f4', 'fortran_order': 0, 'shape': (3,), }",
        "{'descr': '<f4', 'fortran_order': False, 'shape': (3,) ",
        "{'descr': '<f4', 'fortran_order': False, 'shape': ((((((((((((((((((((3,)))))))))))))))))))), }",
        "{'descr: '<f4'}",
        "",
    ];
    for text in bad {
        assert!(parse_header(text).is_err(), "accepted {text:?}");
    }
}

#[test]
fn structured_dtype_is_named() {
    let err = parse_header(
        "{'descr': [('x', '<f4'), ('y', '<f4')], 'fortran_order': False, 'shape': (3,), }",
    )
    .unwrap_err();
    assert!(err.contains("[('x', '<f4'), ('y', '<f4')]"), "{err}");
}

#[test]
fn dtype_parsing() {
    assert_eq!(
        Dtype::parse(">f8").unwrap(),
        Dtype {
            kind: Kind::Float,
            size: 8,
            big_endian: true
        }
    );
    assert_eq!(Dtype::parse("|b1").unwrap().kind, Kind::Bool);
    assert_eq!(Dtype::parse("<u2").unwrap().name(), "uint16");
    for bad in [
        "<c8", "|O", "<U10", "|S3", "<f16", "<i3", "", "<", "|V8", "<M8[ns]",
    ] {
        let err = Dtype::parse(bad).unwrap_err();
        assert!(err.contains(&format!("'{bad}'")), "{err}");
    }
}

#[test]
fn half_floats() {
    assert_eq!(f16_to_f64(0x3c00), 1.0);
    assert_eq!(f16_to_f64(0xc000), -2.0);
    assert_eq!(f16_to_f64(0x7bff), 65504.0);
    assert_eq!(f16_to_f64(0x0001), 2f64.powi(-24));
    assert_eq!(f16_to_f64(0x7c00), f64::INFINITY);
    assert!(f16_to_f64(0x7e00).is_nan());
}

#[test]
fn fortran_reorder_3d() {
    // C-order values 0..24 of shape (2, 3, 4), laid out in Fortran order.
    let shape = [2, 3, 4];
    let mut fortran = vec![0.0; 24];
    for i in 0..2 {
        for j in 0..3 {
            for k in 0..4 {
                fortran[i + 2 * j + 6 * k] = (i * 12 + j * 4 + k) as f64;
            }
        }
    }
    let c = fortran_to_c(&fortran, &shape);
    assert_eq!(c, (0..24).map(|v| v as f64).collect::<Vec<_>>());
}
