//! The server's promises, checked over real sockets without a browser:
//! stale images are never sent after a newer interaction, malformed and
//! oversized messages leave it serving, traversal is 404, a bind beyond
//! loopback refuses requests without the token, and a client that does not
//! read stalls nobody else.

mod support;

use serde_json::json;
use support::*;

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
}

#[test]
fn no_image_for_an_interaction_follows_the_ack_of_a_newer_one() {
    let s = Scratch::new("stale");
    let server = serve(particle_scene(&s, 3000), "127.0.0.1");
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        send(&mut ws, json!({"seq": 1, "type": "hello", "width": 160, "height": 120})).await;
        // A burst of moves without waiting, then a resting view.
        let last = 40;
        for seq in 2..last {
            let msg = json!({"seq": seq, "type": "orbit", "yaw": 3.0, "pitch": 0.5, "drag": seq % 2 == 0});
            send(&mut ws, msg).await;
        }
        send(&mut ws, json!({"seq": last, "type": "zoom", "factor": 1.1})).await;
        let msgs = until_converged(&mut ws, last).await;
        let mut acked = 0;
        let mut images = 0;
        for m in &msgs {
            match m {
                Msg::Text(v) if v["type"] == "ack" => {
                    let seq = v["seq"].as_u64().unwrap();
                    assert!(seq > acked, "acks in order");
                    acked = seq;
                }
                Msg::Text(v) => {
                    let seq = v["seq"].as_u64().unwrap_or(0);
                    assert!(v["type"] == "error" || seq >= acked, "{v} after ack {acked}");
                }
                Msg::Frame(h, img) => {
                    images += 1;
                    assert!(h.seq >= acked, "image of {} after ack {acked}", h.seq);
                    assert!(!img.is_empty());
                }
            }
        }
        assert_eq!(acked, last);
        assert!(images >= 1);
        // The final image is the converged PNG at the full view size.
        let Some(Msg::Frame(h, img)) = msgs.last() else { unreachable!() };
        assert_eq!((h.mime.as_str(), h.width, h.height), ("image/png", 160, 120));
        assert_eq!(&img[1..4], b"PNG");
    });
}

#[test]
fn malformed_and_oversized_messages_leave_the_server_serving() {
    let s = Scratch::new("malformed");
    let server = serve(particle_scene(&s, 500), "127.0.0.1");
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        let bad = [
            "".to_string(),
            "{".into(),
            "null".into(),
            "[]".into(),
            r#"{"type": "orbit"}"#.into(),
            r#"{"seq": -1, "type": "hello", "width": 1, "height": 1}"#.into(),
            r#"{"seq": 1, "type": "nope"}"#.into(),
            r#"{"seq": 1, "type": "orbit", "yaw": "x", "pitch": 0}"#.into(),
            r#"{"seq": 1e400, "type": "reset"}"#.into(),
            r#"{"seq": 2, "type": "set", "patch": {"particles": {"file": "/etc/passwd"}}}"#.into(),
            r#"{"seq": 3, "type": "set", "patch": {"transfer": {"colormap_file": "/etc/passwd"}}}"#
                .into(),
            r#"{"seq": 4, "type": "set", "patch": 5}"#.into(),
            r#"{"seq": 4, "type": "set", "patch": {"particles": {"attribute": "/etc/passwd"}}}"#
                .into(),
            r#"{"seq": 4, "type": "set", "patch": {"amr": {"cells": "/etc/passwd"}}}"#.into(),
            r#"{"seq": 5, "type": "zoom", "factor": -3}"#.into(),
            r#"{"seq": 6, "type": "frame", "frame": 99999999}"#.into(),
            r#"{"seq": 7, "type": "colormap_import", "json": "{]"}"#.into(),
            "\u{0}\u{1}\u{2}".into(),
            "x".repeat(10_000),
        ];
        use futures_util::SinkExt;
        use tokio_tungstenite::tungstenite::Message;
        for i in 0..10_000 {
            let m = &bad[i % bad.len()];
            if i % 97 == 0 {
                ws.send(Message::Binary(vec![0xff; 64].into()))
                    .await
                    .unwrap();
            } else {
                ws.send(Message::Text(m.clone().into())).await.unwrap();
            }
        }
        // The socket still works after all that: a valid view renders.
        send(
            &mut ws,
            json!({"seq": 100, "type": "hello", "width": 64, "height": 48}),
        )
        .await;
        until_converged(&mut ws, 100).await;
        // Oversized messages close their own socket, nothing else.
        for _ in 0..20 {
            let mut big = connect(server.addr, None).await;
            let huge = "y".repeat(voxless_serve::protocol::MAX_MESSAGE_BYTES + 1);
            let _ = big.send(Message::Text(huge.into())).await;
            while next(&mut big).await.is_some() {}
        }
        let mut fresh = connect(server.addr, None).await;
        send(
            &mut fresh,
            json!({"seq": 1, "type": "hello", "width": 64, "height": 48}),
        )
        .await;
        until_converged(&mut fresh, 1).await;
    });
    assert_eq!(
        status(server.addr, "/frame.png?width=32&height=32", ""),
        200
    );
    assert_eq!(status(server.addr, "/frame.png?width=0&height=32", ""), 400);
    assert_eq!(status(server.addr, "/frame.png?width=abc", ""), 400);
}

