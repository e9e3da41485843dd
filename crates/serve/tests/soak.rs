//! A bounded soak of the viewer: tabs that send a thousand hostile
//! messages between valid moves, tabs that drop in the middle of a heavy
//! render, tabs that never read, and `/frame.png` requests that leave, all
//! at once. Afterwards no render may still be running (a dropped tab or
//! request must cancel its work, not leave a core busy) and a fresh tab
//! must get a converged image of a valid view and an error for a bad one.
//!
//! The waits are liveness bounds (PATIENCE); the heavy views would take
//! far longer than that if their cancellation were lost.

mod support;

use std::io::Write;
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use support::*;
use tokio_tungstenite::tungstenite::Message;

/// Patches each of which the viewer must refuse or answer with an error,
/// never wedge on: absurd work, views that show nothing, server paths.
fn hostile_patches() -> Vec<Value> {
    vec![
        json!({"render": {"ao": 1_000_000_000u64, "iso": [0.3]}}),
        json!({"image": {"spp": 4_294_967_295u64}}),
        json!({"image": {"spp": 0}}),
        json!({"render": {"step": 1e-30}}),
        json!({"render": {"sampling_rate": 1e9}}),
        json!({"transfer": {"value_range": [0.5, 0.5]}}),
        json!({"transfer": {"value_range": [1e6, 2e6]}}),
        json!({"camera": {"eye": [1e30, 0.0, 0.0]}}),
        json!({"render": {"clip": [50.0, 50.0, 50.0, 51.0, 51.0, 51.0]}}),
        json!({"particles": {"file": "/etc/passwd"}}),
        json!({"transfer": {"colormap_file": "/dev/zero"}}),
        json!({"particles": {"radius": -1.0}}),
        json!({"image": {"width": 0}}),
        json!(5),
    ]
}

/// Deterministic choices (the test must fail the same way twice): one of
/// `0..n`.
fn below(rng: &mut voxless::core::SmallRng, n: u64) -> u64 {
    ((rng.f() as f64 * n as f64) as u64).min(n - 1)
}

/// One tab's life: hostile and valid messages mixed, then one of three
/// endings. Returns how many messages it sent.
async fn tab_life(addr: SocketAddr, who: u64, messages: usize) -> usize {
    let mut dice = voxless::core::SmallRng(who + 1);
    let mut ws = connect(addr, None).await;
    let mut seq = 1u64;
    send(
        &mut ws,
        json!({"seq": seq, "type": "hello", "width": 64 + below(&mut dice, 200), "height": 48}),
    )
    .await;
    let patches = hostile_patches();
    let mut sent = 1;
    while sent < messages {
        seq += 1;
        let msg = match below(&mut dice, 6) {
            0 | 1 => {
                let p = &patches[below(&mut dice, patches.len() as u64) as usize];
                json!({"seq": seq, "type": "set", "patch": p})
            }
            2 => {
                json!({"seq": seq, "type": "orbit", "yaw": 7.0, "pitch": 1.0, "drag": below(&mut dice, 2) == 0})
            }
            3 => {
                json!({"seq": seq, "type": "zoom", "factor": if below(&mut dice, 2) == 0 { 1e-30 } else { 1.2 }})
            }
            4 => json!({"seq": seq, "type": "reset"}),
            _ => json!({"seq": seq, "type": "frame", "frame": below(&mut dice, 3)}),
        };
        if below(&mut dice, 50) == 0 {
            use futures_util::SinkExt;
            let _ = ws.send(Message::Binary(vec![0xfe; 33].into())).await;
        } else {
            send(&mut ws, msg).await;
        }
        sent += 1;
        // Read now and then, so the server's answers flow for some tabs
        // and pile up for others.
        if who % 3 != 2 && below(&mut dice, 8) == 0 {
            let _ = tokio::time::timeout(Duration::from_millis(5), next(&mut ws)).await;
        }
    }
    match who % 3 {
        // Ends on a heavy view and drops the socket once it renders.
        0 => {
            seq = good_view(&mut ws, seq, 1024, 60000).await;
            loop {
                match next(&mut ws).await {
                    Some(Msg::Frame(h, _)) if h.seq == seq => break,
                    Some(Msg::Text(v)) if v["type"] == "error" && v["seq"] == seq => {
                        panic!("tab {who}: the heavy view fails: {v}")
                    }
                    Some(_) => {}
                    None => panic!("tab {who}: the socket closed"),
                }
            }
            drop(ws);
        }
        // Asks for a valid view and reads until it converges.
        1 => {
            seq = good_view(&mut ws, seq, 64, 2).await;
            until_converged(&mut ws, seq).await;
        }
        // Never reads a byte, then goes.
        _ => drop(ws),
    }
    sent
}

