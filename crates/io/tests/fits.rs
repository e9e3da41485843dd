//! FITS images: round trips through the reader, the header's layout card
//! by card, the checksum, invalid images, and (when a Python with astropy
//! is available) astropy reading and verifying what the writer writes.
//!
//! The astropy test runs `$VOXLESS_PYTHON` (else `python3`) and is skipped
//! with a notice when it cannot import astropy, unless
//! `VOXLESS_REQUIRE_ASTROPY=1`.

mod common;

use std::io::Cursor;
use std::path::Path;
use std::process::Command;

use common::TempFile;
use voxless_io::fits::{
    CardValue, FitsImage, LinearWcs, read_fits_image, read_fits_image_from, write_fits_image,
    write_fits_image_to,
};

const W: usize = 5;
const H: usize = 3;

/// Pixel (row r from the top, column c) = 10 r + c, and one NaN.
fn pixels() -> Vec<f32> {
    let mut data: Vec<f32> = (0..W * H).map(|i| (10 * (i / W) + i % W) as f32).collect();
    data[W + 2] = f32::NAN;
    data
}

/// A long HISTORY record, wrapped over cards.
const LONG: &str = "voxless render snapshot_042.hdf5 --part-type gas --field density \
    --projection --width 5 --height 3 --box 0 0 0 10 10 10 --colormap inferno -o map.fits";

fn image(data: &[f32]) -> FitsImage<'_> {
    FitsImage {
        wcs: Some(LinearWcs::covering(
            W,
            H,
            [-1.0, 2.0],
            [4.0, 5.0],
            ["X", "Y"],
            ["kpc", "kpc"],
        )),
        bunit: Some("g/cm^2".into()),
        cards: vec![
            (
                "OBJECT".into(),
                CardValue::Text("it's a test".into()),
                "name".into(),
            ),
            (
                "TIME".into(),
                CardValue::Real(0.1 + 0.2),
                "simulation time".into(),
            ),
            // 17 digits and an exponent: past column 30, free format.
            (
                "SCALE".into(),
                CardValue::Real(f64::MIN_POSITIVE),
                String::new(),
            ),
            (
                "NPART".into(),
                CardValue::Int(-123_456_789_012),
                "particles".into(),
            ),
            (
                "PERIODIC".into(),
                CardValue::Logical(false),
                "x".repeat(100),
            ),
            (
                "DATE-OBS".into(),
                CardValue::Text(String::new()),
                String::new(),
            ),
        ],
        history: vec!["first line\nsecond line".into(), LONG.into()],
        ..FitsImage::new(W, H, data)
    }
}

/// The header's cards as 80-character strings, up to and including END.
fn cards(bytes: &[u8]) -> Vec<String> {
    let mut out = Vec::new();
    for card in bytes.chunks_exact(80) {
        let card = std::str::from_utf8(card).expect("ASCII header").to_string();
        let end = card.starts_with("END ");
        out.push(card);
        if end {
            break;
        }
    }
    out
}

fn value<'a>(cards: &'a [(String, String)], key: &str) -> &'a str {
    let found = cards.iter().find(|(k, _)| k == key);
    found.unwrap_or_else(|| panic!("no {key}")).1.as_str()
}

