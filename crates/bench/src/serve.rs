//! `serve`: interaction latency of `voxless serve`, as a client sees it.
//!
//! A server (the `voxless-serve` library, as `voxless serve` runs it) on a
//! loopback port serves the dam-break frame and the 64³ tessellation; a
//! websocket client opens a 1024² view, waits for it to converge, then
//! repeatedly sends a camera move (an orbit by a few degrees) and records
//! the time from sending it to the arrival of (1) the first, coarse image
//! and (2) the converged full-resolution PNG — encoding, the websocket and
//! decoding of the frame header included. Drags (coarse only) are timed the
//! same way. The baseline in the same run is `render` of the same view in
//! process (the converged image's own cost), so the ratio says what the
//! serving adds.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::Args;
use futures_util::{SinkExt, StreamExt};
use serde_json::json;
use tokio_tungstenite::tungstenite::Message;
use voxless::{Control, ParticlesDesc, Scene, SceneDesc, TetsDesc};

use crate::common::{median, ms, print_header, verdict};

#[derive(Args)]
pub struct ServeArgs {
    /// Directory of the dam-break frame (positions/h/mass/speed .npy).
    #[arg(long, default_value = "../shared/data/sph-dam-break/npy_01000")]
    dam_break: PathBuf,
    /// N³ Lagrangian positions of the tessellation (.npy) and N, L.
    #[arg(
        long,
        default_value = "../shared/data/nbody-jaxpm/npy_N64_a1/positions.npy"
    )]
    tets: PathBuf,
    #[arg(long, default_value_t = 64)]
    n: usize,
    #[arg(long, default_value_t = 100.0)]
    box_size: f32,
    /// View size (square) and samples per pixel of the converged image.
    #[arg(long, default_value_t = 1024)]
    size: u32,
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// Camera moves timed per data set (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Also a large particle set: positions (.npy) in a periodic box of
    /// side `--box-size`, Wendland C2 kernels of radius `--radius` (its
    /// coarse images come from the merged preview).
    #[arg(long)]
    particles: Option<PathBuf>,
    #[arg(long, default_value_t = 0.4)]
    radius: f32,
}

fn path(p: &std::path::Path) -> Result<String> {
    let p = std::path::absolute(p)?;
    if !p.exists() {
        bail!("{} does not exist", p.display());
    }
    Ok(p.to_string_lossy().into_owned())
}

pub fn run(a: ServeArgs) -> Result<()> {
    print_header();
    let d = &a.dam_break;
    let dam = SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some(path(&d.join("positions.npy"))?),
            radii: Some(path(&d.join("h.npy"))?),
            weights: Some(path(&d.join("mass.npy"))?),
            attribute: Some(path(&d.join("speed.npy"))?),
            kernel: Some(voxless::KernelName::CubicSpline),
            ..Default::default()
        }),
        ..Default::default()
    };
    let tets = SceneDesc {
        tets: Some(TetsDesc {
            file: Some(path(&a.tets)?),
            lagrangian: Some(a.n),
            box_size: Some(a.box_size),
            ..Default::default()
        }),
        ..Default::default()
    };
    println!(
        "| data | view | in-process render s | move → first (coarse) image ms | coarse size | move → converged s | converged / render | drag → coarse ms | first image ≤ 100 ms |"
    );
    println!("|---|---|---:|---:|---|---:|---:|---:|---|");
    let mut sets = vec![
        ("dam break".to_string(), dam),
        ("64³ tessellation".to_string(), tets),
    ];
    if let Some(p) = &a.particles {
        let desc = SceneDesc {
            particles: Some(ParticlesDesc {
                file: Some(path(p)?),
                radius: Some(a.radius),
                kernel: Some(voxless::KernelName::WendlandC2),
                periodic_box: Some(voxless::BoxDesc::Side(a.box_size as f64)),
                ..Default::default()
            }),
            ..Default::default()
        };
        sets.push((format!("{} (periodic)", p.display()), desc));
    }
    for (name, desc) in sets {
        measure(&name, desc, &a)?;
    }
    Ok(())
}

/// One row of the table.
fn measure(name: &str, mut desc: SceneDesc, a: &ServeArgs) -> Result<()> {
    desc.image.spp = Some(a.spp);
    desc.image.width = Some(a.size);
    desc.image.height = Some(a.size);
    // Baseline: the same converged view rendered in process.
    let scene = Scene::open(&desc, ".".as_ref(), 0)?;
    let t = Instant::now();
    scene.render(&Control::new())?;
    let render_s = t.elapsed().as_secs_f64();
    drop(scene);

    let prepared = voxless_serve::prepare(desc, PathBuf::from("."))?;
    let server = voxless_serve::Running::start(
        prepared,
        &voxless_serve::Options {
            port: 0,
            ..Default::default()
        },
    )?;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?;
    let (first, coarse_size, converged, drag) = rt.block_on(async {
        let (mut ws, _) =
            tokio_tungstenite::connect_async(format!("ws://{}/ws", server.addr)).await?;
        let mut seq = 1;
        let hello = json!({"seq": seq, "type": "hello", "width": a.size, "height": a.size});
        ws.send(Message::Text(hello.to_string().into())).await?;
        wait(&mut ws, seq, true).await?;
        let (mut first, mut converged, mut drag, mut size) =
            (vec![], vec![], vec![], String::new());
        for _ in 0..a.repeats {
            seq += 1;
            let t = Instant::now();
            let msg = json!({"seq": seq, "type": "orbit", "yaw": 7.0, "pitch": 1.0});
            ws.send(Message::Text(msg.to_string().into())).await?;
            let (w, h) = wait(&mut ws, seq, false).await?;
            first.push(t.elapsed().as_secs_f64());
            size = format!("{w}×{h}");
            wait(&mut ws, seq, true).await?;
            converged.push(t.elapsed().as_secs_f64());
            // A drag step: the coarse image only.
            seq += 1;
            let t = Instant::now();
            let msg = json!({"seq": seq, "type": "orbit", "yaw": 3.0, "pitch": 0.0, "drag": true});
            ws.send(Message::Text(msg.to_string().into())).await?;
            wait(&mut ws, seq, false).await?;
            drag.push(t.elapsed().as_secs_f64());
        }
        anyhow::Ok((median(first), size, median(converged), median(drag)))
    })?;
    println!(
        "| {name} | {0}², {1} spp | {render_s:.2} | {2:.0} | {coarse_size} | {3:.2} | {4:.2} | {5:.0} | {6} |",
        a.size,
        a.spp,
        ms(first),
        converged,
        converged / render_s,
        ms(drag),
        verdict(first <= 0.1)
    );
    Ok(())
}

/// Waits for an image of `seq` (converged, or any); returns its size.
async fn wait<S>(ws: &mut S, seq: u64, converged: bool) -> Result<(u32, u32)>
where
    S: StreamExt<Item = Result<Message, tokio_tungstenite::tungstenite::Error>> + Unpin,
{
    loop {
        let m = tokio::time::timeout(Duration::from_secs(600), ws.next())
            .await
            .context("no image within 10 minutes")?
            .context("the server closed the socket")??;
        match m {
            Message::Binary(b) => {
                let (h, _) = voxless_serve::unpack_frame(&b).context("a frame")?;
                if h.seq == seq && (!converged || h.stage == "converged") {
                    return Ok((h.width, h.height));
                }
            }
            Message::Text(t) if t.contains("\"error\"") => bail!("the server says {t}"),
            _ => {}
        }
    }
}
