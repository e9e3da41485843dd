//! `--device cpu|gpu|auto` end to end. With the `gpu` feature: `render`
//! and `project --device gpu` equal `--device cpu` (renders within 1/255
//! per channel, projections within 1e-5 of the peak and in Σ), on whatever
//! adapter wgpu finds (skipped with a notice where there is none, a
//! failure under `VOXLESS_REQUIRE_GPU=1`); no adapter, or a setting the GPU
//! does not carry, is an error naming what to do under `gpu` and a note
//! under `auto`. Without the feature: `gpu` is an error naming the feature
//! and `auto` renders on the CPU with a note.

mod common;

#[cfg(feature = "gpu")]
use std::process::Command;

#[cfg(feature = "gpu")]
use common::read;
use common::{Scratch, fails, ok, write_positions, write_values};

/// A small scene: particles with radii, masses and an attribute.
fn scene(s: &Scratch) -> Vec<String> {
    let p = write_positions(&s.path("p.npy"), 3000, 11);
    write_values(&s.path("h.npy"), &vec![0.05; p.len()]);
    let attr: Vec<f32> = p.iter().map(|q| q[0] + 2.0 * q[2]).collect();
    write_values(&s.path("a.npy"), &attr);
    [
        "--particles",
        &s.str("p.npy"),
        "--radii",
        &s.str("h.npy"),
        "--kernel",
        "cubic-spline",
        "--attribute",
        &s.str("a.npy"),
    ]
    .iter()
    .map(|a| a.to_string())
    .collect()
}

/// `command`, the scene's flags, then `more`.
fn args<'a>(command: &'a str, base: &'a [String], more: &[&'a str]) -> Vec<&'a str> {
    std::iter::once(command)
        .chain(base.iter().map(String::as_str))
        .chain(more.iter().copied())
        .collect()
}

#[cfg(not(feature = "gpu"))]
#[test]
fn without_the_feature_gpu_is_an_error_and_auto_a_note() {
    let s = Scratch::new("gpu-cli-off");
    let base = scene(&s);
    let out = s.str("r.png");
    let e = fails(&args(
        "render",
        &base,
        &["--size", "32", "24", "--device", "gpu", "-o", &out],
    ));
    assert!(e.contains("--features gpu"), "{e}");
    let e = ok(&args(
        "render",
        &base,
        &["--size", "32", "24", "--device", "auto", "-o", &out],
    ));
    assert!(e.contains("device auto: on the CPU"), "{e}");
}

/// Whether `voxless info --devices` lists an adapter (a failure instead
/// of a skip under `VOXLESS_REQUIRE_GPU=1`).
#[cfg(feature = "gpu")]
fn have_gpu() -> bool {
    let out = Command::new(common::bin())
        .args(["info", "--devices"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let found = out.status.success() && !text.contains("no GPU adapter");
    voxless_core::testing::prerequisite(
        found,
        "VOXLESS_REQUIRE_GPU",
        &format!("a GPU adapter ({text})"),
    )
}

#[cfg(feature = "gpu")]
#[test]
fn render_and_project_on_the_gpu_equal_the_cpu() {
    if !have_gpu() {
        return;
    }
    let s = Scratch::new("gpu-cli-same");
    let base = scene(&s);
    let view = [
        "--size",
        "80",
        "60",
        "--eye",
        "1.9",
        "-1.2",
        "1.4",
        "--look-at",
        "0.5",
        "0.5",
        "0.5",
    ];
    let mut images = Vec::new();
    for dev in ["cpu", "gpu"] {
        let r = s.str(&format!("r_{dev}.png"));
        let mut a = args("render", &base, &["--device", dev, "-o", &r]);
        a.extend(view);
        let e = ok(&a);
        if dev == "gpu" {
            assert!(e.contains("on the GPU"), "{e}");
        }
        let p = s.str(&format!("p_{dev}.npy"));
        ok(&args(
            "project",
            &base,
            &[
                "--axis", "y", "--size", "64", "48", "--device", dev, "-o", &p,
            ],
        ));
        let png = voxless::io::read_png_rgb8(&s.path(&format!("r_{dev}.png")))
            .unwrap()
            .2;
        images.push((png, read(&s.path(&format!("p_{dev}.npy"))).1));
    }
    let ((ra, pa), (rb, pb)) = (&images[0], &images[1]);
    let lit = ra.iter().filter(|&&v| v > 10).count();
    assert!(lit > ra.len() / 20, "the render shows too little");
    let worst = ra
        .iter()
        .zip(rb)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(worst <= 1, "render: {worst}/255");
    let peak = pa.iter().cloned().fold(0.0, f64::max);
    let dp = pa
        .iter()
        .zip(pb)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / peak;
    let (sa, sb): (f64, f64) = (pa.iter().sum(), pb.iter().sum());
    assert!(
        dp <= 1e-5 && (sa - sb).abs() <= 1e-5 * sa,
        "projection: pixel {dp:.1e}, Σ {sa} vs {sb}"
    );
}

#[cfg(feature = "gpu")]
#[test]
fn what_the_gpu_cannot_do_is_an_error_under_gpu_and_a_note_under_auto() {
    let s = Scratch::new("gpu-cli-refuse");
    let base = scene(&s);
    let out = s.str("r.png");
    // No adapter: wgpu told to look for DirectX 12 only.
    let run = |dev: &str| {
        Command::new(common::bin())
            .env("WGPU_BACKEND", "dx12")
            .args(args(
                "render",
                &base,
                &["--size", "32", "24", "--device", dev, "-o", &out],
            ))
            .output()
            .unwrap()
    };
    let o = run("gpu");
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("mesa-vulkan-drivers") && !e.contains("panicked"),
        "{e}"
    );
    let o = run("auto");
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && e.contains("device auto: on the CPU"),
        "{e}"
    );
    if !have_gpu() {
        return;
    }
    // A setting the GPU does not carry yet: named.
    let e = fails(&args(
        "render",
        &base,
        &[
            "--size", "32", "24", "--iso", "0.5", "--device", "gpu", "-o", &out,
        ],
    ));
    assert!(e.contains("not on the GPU yet: iso-surfaces"), "{e}");
    let e = ok(&args(
        "render",
        &base,
        &[
            "--size", "32", "24", "--iso", "0.5", "--device", "auto", "-o", &out,
        ],
    ));
    assert!(e.contains("rendering on the CPU"), "{e}");
}