#[test]
fn traversal_in_any_spelling_is_404() {
    let s = Scratch::new("traversal");
    let server = serve(particle_scene(&s, 200), "127.0.0.1");
    for path in [
        "/../../../../etc/passwd",
        "/%2e%2e/%2e%2e/%2e%2e/etc/passwd",
        "/..%2f..%2f..%2fetc%2fpasswd",
        "/%2E%2E%2F%2E%2E%2Fetc%2Fpasswd",
        "/..%5c..%5cetc%5cpasswd",
        "/%252e%252e/etc/passwd",
        "//etc/passwd",
        "/etc/passwd",
        "/./../Cargo.toml",
        "/page.html",
        "/src/page.html",
        "/ws/../../etc/passwd",
        "/frame.png/../../etc/passwd",
    ] {
        assert_eq!(status(server.addr, path, ""), 404, "{path}");
    }
    assert_eq!(status(server.addr, "/", ""), 200);
    // A loopback server answers loopback host names only (DNS rebinding).
    let mut s = std::net::TcpStream::connect(server.addr).unwrap();
    use std::io::{Read, Write};
    write!(
        s,
        "GET / HTTP/1.1\r\nHost: attacker.example\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut buf = Vec::new();
    let _ = s.read_to_end(&mut buf);
    assert!(String::from_utf8_lossy(&buf).starts_with("HTTP/1.1 403"));
    // Only the viewer's own page may drive it: `Origin: null` (sandboxed
    // frames) and other ports or hosts are other pages.
    let origin = |o: &str| status(server.addr, "/", &format!("Origin: {o}\r\n"));
    assert_eq!(origin("http://127.0.0.1"), 200);
    for other in [
        "null",
        "http://127.0.0.1:1",
        "http://evil.example",
        "file://",
    ] {
        assert_eq!(origin(other), 403, "{other}");
    }
}

#[test]
fn beyond_loopback_every_request_needs_the_token() {
    let s = Scratch::new("token");
    let server = serve(particle_scene(&s, 200), "0.0.0.0");
    let token = server.token.clone().expect("a token beyond loopback");
    assert!(token.len() >= 32 && server.url.contains(&token));
    let addr = std::net::SocketAddr::from(([127, 0, 0, 1], server.addr.port()));
    for path in ["/", "/frame.png?width=8&height=8", "/ws", "/nope"] {
        assert_eq!(status(addr, path, ""), 401, "{path} without a token");
        let wrong = if path.contains('?') {
            "&token=0000"
        } else {
            "?token=0000"
        };
        assert_eq!(
            status(addr, &format!("{path}{wrong}"), ""),
            403,
            "{path} wrong token"
        );
    }
    assert_eq!(status(addr, &format!("/?token={token}"), ""), 200);
    assert_eq!(
        status(addr, "/", &format!("x-voxless-token: {token}\r\n")),
        200
    );
    runtime().block_on(async {
        let url = format!("ws://{addr}/ws");
        assert!(tokio_tungstenite::connect_async(url).await.is_err());
        let mut ws = connect(addr, Some(&token)).await;
        send(
            &mut ws,
            json!({"seq": 1, "type": "hello", "width": 32, "height": 32}),
        )
        .await;
        until_converged(&mut ws, 1).await;
    });
}

#[test]
fn a_client_that_does_not_read_stalls_no_other() {
    let s = Scratch::new("slow");
    let server = serve(particle_scene(&s, 3000), "127.0.0.1");
    runtime().block_on(async {
        // The slow tab asks for big images and never reads a byte.
        let mut slow = connect(server.addr, None).await;
        send(
            &mut slow,
            json!({"seq": 1, "type": "hello", "width": 1024, "height": 1024}),
        )
        .await;
        send(
            &mut slow,
            json!({"seq": 2, "type": "set", "patch": {"image": {"spp": 1}}}),
        )
        .await;
        for seq in 3..40 {
            send(
                &mut slow,
                json!({"seq": seq, "type": "orbit", "yaw": 5.0, "pitch": 0.0}),
            )
            .await;
        }
        // Another tab gets every view it asks for, converged.
        let mut fast = connect(server.addr, None).await;
        send(
            &mut fast,
            json!({"seq": 1, "type": "hello", "width": 96, "height": 64}),
        )
        .await;
        until_converged(&mut fast, 1).await;
        for seq in 2..6 {
            send(
                &mut fast,
                json!({"seq": seq, "type": "orbit", "yaw": 20.0, "pitch": 5.0}),
            )
            .await;
            until_converged(&mut fast, seq).await;
        }
        drop(slow);
    });
}

#[test]
fn a_tab_colours_by_a_column_of_the_file_and_by_nothing_else() {
    let s = Scratch::new("columns");
    let mut csv = String::from("x,y,z,temp,mass\n");
    let mut rng = voxless::core::SmallRng(9);
    for _ in 0..800 {
        let (x, y, z) = (rng.f(), rng.f(), rng.f());
        csv += &format!("{x},{y},{z},{},{}\n", x * 10.0, 1.0 + y);
    }
    let file = s.0.join("p.csv");
    std::fs::write(&file, csv).unwrap();
    let desc = voxless::SceneDesc {
        particles: Some(voxless::ParticlesDesc {
            file: Some(file.to_string_lossy().into_owned()),
            attribute: Some("temp".into()),
            radius: Some(0.12),
            ..Default::default()
        }),
        ..Default::default()
    };
    let server = serve(desc, "127.0.0.1");
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        send(
            &mut ws,
            json!({"seq": 1, "type": "hello", "width": 48, "height": 32}),
        )
        .await;
        let msgs = until_converged(&mut ws, 1).await;
        let state = msgs
            .iter()
            .find_map(|m| match m {
                Msg::Text(v) if v["type"] == "state" => Some(v.clone()),
                _ => None,
            })
            .expect("a state message");
        // Every column, coordinates included (colouring by height is a view).
        assert_eq!(state["columns"], json!(["x", "y", "z", "temp", "mass"]));
        send(
            &mut ws,
            json!({"seq": 2, "type": "set", "patch": {"particles": {"attribute": "mass"}}}),
        )
        .await;
        until_converged(&mut ws, 2).await;
        let bad = json!({"seq": 3, "type": "set", "patch": {"particles": {"attribute": "p.csv"}}});
        send(&mut ws, bad).await;
        loop {
            if let Some(Msg::Text(v)) = next(&mut ws).await
                && v["type"] == "error"
            {
                assert!(v["message"].as_str().unwrap().contains("column"), "{v}");
                break;
            }
        }
        // A rejected setting does not stick: the next move renders from the
        // view that rendered last, and so after one the renderer refuses.
        send(
            &mut ws,
            json!({"seq": 4, "type": "orbit", "yaw": 10.0, "pitch": 0.0}),
        )
        .await;
        until_converged(&mut ws, 4).await;
        send(
            &mut ws,
            json!({"seq": 5, "type": "set", "patch": {"image": {"spp": 0}}}),
        )
        .await;
        loop {
            if let Some(Msg::Text(v)) = next(&mut ws).await
                && v["type"] == "error"
                && v["seq"] == 5
            {
                break;
            }
        }
        send(
            &mut ws,
            json!({"seq": 6, "type": "orbit", "yaw": 10.0, "pitch": 0.0}),
        )
        .await;
        until_converged(&mut ws, 6).await;
        // A setting wrong whatever the data, with a move right behind it:
        // refused as it arrives, so the move renders the good view and the
        // tab's scene never holds it.
        send(
            &mut ws,
            json!({"seq": 7, "type": "set", "patch": {"image": {"spp": 0}}}),
        )
        .await;
        send(
            &mut ws,
            json!({"seq": 8, "type": "orbit", "yaw": 10.0, "pitch": 0.0}),
        )
        .await;
        until_converged(&mut ws, 8).await;
        send(&mut ws, json!({"seq": 9, "type": "save_scene"})).await;
        loop {
            if let Some(Msg::Text(v)) = next(&mut ws).await
                && v["type"] == "scene"
            {
                let toml = v["toml"].as_str().unwrap();
                assert!(!toml.contains("spp = 0"), "{toml}");
                break;
            }
        }
    });
}

