//! Effects tables of a tessellation (Figure 5 of the phase-space paper),
//! all against the exact render of the framing view:
//!
//! - **Culling**: per view, the (block, tile) pairs `raster::Frame` bins
//!   against every block in every tile, and the exact render
//!   (`voxless_render::render` of the `TetVolume`) against the same
//!   integrator over [`Binned`] with every block in every tile (timed with
//!   `--unculled`). The last column checks the wrapper: its image with the
//!   frame's own bins (and, when timed, with all bins) against the library's.
//!   Views: the framing view, a 4× zoom (same eye, field of view 7.5°), and a
//!   camera inside the box.
//! - **k-buffer**: `RenderSettings::event_budget = Some(EventBudget { k,
//!   layers: 64 })` for k = 4 … 64 against the exact render (time ratio, max
//!   and mean abs RGBA difference, share of covered pixels with at least k
//!   events, where the k-buffer is inexact).
//! - **LOD**: `TetVolume::with_lod_pixels` thresholds on the mesh with 3
//!   coarser levels, against the same mesh without LOD (exact mode).

use anyhow::Result;
use voxless_core::{Camera, Control, EventBudget, Projection, Vec3, Volume};
use voxless_render::RenderSettings;
use voxless_tets::TetVolume;
use voxless_tets::raster::{Frame, TILE};
use voxless_transfer::TransferFunction;

use super::unculled::{Binned, Bins};
use super::work::{sci, work};
use super::{Exact, TetsArgs};
use crate::common::{bench, image_diff, save_png};

/// Renders through the shared integrator; no progress, never cancelled.
fn render<V: voxless_core::Prepare>(
    vol: &V,
    camera: &Camera,
    tf: &TransferFunction,
    settings: &RenderSettings,
) -> Result<voxless_core::Image> {
    Ok(voxless_render::render(
        vol,
        camera,
        tf,
        settings,
        &Control::new(),
    )?)
}