#[test]
fn images_round_trip_with_rows_flipped() {
    let data = pixels();
    let f = TempFile::new("map.fits");
    write_fits_image(f.path(), &image(&data)).unwrap();
    let (cards, w, h, stored) = read_fits_image(f.path()).unwrap();
    assert_eq!((w, h), (W, H));
    // Stored bottom row first.
    let flipped: Vec<f32> = data.chunks(W).rev().flatten().copied().collect();
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&stored), bits(&flipped));
    assert_eq!(value(&cards, "SIMPLE"), "T");
    assert_eq!(value(&cards, "BITPIX"), "-32");
    assert_eq!(value(&cards, "BUNIT"), "g/cm^2");
    assert_eq!(value(&cards, "CTYPE2"), "Y");
    assert_eq!(value(&cards, "CUNIT1"), "kpc");
    assert_eq!(value(&cards, "CRPIX1"), "1.0");
    assert_eq!(value(&cards, "CDELT1"), "1.0");
    assert_eq!(value(&cards, "CRVAL2").parse::<f64>().unwrap(), 2.5);
    assert_eq!(value(&cards, "OBJECT"), "it's a test");
    assert_eq!(value(&cards, "TIME").parse::<f64>().unwrap(), 0.1 + 0.2);
    assert_eq!(
        value(&cards, "SCALE").parse::<f64>().unwrap(),
        f64::MIN_POSITIVE
    );
    assert_eq!(value(&cards, "NPART"), "-123456789012");
    assert_eq!(value(&cards, "PERIODIC"), "F");
    assert_eq!(value(&cards, "DATE-OBS"), "");
    let history: Vec<&str> = cards
        .iter()
        .filter(|(k, _)| k == "HISTORY")
        .map(|(_, v)| v.as_str())
        .collect();
    assert_eq!(history[..2], ["first line", "second line"]);
    assert!(history.len() == 5 && history[2..].iter().all(|h| h.len() <= 72));
    assert_eq!(history[2..].join(" "), LONG);

    // The same bytes through a writer, and back through a reader.
    let mut mem = Vec::new();
    write_fits_image_to(&mut mem, Path::new("mem.fits"), &image(&data)).unwrap();
    assert_eq!(mem, std::fs::read(f.path()).unwrap());
    let (cards2, ..) = read_fits_image_from(Cursor::new(&mem), Path::new("mem.fits")).unwrap();
    assert_eq!(cards2, cards);
}

#[test]
fn header_cards_follow_the_fixed_format() {
    let data = pixels();
    let mut bytes = Vec::new();
    write_fits_image_to(&mut bytes, Path::new("m.fits"), &image(&data)).unwrap();
    assert_eq!(bytes.len() % 2880, 0);
    let cards = cards(&bytes);
    let header_len = cards.len() * 80;
    let data_at = header_len.div_ceil(2880) * 2880;
    assert_eq!(bytes.len(), data_at + 2880, "one block of data");
    assert!(bytes[header_len..data_at].iter().all(|&b| b == b' '));
    assert!(bytes[data_at + W * H * 4..].iter().all(|&b| b == 0));
    let expect = [
        "SIMPLE  =                    T / conforms to FITS standard",
        "BITPIX  =                  -32 / IEEE single precision floating point",
        "NAXIS   =                    2 / number of array dimensions",
        "NAXIS1  =                    5 / width: pixels along x",
        "NAXIS2  =                    3 / height: pixels along y, row 1 at the bottom",
        "BUNIT   = 'g/cm^2  '           / unit of the pixel values",
        "CTYPE1  = 'X       '",
        "CUNIT1  = 'kpc     '",
        "CTYPE2  = 'Y       '",
        "CUNIT2  = 'kpc     '",
        "CRPIX1  =                  1.0 / reference pixel (1-based)",
    ];
    for (card, want) in cards.iter().zip(expect) {
        assert_eq!(card.trim_end(), want);
    }
    let find = |key: &str| {
        let k = format!("{key:<8}=");
        cards.iter().find(|c| c.starts_with(&k)).unwrap().clone()
    };
    assert_eq!(
        find("OBJECT").trim_end(),
        "OBJECT  = 'it''s a test'       / name"
    );
    assert_eq!(find("DATE-OBS").trim_end(), "DATE-OBS= '        '");
    assert_eq!(&find("TIME")[10..30], " 0.30000000000000004");
    assert_eq!(
        find("SCALE").trim_end(),
        "SCALE   = 2.2250738585072014E-308"
    );
    assert_eq!(&find("NPART")[10..30], "       -123456789012");
    // A comment too long for the card is cut at column 80.
    assert_eq!(
        find("PERIODIC"),
        format!("PERIODIC= {:>20} / {}", "F", "x".repeat(47))
    );
    assert!(cards.iter().all(|c| c.len() == 80 && c.is_ascii()));
    assert_eq!(cards.last().unwrap().trim_end(), "END");
    assert!(find("CHECKSUM").starts_with("CHECKSUM= '"));
}

/// The 32-bit ones' complement sum of big-endian words.
fn ones_sum(bytes: &[u8]) -> u32 {
    let mut sum = 0u64;
    for w in bytes.chunks_exact(4) {
        sum += u64::from(u32::from_be_bytes([w[0], w[1], w[2], w[3]]));
        sum = (sum & 0xffff_ffff) + (sum >> 32);
    }
    sum as u32
}