#[test]
fn a_tab_sets_neighbour_radii_in_a_periodic_box() {
    let s = Scratch::new("neighbours");
    let mut csv = String::from("x,y,z\n");
    let mut rng = voxless::core::SmallRng(4);
    for _ in 0..600 {
        csv += &format!("{},{},{}\n", rng.f(), rng.f(), rng.f());
    }
    let file = s.0.join("p.csv");
    std::fs::write(&file, csv).unwrap();
    let desc = voxless::SceneDesc {
        particles: Some(voxless::ParticlesDesc {
            file: Some(file.to_string_lossy().into_owned()),
            periodic_box: Some(voxless::BoxDesc::Side(1.0)),
            ..Default::default()
        }),
        ..Default::default()
    };
    let server = serve(desc, "127.0.0.1");
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        send(
            &mut ws,
            json!({"seq": 1, "type": "hello", "width": 32, "height": 32}),
        )
        .await;
        until_converged(&mut ws, 1).await;
        send(
            &mut ws,
            json!({"seq": 2, "type": "set", "patch": {"particles": {"neighbours": 8}}}),
        )
        .await;
        let msgs = until_converged(&mut ws, 2).await;
        let state = msgs
            .iter()
            .rev()
            .find_map(|m| match m {
                Msg::Text(v) if v["type"] == "state" => Some(v.clone()),
                _ => None,
            })
            .expect("a state message");
        assert_eq!(
            state["scene"]["particles"]["neighbours"],
            json!(8),
            "{state}"
        );
        assert_eq!(state["scene"]["particles"]["box"], json!(1.0), "{state}");
    });
}