pub(super) fn bench_effects(
    label: &str,
    vol: TetVolume,
    exact: &Exact,
    o: &TetsArgs,
) -> Result<()> {
    let size = o.size;
    let (tf, settings) = (&exact.view.tf, &exact.view.settings);
    let stem = label.replace(['³', ' '], "");

    // ---- culling
    let b = vol.bounds();
    let c = b.center();
    let framing = exact.view.camera;
    let zoom = Camera::look_at(
        framing.eye,
        c,
        Vec3::new(0.0, 1.0, 0.0),
        Projection::Perspective { fov_y_deg: 7.5 },
    )?;
    let inside = Camera::look_at(
        c,
        c + Vec3::new(1.0, 0.3, 0.2),
        Vec3::new(0.0, 1.0, 0.0),
        Projection::Perspective { fov_y_deg: 60.0 },
    )?;
    let mesh = &vol.mesh;
    println!("### Phase-space tessellation effects: {label}, {size}×{size}\n");
    println!(
        "Block culling. \"binned\" counts (block, tile) pairs; \"all\" is every block in every tile. \
         Times: exact mode, the library's render vs the same integrator with every block in \
         every tile.\n"
    );
    println!(
        "| view | blocks | blocks on screen | binned / all | pixel tests | crossings | culled s | unculled s | speedup | max abs diff vs `render` |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let tiles = (size.div_ceil(TILE) * size.div_ceil(TILE)) as u64;
    for (name, cam) in [
        ("framing (whole box)", framing),
        ("zoom 4× (fov 7.5°)", zoom),
        ("inside (eye at centre, fov 60°)", inside),
    ] {
        let frame = Frame::new(mesh, &cam, size, size, None);
        let binned: u64 = frame.bins.iter().map(|b| b.len() as u64).sum();
        let all = mesh.blocks().len() as u64 * tiles;
        let on_screen = frame.blocks_per_level[0];
        drop(frame);
        let (w, _) = work(mesh, &cam, size, None);
        // A view whose pixel tests exceed the work limit would take hours.
        let feasible = w.crossings.is_some();
        let (culled, unculled, diff) = if feasible {
            eprintln!("tets/{label}: culling, {name}");
            let (tc, img) = bench(o.repeats, || (), |_| render(&vol, &cam, tf, settings));
            let img = img?;
            if let Some(dir) = &o.save {
                let v = name.split(' ').next().unwrap_or("view");
                save_png(&dir.join(format!("{stem}-view-{v}.png")), &img)?;
            }
            // The wrapper with the library's bins: the check that only the
            // bins differ between the two timed variants.
            let culled_bins = Binned {
                volume: &vol,
                bins: Bins::Culled,
            };
            let mut diff = image_diff(&render(&culled_bins, &cam, tf, settings)?, &img).0;
            let tu = if o.unculled {
                let every = Binned {
                    volume: &vol,
                    bins: Bins::All,
                };
                let (tu, img_u) = bench(o.repeats, || (), |_| render(&every, &cam, tf, settings));
                let d = image_diff(&img_u?, &img).0;
                if d > 0.0 {
                    eprintln!("warning: unculled image differs by {d:e}");
                }
                diff = diff.max(d);
                Some(tu)
            } else {
                None
            };
            (format!("{tc:.2}"), tu, format!("{diff:.1e}"))
        } else {
            ("not timed".into(), None, "—".into())
        };
        let (un, speed) = match (unculled, culled.parse::<f64>().ok()) {
            (Some(tu), Some(tc)) => (format!("{tu:.2}"), format!("{:.1}", tu / tc)),
            _ => ("—".into(), "—".into()),
        };
        println!(
            "| {name} | {} | {on_screen} | {:.3} | {} | {} | {culled} | {un} | {speed} | {diff} |",
            mesh.blocks().len(),
            binned as f64 / all as f64,
            sci(w.tests as f64),
            w.crossings.map_or("—".into(), |c| sci(c as f64)),
        );
    }
    println!();

    // ---- k-buffer
    println!(
        "k-buffer (`EventBudget {{ k, layers: 64 }}`) against exact mode, framing view. \
         Inexact pixels: covered pixels with ≥ k events (2 per crossing).\n"
    );
    println!("| mode | s | time / exact | max abs diff | mean abs diff | inexact pixels |");
    println!("|---|---:|---:|---:|---:|---:|");
    println!("| exact | {:.2} | 1.00 | 0 | 0 | 0 % |", exact.time);
    let covered = exact.crossings.iter().filter(|&&c| c > 0).count().max(1);
    for k in [4usize, 8, 16, 32, 64] {
        eprintln!("tets/{label}: k-buffer k = {k}");
        let kbuffer = RenderSettings {
            event_budget: Some(EventBudget { k, layers: 64 }),
            ..settings.clone()
        };
        let (t, img) = bench(o.repeats, || (), |_| render(&vol, &framing, tf, &kbuffer));
        let img = img?;
        let (max, mean) = image_diff(&img, &exact.image);
        let inexact = exact
            .crossings
            .iter()
            .filter(|&&c| 2 * c as usize >= k)
            .count();
        println!(
            "| k = {k} | {t:.2} | {:.2} | {max:.3} | {mean:.2e} | {:.1} % |",
            t / exact.time,
            100.0 * inexact as f64 / covered as f64
        );
        if let Some(dir) = &o.save {
            save_png(&dir.join(format!("{stem}-kbuffer{k}.png")), &img)?;
        }
    }
    println!();

    // ---- LOD
    println!(
        "Level of detail: blocks whose screen box is below the threshold use coarser levels \
         (one per halving; {} levels built). Exact mode, framing view, against the same mesh without LOD.\n",
        mesh.lod().len()
    );
    println!(
        "| lod_pixels | blocks per level (0/1/2/3) | pixel tests | s | time / no LOD | max abs diff | mean abs diff |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    let (w0, _) = work(mesh, &framing, size, None);
    println!(
        "| none | {} | {} | {:.2} | 1.00 | 0 | 0 |",
        mesh.blocks().len(),
        sci(w0.tests as f64),
        exact.time
    );
    let mut vol = vol;
    for p in [8.0f32, 16.0, 32.0, 64.0, 128.0] {
        eprintln!("tets/{label}: LOD {p} px");
        vol = vol.with_lod_pixels(Some(p));
        let frame = Frame::new(&vol.mesh, &framing, size, size, Some(p));
        let per_level: Vec<String> = frame
            .blocks_per_level
            .iter()
            .map(|b| b.to_string())
            .collect();
        drop(frame);
        let (w, _) = work(&vol.mesh, &framing, size, Some(p));
        let (t, img) = bench(o.repeats, || (), |_| render(&vol, &framing, tf, settings));
        let img = img?;
        let (max, mean) = image_diff(&img, &exact.image);
        println!(
            "| {p} | {} | {} | {t:.2} | {:.2} | {max:.3} | {mean:.2e} |",
            per_level.join(" / "),
            sci(w.tests as f64),
            t / exact.time
        );
        if let Some(dir) = &o.save {
            save_png(&dir.join(format!("{stem}-lod{p}.png")), &img)?;
        }
    }
    println!();
    Ok(())
}