/// Resets the camera and every setting the hostile patches touch, at
/// `side`² and `spp` samples; returns the seq whose image answers.
async fn good_view(ws: &mut Ws, mut seq: u64, side: u32, spp: u32) -> u64 {
    seq += 1;
    send(
        ws,
        json!({"seq": seq, "type": "resize", "width": side, "height": side}),
    )
    .await;
    seq += 1;
    send(ws, json!({"seq": seq, "type": "reset"})).await;
    seq += 1;
    let good = json!({"render": null, "camera": null, "transfer": {"value_range": null, "colormap_file": null}, "image": {"spp": spp}});
    send(ws, json!({"seq": seq, "type": "set", "patch": good})).await;
    seq
}

/// A `/frame.png` request for a big image whose client leaves at once.
fn dropped_frame_png(addr: SocketAddr) {
    if let Ok(mut s) = TcpStream::connect(addr) {
        let _ = write!(
            s,
            "GET /frame.png?width=3000&height=3000 HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn a_thousand_hostile_messages_dropped_tabs_and_silent_clients_leave_no_render_running() {
    let s = Scratch::new("soak");
    let server = serve(particle_scene(&s, 3000), "127.0.0.1");
    let addr = server.addr;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let sent = runtime.block_on(async {
        let tabs: Vec<_> = (0..12)
            .map(|who| tokio::spawn(tab_life(addr, who, 100)))
            .collect();
        let pngs = tokio::task::spawn_blocking(move || {
            for _ in 0..6 {
                dropped_frame_png(addr);
            }
        });
        let mut sent = 0;
        for t in tabs {
            sent += tokio::time::timeout(PATIENCE, t)
                .await
                .expect("a tab finishes")
                .expect("a tab's task does not panic");
        }
        pngs.await.unwrap();
        sent
    });
    assert!(sent >= 1000, "{sent} messages");

    // Every dropped tab and request cancels its render.
    let start = Instant::now();
    while server.renders_running() > 0 {
        assert!(
            start.elapsed() < PATIENCE,
            "{} render(s) still running after every client left",
            server.renders_running()
        );
        std::thread::sleep(Duration::from_millis(20));
    }

    // A fresh tab: a valid view converges, a refused setting is an error
    // and the next move renders the last good view.
    runtime.block_on(async {
        let mut ws = connect(addr, None).await;
        send(
            &mut ws,
            json!({"seq": 1, "type": "hello", "width": 48, "height": 32}),
        )
        .await;
        until_converged(&mut ws, 1).await;
        let bad = json!({"render": {"ao": 1_000_000_000u64, "iso": [0.3]}});
        send(&mut ws, json!({"seq": 2, "type": "set", "patch": bad})).await;
        until_error(&mut ws, 2).await;
        send(
            &mut ws,
            json!({"seq": 3, "type": "orbit", "yaw": 10.0, "pitch": 0.0}),
        )
        .await;
        until_converged(&mut ws, 3).await;
    });
    assert_eq!(
        status(addr, "/frame.png?width=16&height=16", ""),
        200,
        "the server still answers /frame.png"
    );
}