/// The CLI's checks hold in the viewer: a view that shows nothing (a value
/// range above the data, a clip box away from it) is an error naming the
/// cause, not a black "converged" image, and the tab goes back to the view
/// that rendered last.
#[test]
fn a_view_that_shows_nothing_is_an_error_not_a_black_image() {
    let s = Scratch::new("black");
    let server = serve(particle_scene(&s, 600), "127.0.0.1");
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        send(
            &mut ws,
            json!({"seq": 1, "type": "hello", "width": 40, "height": 30}),
        )
        .await;
        until_converged(&mut ws, 1).await;
        let cases = [
            json!({"transfer": {"value_range": [1e6, 2e6]}}),
            json!({"render": {"clip": [50.0, 50.0, 50.0, 51.0, 51.0, 51.0]}}),
        ];
        for (k, patch) in cases.into_iter().enumerate() {
            let seq = 2 + 2 * k as u64;
            send(&mut ws, json!({"seq": seq, "type": "set", "patch": patch})).await;
            let m = until_error(&mut ws, seq).await;
            assert!(m.contains("back to the last one"), "{m}");
            // The next move renders from the last good view.
            send(
                &mut ws,
                json!({"seq": seq + 1, "type": "orbit", "yaw": 5.0, "pitch": 0.0}),
            )
            .await;
            until_converged(&mut ws, seq + 1).await;
        }
        // A zero-width value range, an eye a light year away and a zoom
        // of 1e-30: each an error for its own message, never a black
        // "converged" image; the next move renders.
        let cases = [
            json!({"seq": 10, "type": "set", "patch": {"transfer": {"value_range": [0.5, 0.5]}}}),
            json!({"seq": 12, "type": "set", "patch": {"camera": {"eye": [1e30, 0.0, 0.0]}}}),
            json!({"seq": 14, "type": "zoom", "factor": 1e-30}),
        ];
        for msg in cases {
            let seq = msg["seq"].as_u64().unwrap();
            send(&mut ws, msg).await;
            until_error(&mut ws, seq).await;
            send(
                &mut ws,
                json!({"seq": seq + 1, "type": "orbit", "yaw": 5.0, "pitch": 0.0}),
            )
            .await;
            until_converged(&mut ws, seq + 1).await;
        }
    });
}

