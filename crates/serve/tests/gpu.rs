//! The viewer on the GPU (`voxless serve --device gpu`, the `gpu`
//! feature): its converged `/frame.png` equals the CPU viewer's within
//! 1/255 per channel. Skipped with a notice where wgpu finds no adapter (a
//! failure under `VOXLESS_REQUIRE_GPU=1`, as CI sets on lavapipe).
#![cfg(feature = "gpu")]

mod support;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;

use support::{PATIENCE, Scratch, particle_scene};
use voxless::device::{Device, DeviceChoice};
use voxless_serve::{Options, Running};

/// The body of `GET path`.
fn get(server: &Running, path: &str) -> Vec<u8> {
    let mut s = TcpStream::connect(server.addr).unwrap();
    s.set_read_timeout(Some(PATIENCE)).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut buf = Vec::new();
    s.read_to_end(&mut buf).unwrap();
    let head_end = buf.windows(4).position(|w| w == b"\r\n\r\n").unwrap() + 4;
    let head = String::from_utf8_lossy(&buf[..head_end]);
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    assert!(
        !head
            .to_ascii_lowercase()
            .contains("transfer-encoding: chunked"),
        "{head}"
    );
    buf[head_end..].to_vec()
}

/// RGB pixels of a PNG.
fn pixels(png: &[u8]) -> Vec<u8> {
    let dir = std::env::temp_dir().join(format!("voxless-gpu-serve-{}.png", std::process::id()));
    std::fs::write(&dir, png).unwrap();
    let p = voxless::io::read_png_rgb8(&dir).unwrap().2;
    let _ = std::fs::remove_file(&dir);
    p
}

#[test]
fn the_viewer_on_the_gpu_draws_the_cpu_viewers_image() {
    let gpu = Device::open(DeviceChoice::Gpu);
    let what = match &gpu {
        Ok(_) => String::new(),
        Err(e) => format!("a GPU adapter ({e})"),
    };
    if !voxless_core::testing::prerequisite(gpu.is_ok(), "VOXLESS_REQUIRE_GPU", &what) {
        return;
    }
    let (gpu, _) = gpu.unwrap();
    let s = Scratch::new("gpu-serve");
    let desc = particle_scene(&s, 3000);
    let start = |device: Device| {
        let prepared = voxless_serve::prepare(desc.clone(), PathBuf::from(".")).unwrap();
        Running::start(
            prepared,
            &Options {
                port: 0,
                device,
                ..Default::default()
            },
        )
        .unwrap()
    };
    let (cpu_server, gpu_server) = (start(Device::cpu()), start(gpu));
    let path = "/frame.png?width=96&height=64";
    let (a, b) = (
        pixels(&get(&cpu_server, path)),
        pixels(&get(&gpu_server, path)),
    );
    assert_eq!(a.len(), b.len());
    assert!(
        a.iter().filter(|&&v| v > 10).count() > a.len() / 20,
        "the view shows too little"
    );
    let worst = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
    assert!(worst <= 1, "{worst}/255");
}