#[test]
fn checksums_make_the_unit_sum_to_minus_zero() {
    for data in [pixels(), vec![0.0; 7], vec![f32::MAX; 2881]] {
        let n = data.len();
        let img = FitsImage {
            history: vec!["checksum".into()],
            ..FitsImage::new(n, 1, &data)
        };
        let mut bytes = Vec::new();
        write_fits_image_to(&mut bytes, Path::new("c.fits"), &img).unwrap();
        let header_len = cards(&bytes).len().div_ceil(36) * 2880;
        assert_eq!(ones_sum(&bytes), 0xffff_ffff, "{n} values");
        let (cards, ..) = read_fits_image_from(Cursor::new(&bytes), Path::new("c")).unwrap();
        let datasum: u32 = value(&cards, "DATASUM").parse().unwrap();
        assert_eq!(datasum, ones_sum(&bytes[header_len..]));
    }
}

#[test]
fn invalid_images_and_cards_are_refused() {
    let data = pixels();
    let with_card = |key: &str, v: CardValue| FitsImage {
        cards: vec![(key.into(), v, String::new())],
        ..image(&data)
    };
    let mut zero_cdelt = image(&data);
    if let Some(wcs) = zero_cdelt.wcs.as_mut() {
        wcs.cdelt[1] = 0.0;
    }
    let cases = [
        (FitsImage::new(W, H - 1, &data), "needs 5·2 values but 15"),
        (FitsImage::new(0, H, &data[..0]), "at least 1 pixel"),
        (FitsImage::new(usize::MAX, 2, &data), "needs"),
        (with_card("lower", CardValue::Int(1)), "not a FITS keyword"),
        (
            with_card("NINECHARS", CardValue::Int(1)),
            "not a FITS keyword",
        ),
        (with_card("NAXIS3", CardValue::Int(1)), "sets itself"),
        (with_card("BSCALE", CardValue::Real(2.0)), "sets itself"),
        (
            with_card("BUNIT", CardValue::Text("K".into())),
            "appears twice",
        ),
        (
            with_card("T", CardValue::Real(f64::NAN)),
            "not a finite number",
        ),
        (
            with_card("T", CardValue::Real(f64::INFINITY)),
            "not a finite number",
        ),
        (
            with_card("T", CardValue::Text("µm".into())),
            "printable ASCII",
        ),
        (with_card("T", CardValue::Text("'".repeat(35))), "too long"),
        (zero_cdelt, "CDELT2 is 0"),
    ];
    for (img, wanted) in cases {
        let f = TempFile::new("bad.fits");
        let e = write_fits_image(f.path(), &img).unwrap_err().to_string();
        assert!(
            e.contains(wanted) && e.contains("bad.fits"),
            "{wanted}: {e}"
        );
        assert!(!f.path().exists());
    }
    // 68 characters fit, quotes counted twice.
    let fits = with_card("T", CardValue::Text(format!("{}''", "a".repeat(64))));
    assert!(write_fits_image_to(Vec::new(), Path::new("ok"), &fits).is_ok());
}

#[test]
fn damaged_files_are_errors_never_panics() {
    let data = pixels();
    let mut bytes = Vec::new();
    write_fits_image_to(&mut bytes, Path::new("d.fits"), &image(&data)).unwrap();
    let name = Path::new("d.fits");
    // The zero padding after the data may be missing; nothing else.
    for cut in (0..bytes.len()).step_by(37) {
        let r = read_fits_image_from(Cursor::new(&bytes[..cut]), name);
        assert_eq!(r.is_ok(), cut >= 2880 + W * H * 4, "cut at {cut}");
    }
    // SIMPLE, SIMPLE = F, BITPIX = -62, a string without its closing quote.
    for (at, byte) in [
        (0, b'X'),
        (29, b'F'),
        (80 + 28, b'6'),
        (10 * 80 + 11, b'\''),
    ] {
        let mut b = bytes.clone();
        b[at] = byte;
        assert!(
            read_fits_image_from(Cursor::new(&b), name).is_err(),
            "byte {at}"
        );
    }
    // NAXIS1 claiming far more data than the file holds.
    let mut b = bytes.clone();
    b[3 * 80 + 10..3 * 80 + 30].copy_from_slice(format!("{:>20}", u64::MAX / 2).as_bytes());
    let f = TempFile::with_bytes("huge.fits", &b);
    let e = read_fits_image(f.path()).unwrap_err().to_string();
    assert!(
        e.contains("bytes of data but") && e.contains("huge.fits"),
        "{e}"
    );
    let e = read_fits_image_from(Cursor::new(b"SIMPLE"), name).unwrap_err();
    assert!(e.to_string().contains("not a FITS file"), "{e}");
}

