//! `voxless serve` on every data kind, over the websocket protocol: a tab
//! orbits, changes the transfer function and saves the scene, and
//! `voxless render` of the saved file draws the tab's converged image —
//! the same pixels (≤ 1/255 allowed; the renderer is deterministic, so 0 is
//! expected).

#[path = "../../serve/tests/support/mod.rs"]
mod support;

use std::path::Path;
use std::process::Command;

use serde_json::{Value, json};
use support::*;
use voxless::{AmrDesc, SceneDesc, TetsDesc};

fn decode(png_bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let mut reader = png::Decoder::new(std::io::Cursor::new(png_bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Runs a tab's session on `desc`; returns the largest channel difference
/// between its converged image and `voxless render` of its saved scene.
fn session_vs_render(s: &Scratch, desc: SceneDesc, patch: Value) -> u8 {
    let server = serve(desc, "127.0.0.1");
    let (png_bytes, toml) = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .unwrap()
        .block_on(async {
            let mut ws = connect(server.addr, None).await;
            send(
                &mut ws,
                json!({"seq": 1, "type": "hello", "width": 96, "height": 64}),
            )
            .await;
            until_converged(&mut ws, 1).await;
            send(
                &mut ws,
                json!({"seq": 2, "type": "orbit", "yaw": 25.0, "pitch": 12.5, "drag": true}),
            )
            .await;
            send(&mut ws, json!({"seq": 3, "type": "end_drag"})).await;
            until_converged(&mut ws, 3).await;
            send(&mut ws, json!({"seq": 4, "type": "set", "patch": patch})).await;
            let msgs = until_converged(&mut ws, 4).await;
            let Some(Msg::Frame(_, png_bytes)) = msgs.into_iter().last() else {
                unreachable!()
            };
            send(&mut ws, json!({"seq": 5, "type": "save_scene"})).await;
            loop {
                if let Some(Msg::Text(v)) = next(&mut ws).await
                    && v["type"] == "scene"
                {
                    return (png_bytes, v["toml"].as_str().unwrap().to_string());
                }
            }
        });
    let scene = s.0.join("saved.toml");
    std::fs::write(&scene, &toml).unwrap();
    let out = s.0.join("cli.png");
    let run = Command::new(env!("CARGO_BIN_EXE_voxless"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}\n{toml}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (w, h, page) = decode(&png_bytes);
    let (w2, h2, cli) = decode(&std::fs::read(&out).unwrap());
    assert_eq!((w, h), (w2, h2));
    page.iter()
        .zip(&cli)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap_or(0)
}

fn tf_patch() -> Value {
    json!({"transfer": {"colormap": "magma", "opacity_points": [[0.0, 0.0], [0.4, 0.1], [1.0, 0.9]]},
           "image": {"spp": 3}})
}

#[test]
fn particles_saved_scene_renders_the_page_image() {
    let s = Scratch::new("cli-particles");
    let mut desc = particle_scene(&s, 2000);
    desc.light = Some(Default::default());
    let mut patch = tf_patch();
    patch["particles"] = json!({"radius_scale": 1.25});
    assert!(session_vs_render(&s, desc, patch) <= 1);
}

#[test]
fn materials_saved_scene_renders_the_page_image() {
    let s = Scratch::new("cli-materials");
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut desc = voxless::read_scene(&examples.join("materials.toml")).unwrap();
    let p = desc.particles.as_mut().unwrap();
    p.file = Some(examples.join("nacl.xyz").to_string_lossy().into_owned());
    let patch = json!({"render": {"opacity_scale": 2.5}, "image": {"spp": 2}});
    assert!(session_vs_render(&s, desc, patch) <= 1);
}

#[test]
fn amr_saved_scene_renders_the_page_image() {
    let s = Scratch::new("cli-amr");
    // Two levels over [0, 8)³ finest cells: a fine corner, coarse elsewhere.
    let mut cells: Vec<[i32; 4]> = Vec::new();
    for z in (0..8).step_by(2) {
        for y in (0..8).step_by(2) {
            for x in (0..8).step_by(2) {
                if x < 4 && y < 4 && z < 4 {
                    for d in 0..8 {
                        cells.push([x + (d & 1), y + (d >> 1 & 1), z + (d >> 2), 0]);
                    }
                } else {
                    cells.push([x, y, z, 1]);
                }
            }
        }
    }
    let (mut c, mut a, mut b) = (Vec::new(), Vec::new(), Vec::new());
    for cell in &cells {
        cell.iter().for_each(|v| c.extend(v.to_le_bytes()));
        let r2: i32 = (0..3).map(|k| (cell[k] - 4) * (cell[k] - 4)).sum();
        a.extend((1.0 / (1.0 + r2 as f32)).to_le_bytes());
        b.extend((cell[0] as f32).to_le_bytes());
    }
    let path = |n: &str| s.0.join(n).to_string_lossy().into_owned();
    std::fs::write(path("t.cells"), c).unwrap();
    std::fs::write(path("t.rho.scalars"), a).unwrap();
    std::fs::write(path("t.x.scalars"), b).unwrap();
    let desc = SceneDesc {
        amr: Some(AmrDesc {
            cells: Some(path("t.cells")),
            scalars: Some(vec![path("t.rho.scalars"), path("t.x.scalars")]),
            cell_size: Some(0.25),
            ..Default::default()
        }),
        ..Default::default()
    };
    let mut patch = tf_patch();
    patch["amr"] = json!({"color_field": "x"});
    patch["render"] = json!({"iso": [0.2]});
    assert!(session_vs_render(&s, desc, patch) <= 1);
}

#[test]
fn tessellation_saved_scene_renders_the_page_image() {
    let s = Scratch::new("cli-tets");
    // An 8³ Lagrangian grid, displaced by a smooth field.
    let n = 8;
    let mut pos = Vec::new();
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let q = [i, j, k].map(|v| (v as f32 + 0.5) / n as f32);
                let d = 0.04 * (std::f32::consts::TAU * q[1]).sin();
                pos.extend([(q[0] + d).rem_euclid(1.0), q[1], q[2]]);
            }
        }
    }
    let file = s.0.join("pos.npy");
    voxless::io::write_npy_f32(&file, &[n * n * n, 3], &pos).unwrap();
    let desc = SceneDesc {
        tets: Some(TetsDesc {
            file: Some(file.to_string_lossy().into_owned()),
            lagrangian: Some(n),
            box_size: Some(1.0),
            ..Default::default()
        }),
        ..Default::default()
    };
    let mut patch = tf_patch();
    patch["render"] = json!({"clip": [0.0, 0.0, 0.0, 1.0, 0.6, 1.0]});
    assert!(session_vs_render(&s, desc, patch) <= 1);
}

#[test]
fn serve_refuses_a_bad_scene_before_listening() {
    let out = Command::new(env!("CARGO_BIN_EXE_voxless"))
        .args(["serve", "--particles", "does-not-exist.npy", "--port", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("does-not-exist.npy") && !err.contains("panicked"),
        "{err}"
    );
}
