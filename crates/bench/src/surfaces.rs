//! `voxless-bench surfaces`: what a large mesh and ambient occlusion cost
//! in a frame.
//!
//! The dam break (cubic spline, h and m per particle, coloured by speed)
//! rendered three ways, interleaved per repetition: the volume alone, with
//! a triangle mesh (the tank from `tools/dam_break_mesh.py`, or without
//! `--mesh` a synthetic open box of `--triangles` triangles around the
//! fluid), and with the mesh and 2 ambient-occlusion rays per hit. Also the
//! mesh's read and BVH build time and memory. Ratios are against the
//! volume alone in the same run.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use voxless_core::{Aabb, Control, Vec3};
use voxless_render::{AmbientOcclusion, Mesh, Paint, Surfaces};

use crate::common::{count, median, print_header};

#[derive(clap::Args)]
pub struct SurfacesArgs {
    /// The dam-break snapshot (.npy layout).
    #[arg(long, default_value = "../shared/data/sph-dam-break/npy_01000")]
    dam_break: PathBuf,
    /// A mesh file (PLY, OBJ, STL, VTP) in the data's coordinates; default
    /// a synthetic open box around the fluid.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Triangles of the synthetic box.
    #[arg(long, default_value_t = 1_000_000)]
    triangles: usize,
    /// Image width and height.
    #[arg(long, num_args = 2, default_values_t = [800, 600])]
    size: Vec<u32>,
    /// Repetitions (median reported).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
}

pub fn run(o: SurfacesArgs) -> Result<()> {
    if o.repeats == 0 || o.size.contains(&0) {
        bail!("--repeats and --size must be > 0");
    }
    let d = o.dam_break.to_string_lossy().into_owned();
    let desc: voxless::SceneDesc = toml::from_str(&format!(
        "[particles]\nfile = '{d}/positions.npy'\nradii = '{d}/h.npy'\nweights = '{d}/mass.npy'\n\
         attribute = '{d}/speed.npy'\nkernel = 'cubic-spline'\n\
         [image]\nwidth = {}\nheight = {}\n\
         [camera]\neye = [2.2, -2.1, 4.4]\nlook_at = [1.6, 0.0, 0.0]\nup = [0.0, 0.0, 1.0]\n",
        o.size[0], o.size[1]
    ))?;
    eprintln!("surfaces: loading the dam break");
    let scene = voxless::Scene::open(&desc, std::path::Path::new("."), 0)?;
    let t = Instant::now();
    let (mesh, what) = match &o.mesh {
        Some(p) => {
            let m = voxless_io::read_surface(p)?;
            let mesh = Mesh {
                positions: m
                    .positions
                    .iter()
                    .map(|q| scene.frame.to_local(*q).to_array())
                    .collect(),
                triangles: m.triangles,
                fields: Vec::new(),
            };
            (mesh, p.display().to_string())
        }
        None => (
            open_box(&scene.volume.bounds(), o.triangles),
            "synthetic open box".to_string(),
        ),
    };
    let paint = Paint::Solid([0.6, 0.6, 0.6]);
    let surfaces = Surfaces::new(&[(&mesh, &paint)])?;
    let t_build = t.elapsed().as_secs_f64();
    let mut with_mesh = scene.view.settings.clone();
    with_mesh.surfaces = Some(surfaces.clone());
    let mut with_ao = with_mesh.clone();
    with_ao.ao = Some(AmbientOcclusion {
        rays: 2,
        distance: 0.1 * scene.volume.bounds().diagonal(),
    });
    let variants = [
        ("volume alone", &scene.view.settings),
        ("+ mesh", &with_mesh),
        ("+ mesh + AO 2 rays", &with_ao),
    ];
    let mut times = vec![Vec::new(); variants.len()];
    for rep in 0..o.repeats {
        for (i, (name, s)) in variants.iter().enumerate() {
            let t = Instant::now();
            scene
                .volume
                .render(&scene.view.camera, &scene.view.tf, s, &Control::new())?;
            times[i].push(t.elapsed().as_secs_f64());
            eprintln!("surfaces: rep {rep}: {name} {:.2} s", times[i][rep]);
        }
    }
    print_header();
    println!(
        "### Surfaces: dam break {}×{}, 1 spp; mesh {} ({} triangles, read + BVH {:.2} s, {:.0} MB)\n",
        o.size[0],
        o.size[1],
        what,
        count(surfaces.triangle_count()),
        t_build,
        surfaces.memory_bytes() as f64 / 1e6
    );
    println!("| frame | median s | ratio to the volume alone |");
    println!("|---|---:|---:|");
    let base = median(times[0].clone());
    for ((name, _), t) in variants.iter().zip(times) {
        let m = median(t);
        println!("| {name} | {m:.2} | {:.2} |", m / base);
    }
    println!();
    Ok(())
}

/// A floor and four walls around `b` (open at the top), `n` triangles in
/// all, as square grids.
fn open_box(b: &Aabb, n: usize) -> Mesh {
    let per_face = (n as f64 / 10.0).sqrt().ceil().max(1.0) as u32;
    let (lo, hi) = (b.min - b.extent() * 0.05, b.max + b.extent() * 0.05);
    let mut m = Mesh::default();
    // (corner, u edge, v edge) of each face.
    let faces = [
        (
            lo,
            Vec3::new(hi.x - lo.x, 0.0, 0.0),
            Vec3::new(0.0, hi.y - lo.y, 0.0),
        ),
        (
            lo,
            Vec3::new(hi.x - lo.x, 0.0, 0.0),
            Vec3::new(0.0, 0.0, hi.z - lo.z),
        ),
        (
            Vec3::new(lo.x, hi.y, lo.z),
            Vec3::new(hi.x - lo.x, 0.0, 0.0),
            Vec3::new(0.0, 0.0, hi.z - lo.z),
        ),
        (
            lo,
            Vec3::new(0.0, hi.y - lo.y, 0.0),
            Vec3::new(0.0, 0.0, hi.z - lo.z),
        ),
        (
            Vec3::new(hi.x, lo.y, lo.z),
            Vec3::new(0.0, hi.y - lo.y, 0.0),
            Vec3::new(0.0, 0.0, hi.z - lo.z),
        ),
    ];
    let k = per_face;
    for (c, u, v) in faces {
        let base = m.positions.len() as u32;
        for j in 0..=k {
            for i in 0..=k {
                let p = c + u * (i as f32 / k as f32) + v * (j as f32 / k as f32);
                m.positions.push(p.to_array());
            }
        }
        for j in 0..k {
            for i in 0..k {
                let a = base + j * (k + 1) + i;
                m.triangles.push([a, a + 1, a + k + 2]);
                m.triangles.push([a, a + k + 2, a + k + 1]);
            }
        }
    }
    m
}