/// What astropy must see in the file, checked in Python. Any warning
/// (a bad checksum, a card astropy would fix, a WCS it would repair) fails.
const ASTROPY_CHECK: &str = r#"
import json, sys, warnings
import numpy as np
from astropy.io import fits
from astropy.wcs import WCS
warnings.simplefilter("error")
path, exp = sys.argv[1], json.loads(sys.argv[2])
with fits.open(path, checksum=True) as hdul:
    hdul.verify("exception")
    assert len(hdul) == 1, len(hdul)
    hdr, data = hdul[0].header, hdul[0].data
    assert data.dtype == np.dtype(">f4"), data.dtype
    rows = np.array([[np.nan if v is None else v for v in r] for r in exp["rows"]], "f4")
    assert np.array_equal(data, rows[::-1], equal_nan=True), (data, rows)
    assert hdr["BUNIT"] == exp["bunit"], hdr["BUNIT"]
    assert hdr["OBJECT"] == "it's a test", hdr["OBJECT"]
    assert hdr["TIME"] == 0.1 + 0.2 and hdr["SCALE"] == 2.2250738585072014e-308
    assert hdr["NPART"] == -123456789012 and hdr["PERIODIC"] is False
    assert " ".join(list(hdr["HISTORY"])[2:]) == exp["history"], list(hdr["HISTORY"])
    wcs = WCS(hdr)
    # Corners of the picture (numpy's 0-based pixel centres, edges at -0.5).
    lo = wcs.pixel_to_world_values(-0.5, -0.5)
    hi = wcs.pixel_to_world_values(exp["width"] - 0.5, exp["height"] - 0.5)
    first = wcs.pixel_to_world_values(0, 0)
    for got, want in [(lo, exp["lo"]), (hi, exp["hi"]), (first, exp["first"])]:
        assert np.allclose(got, want, rtol=0, atol=1e-12), (got, want)
    assert [str(u) for u in wcs.wcs.cunit] == ["kpc", "kpc"], wcs.wcs.cunit
print("astropy read the file: OK")
"#;

#[test]
fn astropy_reads_and_verifies_the_file() {
    let python = std::env::var("VOXLESS_PYTHON").unwrap_or_else(|_| "python3".into());
    let required = std::env::var("VOXLESS_REQUIRE_ASTROPY").is_ok_and(|v| v == "1");
    let found = Command::new(&python)
        .args(["-c", "import astropy, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            !required,
            "VOXLESS_REQUIRE_ASTROPY=1 but {python} cannot import astropy"
        );
        eprintln!("skipped: {python} cannot import astropy (set VOXLESS_PYTHON)");
        return;
    }
    let data = pixels();
    let f = TempFile::new("astropy.fits");
    write_fits_image(f.path(), &image(&data)).unwrap();
    let rows: Vec<Vec<Option<f32>>> = data
        .chunks(W)
        .map(|r| r.iter().map(|v| v.is_finite().then_some(*v)).collect())
        .collect();
    let expect = serde_json::json!({
        "rows": rows, "bunit": "g/cm^2", "width": W, "height": H, "history": LONG,
        "lo": [-1.0, 2.0], "hi": [4.0, 5.0], "first": [-0.5, 2.5],
    });
    let out = Command::new(&python)
        .args(["-c", ASTROPY_CHECK])
        .arg(f.path())
        .arg(expect.to_string())
        .output()
        .expect("run python");
    let text = String::from_utf8_lossy(&out.stdout) + String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "astropy check failed:\n{text}");
    assert!(text.contains("OK"), "{text}");
}
