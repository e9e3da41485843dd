//! Meshes, ambient occlusion and mirror instances through the binary:
//! they change the image, do not depend on the data's units, and bad
//! values are refused by name.

mod common;
use common::*;

/// A PLY floor under the unit cube's data and a wall behind it, in
/// coordinates `x·scale + shift`.
fn write_floor(path: &std::path::Path, scale: f64, shift: f64) {
    let v = [
        [-0.5, -0.5, -0.05],
        [1.5, -0.5, -0.05],
        [1.5, 1.5, -0.05],
        [-0.5, 1.5, -0.05],
        [-0.5, 1.5, 1.2],
        [1.5, 1.5, 1.2],
    ];
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty double x\nproperty double y\n\
         property double z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n",
        v.len()
    );
    for p in v {
        let q = p.map(|c| c * scale + shift);
        s += &format!("{:.17e} {:.17e} {:.17e}\n", q[0], q[1], q[2]);
    }
    s += "3 0 1 2\n3 0 2 3\n3 3 2 5\n3 3 5 4\n";
    std::fs::write(path, s).unwrap();
}

fn blob(scale: f64, shift: f64) -> Vec<[f64; 3]> {
    let mut rng = Lcg(4);
    (0..2000)
        .map(|_| {
            let p = [rng.f() as f64, 0.6 * rng.f() as f64, 0.4 * rng.f() as f64];
            p.map(|c| c * scale + shift)
        })
        .collect()
}

/// The blob (and, with `mesh`, the floor) in units `scale`, offset
/// `shift`, rendered with `extra` flags.
fn render(s: &Scratch, tag: &str, scale: f64, shift: f64, mesh: bool, extra: &[&str]) -> Vec<u8> {
    write_f64(&s.path(&format!("p{tag}.npy")), &blob(scale, shift));
    write_floor(&s.path(&format!("m{tag}.ply")), scale, shift);
    let radius = format!("{}", 0.1 * scale);
    let out = s.str(&format!("{tag}.png"));
    let pos = s.str(&format!("p{tag}.npy"));
    let floor = s.str(&format!("m{tag}.ply"));
    let mut args = vec![
        "render",
        "--particles",
        &pos,
        "--radius",
        &radius,
        "--size",
        "64",
        "48",
        "--orbit",
        "30",
        "--elevation",
        "25",
        "-o",
        &out,
    ];
    if mesh {
        args.extend(["--mesh", floor.as_str()]);
    }
    args.extend_from_slice(extra);
    ok(&args);
    voxless_io::read_png_rgb8(std::path::Path::new(&out))
        .unwrap()
        .2
}

fn max_diff(a: &[u8], b: &[u8]) -> u8 {
    a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap()
}

#[test]
fn meshes_ao_and_mirrors_change_the_image_in_any_units() {
    let s = Scratch::new("surfaces");
    let plain = render(&s, "plain", 1.0, 0.0, false, &[]);
    let mesh = render(&s, "a", 1.0, 0.0, true, &[]);
    assert!(
        max_diff(&plain, &mesh) > 20,
        "--mesh does not change the image"
    );
    let ao = render(&s, "b", 1.0, 0.0, true, &["--ao", "4"]);
    assert!(max_diff(&mesh, &ao) > 5, "--ao does not change the image");
    // Occlusion only darkens.
    assert!(mesh.iter().zip(&ao).all(|(m, a)| a <= m));
    let mirrored = render(&s, "c", 1.0, 0.0, true, &["--mirror", "x"]);
    assert!(
        max_diff(&mesh, &mirrored) > 20,
        "--mirror does not change the image"
    );
    // The same scene in other units and far from the origin.
    for (tag, scale, shift) in [("d", 1e6, 0.0), ("e", 1.0, 1e7), ("f", 1e-6, 0.0)] {
        let far = render(&s, tag, scale, shift, true, &["--ao", "4"]);
        assert!(max_diff(&ao, &far) <= 2, "x{scale} +{shift}: image differs");
    }
}

#[test]
fn bad_surface_settings_are_named() {
    let s = Scratch::new("surfaces-bad");
    let pos = s.str("p.npy");
    write_positions(&s.path("p.npy"), 200, 1);
    let out = s.str("o.png");
    let base = [
        "render",
        "--particles",
        &pos,
        "--size",
        "16",
        "16",
        "-o",
        &out,
    ];
    let with = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        fails(&a)
    };
    let missing = s.str("missing.ply");
    assert!(with(&["--mesh", &missing]).contains("missing.ply"));
    let odd = s.str("mesh.off");
    std::fs::write(&odd, "OFF\n").unwrap();
    assert!(with(&["--mesh", &odd]).contains(".ply"));
    assert!(with(&["--ao", "2"]).contains("--ao"));
    assert!(with(&["--ao-distance", "1"]).contains("--ao"));
    assert!(with(&["--mirror", "w"]).contains("mirror"));
    assert!(with(&["--mirror", "x", "--mirror", "x=1"]).contains("mirror"));
    let bad = s.str("bad.ply");
    std::fs::write(
        &bad,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
    )
    .unwrap();
    let e = with(&["--mesh", &bad]);
    assert!(e.contains("bad.ply") && e.contains('7'), "{e}");
}