/// A setting that fails only on the data (a value range above it) with a
/// camera move queued behind it: the error says the view went back to the
/// last good settings, and the move is kept — the next image is that view
/// moved, the same image a fresh tab gets for the same move.
#[test]
fn a_move_queued_behind_a_setting_that_fails_on_the_data_is_kept() {
    let s = Scratch::new("queued");
    let server = serve(particle_scene(&s, 600), "127.0.0.1");
    let orbit = |seq: u64| json!({"seq": seq, "type": "orbit", "yaw": 25.0, "pitch": 10.0});
    let hello = json!({"seq": 1, "type": "hello", "width": 40, "height": 30});
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        send(&mut ws, hello.clone()).await;
        until_converged(&mut ws, 1).await;
        let bad = json!({"transfer": {"value_range": [1e6, 2e6]}});
        send(&mut ws, json!({"seq": 2, "type": "set", "patch": bad})).await;
        send(&mut ws, orbit(3)).await;
        // Usually the move arrives before the setting's render fails (the
        // case this test is for); should the render fail first, the error
        // is the setting's own and the move renders from the good view.
        loop {
            match next(&mut ws).await.expect("socket open") {
                Msg::Text(v) if v["type"] == "error" && v["seq"] == 2 => break,
                Msg::Text(v) if v["type"] == "error" => {
                    assert_eq!(v["seq"], 3, "{v}");
                    let m = v["message"].as_str().unwrap();
                    assert!(m.contains("with the camera moved since"), "{m}");
                    break;
                }
                _ => {}
            }
        }
        let kept = until_converged(&mut ws, 3).await;
        let Some(Msg::Frame(_, kept)) = kept.last() else {
            unreachable!()
        };

        let mut fresh = connect(server.addr, None).await;
        send(&mut fresh, hello).await;
        until_converged(&mut fresh, 1).await;
        send(&mut fresh, orbit(2)).await;
        let moved = until_converged(&mut fresh, 2).await;
        let Some(Msg::Frame(_, moved)) = moved.last() else {
            unreachable!()
        };
        assert!(
            kept == moved,
            "the kept move's image differs from a fresh tab's"
        );

        // A move that fails by itself (a pan far off the data) is not made
        // again: the view is the last good one, and the next move starts
        // from it, as a fresh tab's second move does.
        send(
            &mut ws,
            json!({"seq": 4, "type": "pan", "dx": 40.0, "dy": 0.0}),
        )
        .await;
        let m = until_error(&mut ws, 4).await;
        assert!(!m.contains("moved since"), "{m}");
        send(&mut ws, orbit(5)).await;
        let again = until_converged(&mut ws, 5).await;
        let Some(Msg::Frame(_, again)) = again.last() else {
            unreachable!()
        };
        send(&mut fresh, orbit(3)).await;
        let twice = until_converged(&mut fresh, 3).await;
        let Some(Msg::Frame(_, twice)) = twice.last() else {
            unreachable!()
        };
        assert!(
            again == twice,
            "after a failed move the view is not the last good one"
        );
    });
}
