//! PNG and OpenEXR round trips.

mod common;

use common::TempFile;
use voxless_io::{
    IoError, read_exr_gray, read_png_rgb8, write_exr_gray, write_exr_rgba, write_png_rgb8,
};

#[test]
fn png_round_trip() {
    let (w, h) = (5u32, 3u32);
    let rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 17 % 256) as u8).collect();
    let file = TempFile::new("rt.png");
    write_png_rgb8(file.path(), w, h, &rgb).unwrap();
    let bytes = std::fs::read(file.path()).unwrap();
    assert!(bytes.windows(4).any(|c| c == b"sRGB"), "missing sRGB chunk");
    assert_eq!(read_png_rgb8(file.path()).unwrap(), (w, h, rgb));
}

#[test]
fn png_length_mismatch() {
    let file = TempFile::new("bad.png");
    let err = write_png_rgb8(file.path(), 4, 4, &[0; 47]).unwrap_err();
    assert!(matches!(err, IoError::Format { .. }));
    assert!(err.to_string().contains("48"), "{err}");
    assert!(write_png_rgb8(file.path(), 0, 4, &[]).is_err());
}

#[test]
fn corrupt_png() {
    let file = TempFile::new("rt2.png");
    write_png_rgb8(file.path(), 8, 8, &[9; 192]).unwrap();
    let bytes = std::fs::read(file.path()).unwrap();
    let truncated = TempFile::with_bytes("trunc.png", &bytes[..bytes.len() / 2]);
    let err = read_png_rgb8(truncated.path()).unwrap_err();
    assert!(
        err.to_string()
            .contains(&truncated.path().display().to_string()),
        "{err}"
    );
    let garbage = TempFile::with_bytes("garbage.png", b"definitely not a png");
    assert!(matches!(
        read_png_rgb8(garbage.path()),
        Err(IoError::Format { .. })
    ));
}

#[test]
fn png_absurd_size_is_rejected() {
    // Valid PNG with its IHDR patched to claim 65535 x 65535 pixels (the CRC
    // is recomputed so that only the size check can reject it).
    let file = TempFile::new("small.png");
    write_png_rgb8(file.path(), 2, 2, &[1; 12]).unwrap();
    let mut bytes = std::fs::read(file.path()).unwrap();
    bytes[16..20].copy_from_slice(&65535u32.to_be_bytes());
    bytes[20..24].copy_from_slice(&65535u32.to_be_bytes());
    let crc = crc32(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    let patched = TempFile::with_bytes("huge.png", &bytes);
    let err = read_png_rgb8(patched.path()).unwrap_err();
    assert!(matches!(err, IoError::Format { .. }), "{err:?}");
}

/// CRC-32 as used by PNG chunks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[test]
fn exr_gray_round_trip() {
    let (w, h) = (7usize, 4usize);
    let values: Vec<f32> = (0..w * h).map(|i| i as f32 * 0.1 - 1.0).collect();
    let file = TempFile::new("gray.exr");
    write_exr_gray(file.path(), w, h, &values).unwrap();
    assert_eq!(read_exr_gray(file.path()).unwrap(), (w, h, values));
}

#[test]
fn exr_rgba_round_trip() {
    let (w, h) = (3usize, 2usize);
    let rgba: Vec<f32> = (0..w * h * 4).map(|i| i as f32 * 0.25).collect();
    let file = TempFile::new("rgba.exr");
    write_exr_rgba(file.path(), w, h, &rgba).unwrap();
    // No "Y" channel: the first channel (alphabetically "A") is returned.
    let (rw, rh, alpha) = read_exr_gray(file.path()).unwrap();
    assert_eq!((rw, rh), (w, h));
    let expected: Vec<f32> = rgba.chunks(4).map(|p| p[3]).collect();
    assert_eq!(alpha, expected);
    // Row 0 is the top row: check the channel values in full with the exr crate.
    let image = exr::prelude::read_first_rgba_layer_from_file(
        file.path(),
        |size, _| vec![[0f32; 4]; size.0 * size.1],
        move |pixels: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| {
            pixels[pos.1 * w + pos.0] = [r, g, b, a];
        },
    )
    .unwrap();
    let flat: Vec<f32> = image.layer_data.channel_data.pixels.concat();
    assert_eq!(flat, rgba);
}

#[test]
fn exr_length_mismatch_and_corrupt_file() {
    let file = TempFile::new("bad.exr");
    let err = write_exr_rgba(file.path(), 2, 2, &[0.0; 15]).unwrap_err();
    assert!(matches!(err, IoError::Format { .. }));
    let err = write_exr_gray(file.path(), 2, 2, &[0.0; 5]).unwrap_err();
    assert!(err.to_string().contains(&file.path().display().to_string()));

    write_exr_gray(file.path(), 16, 16, &[0.5; 256]).unwrap();
    let bytes = std::fs::read(file.path()).unwrap();
    let truncated = TempFile::with_bytes("trunc.exr", &bytes[..bytes.len() / 2]);
    assert!(read_exr_gray(truncated.path()).is_err());
    let garbage = TempFile::with_bytes("garbage.exr", b"not an exr file at all");
    assert!(matches!(
        read_exr_gray(garbage.path()),
        Err(IoError::Format { .. })
    ));
}

#[test]
fn missing_image_files() {
    let file = TempFile::new("missing.exr");
    assert!(matches!(
        read_exr_gray(file.path()),
        Err(IoError::Io { .. })
    ));
    let file = TempFile::new("missing.png");
    let err = read_png_rgb8(file.path()).unwrap_err();
    assert!(matches!(err, IoError::Io { .. }));
    assert!(err.to_string().contains(&file.path().display().to_string()));
}
