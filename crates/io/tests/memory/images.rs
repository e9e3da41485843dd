//! PNG and OpenEXR writers into memory and readers from memory, against the
//! path functions.

use std::io::{Cursor, Seek, SeekFrom, Write};

use voxless_io::{
    read_exr_gray, read_exr_gray_from, read_png_rgb8, read_png_rgb8_from, write_exr_gray,
    write_exr_gray_to, write_exr_rgba, write_exr_rgba_to, write_png_rgb8, write_png_rgb8_to,
};

use super::{Tally, TempDir, variants};

#[test]
fn png_in_memory_matches_file() {
    let dir = TempDir::new("png");
    let path = dir.path("img.png");
    let (w, h) = (5u32, 3u32);
    let rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 17 % 256) as u8).collect();
    write_png_rgb8(&path, w, h, &rgb).unwrap();
    let mut bytes = Vec::new();
    write_png_rgb8_to(&mut bytes, &path, w, h, &rgb).unwrap();
    assert_eq!(bytes, std::fs::read(&path).unwrap());

    let mut tally = Tally::default();
    for (v, bytes) in variants(&bytes).iter().enumerate() {
        let path = dir.write("case.png", bytes);
        tally.same(
            &format!("variant {v}"),
            read_png_rgb8(&path),
            read_png_rgb8_from(Cursor::new(bytes), &path),
        );
    }
    tally.check_both("png");

    // A buffer of the wrong length: the same error, and no file.
    let bad = dir.path("bad.png");
    let from_path = write_png_rgb8(&bad, w, h, &rgb[1..]).unwrap_err();
    let from_memory = write_png_rgb8_to(Vec::new(), &bad, w, h, &rgb[1..]).unwrap_err();
    assert_eq!(from_path.to_string(), from_memory.to_string());
    assert!(!bad.exists());
}

#[test]
fn exr_in_memory_matches_file() {
    let dir = TempDir::new("exr");
    let (w, h) = (4usize, 3usize);
    let gray: Vec<f32> = (0..w * h).map(|i| i as f32 * 0.25).collect();
    let rgba: Vec<f32> = (0..w * h * 4).map(|i| i as f32 / 7.0).collect();

    let gray_path = dir.path("gray.exr");
    write_exr_gray(&gray_path, w, h, &gray).unwrap();
    let mut gray_bytes = Cursor::new(Vec::new());
    write_exr_gray_to(&mut gray_bytes, &gray_path, w, h, &gray).unwrap();
    assert_eq!(gray_bytes.get_ref(), &std::fs::read(&gray_path).unwrap());

    let rgba_path = dir.path("rgba.exr");
    write_exr_rgba(&rgba_path, w, h, &rgba).unwrap();
    // Written after other bytes, the image is the same from its start.
    let mut shifted = Cursor::new(Vec::new());
    shifted.write_all(b"prefix").unwrap();
    write_exr_rgba_to(&mut shifted, &rgba_path, w, h, &rgba).unwrap();
    assert_eq!(
        &shifted.get_ref()[6..],
        &std::fs::read(&rgba_path).unwrap()[..]
    );

    // And read from there on.
    shifted.seek(SeekFrom::Start(6)).unwrap();
    let mut tally = Tally::default();
    tally.same(
        "rgba",
        read_exr_gray(&rgba_path),
        read_exr_gray_from(shifted, &rgba_path),
    );
    for (v, bytes) in variants(gray_bytes.get_ref()).iter().enumerate() {
        let path = dir.write("case.exr", bytes);
        tally.same(
            &format!("gray variant {v}"),
            read_exr_gray(&path),
            read_exr_gray_from(Cursor::new(bytes), &path),
        );
    }
    tally.check_both("exr");
    let (_, _, values) = read_exr_gray_from(Cursor::new(gray_bytes.get_ref()), &gray_path).unwrap();
    assert_eq!(values, gray);

    // A buffer of the wrong length: the same error, and no file.
    let bad = dir.path("bad.exr");
    let from_path = write_exr_gray(&bad, w, h, &gray[1..]).unwrap_err();
    let from_memory =
        write_exr_gray_to(Cursor::new(Vec::new()), &bad, w, h, &gray[1..]).unwrap_err();
    assert_eq!(from_path.to_string(), from_memory.to_string());
    assert!(!bad.exists());
}
