//! Builds one volume of each kind from arrays in memory — no file is read —
//! and renders each with the library's defaults:
//!
//! ```sh
//! cargo run --release --example in_memory -- OUT_DIR
//! ```
//!
//! writes `OUT_DIR/particles.png` (a ring of particles with a temperature),
//! `OUT_DIR/amr.png` (a two-level AMR blast wave) and `OUT_DIR/tets.png`
//! (the phase-space tessellation of a shell-crossed N-body sheet).

use std::path::{Path, PathBuf};

use voxless::{
    AmrArrays, AmrDesc, AnyVolume, Control, Loaded, ParticleArrays, ParticlesDesc, Scene,
    SceneDesc, TetsDesc, Vec3,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .ok_or("usage: in_memory OUT_DIR")?;
    std::fs::create_dir_all(&out)?;

    // Particles: a warped ring, hotter on the inside.
    let mut rng = voxless::core::SmallRng(7);
    let n = 60_000;
    let (mut positions, mut temperature) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for _ in 0..n {
        let a = rng.f() * std::f32::consts::TAU;
        let r = 1.0 + 0.25 * (rng.f() - 0.5) + 0.08 * (3.0 * a).sin();
        let h = 0.08 * (rng.f() - 0.5) + 0.1 * (2.0 * a).cos();
        positions.push(Vec3::new(r * a.cos(), h, r * a.sin()));
        temperature.push(1.3 - r);
    }
    let particles = AnyVolume::from_particles(
        ParticleArrays {
            positions,
            attribute: Some(temperature),
            ..Default::default()
        },
        &ParticlesDesc::default(),
    )?;
    render(particles, &out.join("particles.png"))?;

    // AMR: a spherical blast on a 32³ base grid of cells 2 wide, refined
    // (cells 1 wide) where the shock runs.
    let shell = |p: Vec3| (p - Vec3::splat(32.0)).length() - 18.0;
    let density = |p: Vec3| 1.0 + 2.0 * (-(shell(p) / 3.0).powi(2)).exp();
    let mut cells = Vec::new();
    for z in (0..64).step_by(2) {
        for y in (0..64).step_by(2) {
            for x in (0..64).step_by(2) {
                let centre = Vec3::new(x as f32 + 1.0, y as f32 + 1.0, z as f32 + 1.0);
                if shell(centre).abs() < 6.0 {
                    for k in 0..8 {
                        cells.push([x + (k & 1), y + (k >> 1 & 1), z + (k >> 2), 0]);
                    }
                } else {
                    cells.push([x, y, z, 1]);
                }
            }
        }
    }
    let values = cells
        .iter()
        .map(|c| {
            let w = (1 << c[3]) as f32;
            density(Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) + Vec3::splat(0.5 * w))
        })
        .collect();
    let amr = AnyVolume::from_amr(
        AmrArrays {
            cells,
            fields: vec![("density".into(), values)],
            origin: [0.0; 3],
            cell_size: 1.0 / 32.0,
        },
        &AmrDesc::default(),
    )?;
    render(amr, &out.join("amr.png"))?;

    // Tessellation: 48³ particles displaced by two crossing Zel'dovich
    // waves, past shell crossing, in a periodic box of side 100.
    let (side, l) = (48usize, 100.0f32);
    let k = std::f32::consts::TAU / l;
    let mut grid = Vec::with_capacity(side * side * side);
    for i in 0..side {
        for j in 0..side {
            for m in 0..side {
                let q = Vec3::new(i as f32, j as f32, m as f32) * (l / side as f32);
                let d = Vec3::new(
                    1.6 / k * (k * q.x).sin() * (0.6 + 0.4 * (k * q.y).cos()),
                    1.2 / k * (k * q.y + 0.5).sin(),
                    0.8 / k * (k * q.z).sin() * (k * q.x).cos(),
                );
                let p = q + d;
                grid.push(Vec3::new(
                    p.x.rem_euclid(l),
                    p.y.rem_euclid(l),
                    p.z.rem_euclid(l),
                ));
            }
        }
    }
    let tets = AnyVolume::from_tessellation(grid, side, l, &TetsDesc::default())?;
    render(tets, &out.join("tets.png"))?;
    Ok(())
}

/// Renders a loaded volume with every default and writes it as a PNG.
fn render(loaded: Loaded, path: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let kind = loaded.volume.kind();
    let scene = Scene::with_loaded(loaded, &SceneDesc::default(), Path::new("."))?;
    for n in &scene.view.notes {
        eprintln!("note: {n}");
    }
    let image = scene.render(&Control::new())?;
    voxless::io::write_png_rgb8(
        path,
        image.width,
        image.height,
        &image.to_srgb8(scene.view.background),
    )?;
    eprintln!("{kind} → {}", path.display());
    Ok(())
}
