//! Camera paths over the protocol: keyframes recorded from the views a tab
//! shows are saved in its scene file and read back equal; a preview plays
//! the path as coarse images at the path's frames (and a time series'
//! data frames), ends by itself or at the next interaction, and refused
//! requests answer errors without disturbing the tab.

mod support;

use std::time::Instant;

use serde_json::{Value, json};
use support::*;
use voxless::KeyframeDesc;
use voxless::camera_path::CameraPath;

fn runtime() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
}

/// Reads until a text message of `kind` (an `error` first fails, unless
/// that is the kind asked for); returns it.
async fn until_type(ws: &mut Ws, kind: &str) -> Value {
    loop {
        if let Some(Msg::Text(v)) = next(ws).await {
            if v["type"] == kind {
                return v;
            }
            assert!(v["type"] != "error", "waiting for {kind}: {v}");
        }
    }
}

/// The last `state` message among `msgs`.
fn last_state(msgs: &[Msg]) -> Value {
    msgs.iter()
        .rev()
        .find_map(|m| match m {
            Msg::Text(v) if v["type"] == "state" => Some(v.clone()),
            _ => None,
        })
        .expect("a state message")
}

/// Asserts keyframe `k` records the explicit camera `c` (a state's
/// `scene.camera`) at `frame`, perspective with the default 30°.
fn assert_records(k: &Value, c: &Value, frame: f64) {
    assert_eq!(k["frame"], json!(frame), "{k}");
    for key in ["eye", "look_at", "up"] {
        assert!(c[key].is_array(), "the view's camera is explicit: {c}");
        assert_eq!(k[key], c[key], "{key}: keyframe {k} view {c}");
    }
    assert_eq!(k["fov"], json!(30.0), "{k}");
    assert!(k["orthographic"].is_null(), "{k}");
}

#[test]
fn keyframes_recorded_from_the_view_are_saved_and_read_back() {
    let s = Scratch::new("path-save");
    let mut desc = particle_scene(&s, 1500);
    // A starting view turned by `orbit`: recorded with the turn folded in
    // (a path renders with `orbit` on top of it).
    desc.camera.orbit = Some(30.0);
    let server = serve(desc.clone(), "127.0.0.1");
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        send(
            &mut ws,
            json!({"seq": 1, "type": "hello", "width": 96, "height": 64}),
        )
        .await;
        let msgs = until_converged(&mut ws, 1).await;
        // The scene came without keyframes.
        let hello = msgs
            .iter()
            .find_map(|m| match m {
                Msg::Text(v) if v["type"] == "keyframes" => Some(v.clone()),
                _ => None,
            })
            .expect("a keyframes message after hello");
        assert_eq!(hello["keyframes"], json!([]));
        assert_eq!(hello["next_frame"], json!(0.0));

        // The untouched (default) view: recorded as explicit vectors that
        // give the same camera.
        send(&mut ws, json!({"seq": 2, "type": "add_keyframe"})).await;
        let r = until_type(&mut ws, "keyframes").await;
        assert_eq!(r["keyframes"].as_array().unwrap().len(), 1, "{r}");
        assert_eq!(r["next_frame"], json!(24.0));
        let first: KeyframeDesc = serde_json::from_value(r["keyframes"][0].clone()).unwrap();
        assert_eq!(first.frame, Some(0.0));
        assert_default_view(&desc, &first);

        // Moved views: recorded exactly as the tab's camera.
        send(
            &mut ws,
            json!({"seq": 3, "type": "orbit", "yaw": 40.0, "pitch": 10.0}),
        )
        .await;
        let c3 = last_state(&until_converged(&mut ws, 3).await)["scene"]["camera"].clone();
        send(
            &mut ws,
            json!({"seq": 4, "type": "add_keyframe", "frame": 30}),
        )
        .await;
        let r = until_type(&mut ws, "keyframes").await;
        assert_records(&r["keyframes"][1], &c3, 30.0);
        assert_eq!(r["next_frame"], json!(54.0));

        send(&mut ws, json!({"seq": 5, "type": "zoom", "factor": 1.5})).await;
        let c5 = last_state(&until_converged(&mut ws, 5).await)["scene"]["camera"].clone();
        send(&mut ws, json!({"seq": 6, "type": "add_keyframe"})).await;
        let r = until_type(&mut ws, "keyframes").await;
        assert_records(&r["keyframes"][2], &c5, 54.0);
        // Remove the last and record it again at another frame.
        send(
            &mut ws,
            json!({"seq": 7, "type": "keyframes", "op": "remove_last"}),
        )
        .await;
        let r = until_type(&mut ws, "keyframes").await;
        assert_eq!(r["keyframes"].as_array().unwrap().len(), 2, "{r}");
        send(
            &mut ws,
            json!({"seq": 8, "type": "add_keyframe", "frame": 60.5}),
        )
        .await;
        let r = until_type(&mut ws, "keyframes").await;
        assert_records(&r["keyframes"][2], &c5, 60.5);
        let recorded: Vec<KeyframeDesc> = serde_json::from_value(r["keyframes"].clone()).unwrap();

        // Back to the starting view: the keyframes stay, and the saved
        // scene reads back with them and a camera the path is not moved by
        // (no orbit, elevation or zoom on top).
        send(&mut ws, json!({"seq": 9, "type": "reset"})).await;
        until_converged(&mut ws, 9).await;
        send(&mut ws, json!({"seq": 10, "type": "save_scene"})).await;
        let scene = until_type(&mut ws, "scene").await;
        let toml = scene["toml"].as_str().unwrap();
        assert!(toml.contains("[[camera.keyframes]]"), "{toml}");
        let file = s.0.join("saved.toml");
        std::fs::write(&file, toml).unwrap();
        let read = voxless::read_scene(&file).unwrap();
        assert_same_keyframes(read.camera.keyframes.as_deref().unwrap(), &recorded);
        assert_eq!(
            (read.camera.orbit, read.camera.elevation, read.camera.zoom),
            (None, None, None)
        );
        let path = CameraPath::new(&read.camera).unwrap().expect("a path");
        assert_eq!(path.span(), (0.0, 60.5));
        // At a keyframe the path's camera is the recorded view.
        let at = path.apply(&read, 30.0).camera;
        let view = |key: &str| serde_json::from_value::<[f64; 3]>(c3[key].clone()).unwrap();
        assert_close(at.eye.unwrap(), view("eye"));
        assert_close(at.look_at.unwrap(), view("look_at"));

        // Clear: no keyframes, and a saved scene without any.
        send(
            &mut ws,
            json!({"seq": 11, "type": "keyframes", "op": "clear"}),
        )
        .await;
        let r = until_type(&mut ws, "keyframes").await;
        assert_eq!(r["keyframes"], json!([]));
        send(&mut ws, json!({"seq": 12, "type": "save_scene"})).await;
        let scene = until_type(&mut ws, "scene").await;
        assert!(!scene["toml"].as_str().unwrap().contains("keyframes"));
    });
}

/// The test reads JSON numbers to within an ulp (serde_json's default
/// float parsing), TOML ones exactly: equal to a few ulps.
fn assert_close(a: [f64; 3], b: [f64; 3]) {
    for (x, y) in a.into_iter().zip(b) {
        assert!(
            (x - y).abs() <= 4.0 * f64::EPSILON * x.abs().max(y.abs()),
            "{a:?} {b:?}"
        );
    }
}

fn assert_same_keyframes(read: &[KeyframeDesc], recorded: &[KeyframeDesc]) {
    assert_eq!(read.len(), recorded.len());
    for (a, b) in read.iter().zip(recorded) {
        assert_eq!(
            (a.frame, a.up, a.fov, a.orthographic),
            (b.frame, b.up, b.fov, b.orthographic)
        );
        assert_close(a.eye.unwrap(), b.eye.unwrap());
        assert_close(a.look_at.unwrap(), b.look_at.unwrap());
    }
}

/// `k` recorded the default view of `desc` (96×64): the library's camera
/// at the keyframe is the default camera (to float precision).
fn assert_default_view(desc: &voxless::SceneDesc, k: &KeyframeDesc) {
    let base = std::path::Path::new(".");
    let mut desc = desc.clone();
    desc.image.width = Some(96);
    desc.image.height = Some(64);
    let loaded = voxless::load(&desc, base, 0).unwrap();
    let resolve = |d: &voxless::SceneDesc| {
        voxless::resolve_in(&loaded.volume, &loaded.frame, d, base)
            .unwrap()
            .camera
    };
    let default = resolve(&desc);
    let mut with = desc.clone();
    with.camera.orbit = None;
    with.camera.keyframes = Some(vec![
        k.clone(),
        KeyframeDesc {
            frame: Some(k.frame.unwrap() + 1.0),
            ..k.clone()
        },
    ]);
    let path = CameraPath::new(&with.camera).unwrap().unwrap();
    let recorded = resolve(&path.apply(&with, k.frame.unwrap()));
    let scale = (default.eye - loaded.frame.to_local(k.look_at.unwrap())).length();
    assert!(
        (recorded.eye - default.eye).length() <= 1e-5 * scale,
        "{recorded:?} {default:?}"
    );
    for (a, b) in [
        (recorded.forward, default.forward),
        (recorded.up, default.up),
        (recorded.right, default.right),
    ] {
        assert!((a - b).length() <= 1e-5, "{recorded:?} {default:?}");
    }
    assert_eq!(recorded.projection, default.projection);
}

/// Adds keyframes at `frames`, orbiting between them; `seq` is the next
/// sequence number and is advanced.
async fn record_path(ws: &mut Ws, seq: &mut u64, frames: &[f64]) {
    for (i, f) in frames.iter().enumerate() {
        if i > 0 {
            send(
                ws,
                json!({"seq": *seq, "type": "orbit", "yaw": 60.0, "pitch": 5.0}),
            )
            .await;
            until_converged(ws, *seq).await;
            *seq += 1;
        }
        send(ws, json!({"seq": *seq, "type": "add_keyframe", "frame": f})).await;
        until_type(ws, "keyframes").await;
        *seq += 1;
    }
}

/// What a preview sent: its opening message, its images' (path frame,
/// data frame, stage), its end message, and the messages after it up to
/// the view's converged image.
struct Played {
    playing: Value,
    images: Vec<(f64, usize, String)>,
    done: Value,
    after: Vec<Msg>,
}

async fn play(ws: &mut Ws, seq: u64) -> Played {
    send(ws, json!({"seq": seq, "type": "preview_path"})).await;
    let (mut playing, mut images) = (Value::Null, Vec::new());
    let done = loop {
        match next(ws).await.expect("socket open") {
            Msg::Text(v) if v["type"] == "error" => panic!("preview: {v}"),
            Msg::Text(v) if v["type"] == "preview" && v["state"] == "playing" => playing = v,
            Msg::Text(v) if v["type"] == "preview" && v["state"] == "done" => break v,
            Msg::Frame(h, img) => {
                assert_eq!(h.seq, seq);
                assert!(!img.is_empty());
                assert!(h.stage != "converged", "{h:?}");
                let f = h.path_frame.expect("a preview image names its path frame");
                images.push((f, h.data_frame.expect("and its data frame"), h.stage));
            }
            Msg::Text(_) => {}
        }
    };
    assert_eq!(playing["seq"], json!(seq), "opened before its images");
    let after = until_converged(ws, seq).await;
    Played {
        playing,
        images,
        done,
        after,
    }
}

#[test]
fn a_preview_plays_the_path_in_coarse_images_then_the_view() {
    let s = Scratch::new("path-preview");
    let server = serve(particle_scene(&s, 1500), "127.0.0.1");
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        send(
            &mut ws,
            json!({"seq": 1, "type": "hello", "width": 96, "height": 64}),
        )
        .await;
        until_converged(&mut ws, 1).await;
        let mut seq = 2;
        record_path(&mut ws, &mut seq, &[0.0, 24.0]).await;
        // The view before the preview.
        send(&mut ws, json!({"seq": seq, "type": "end_drag"})).await;
        let before = last_state(&until_converged(&mut ws, seq).await);
        seq += 1;

        let start = Instant::now();
        let p = play(&mut ws, seq).await;
        let took = start.elapsed().as_secs_f64();
        assert_eq!(
            (p.playing["first"].as_f64(), p.playing["last"].as_f64()),
            (Some(0.0), Some(24.0))
        );
        assert_eq!(p.playing["frames"], json!(25));
        assert_eq!(p.done["frames"], json!(25));
        // The first and the last frames are always rendered.
        let shown = p.done["shown"].as_u64().unwrap();
        assert!((2..=25).contains(&shown), "{}", p.done);
        assert!(!p.images.is_empty());
        let frames: Vec<f64> = p.images.iter().map(|i| i.0).collect();
        assert!(frames.windows(2).all(|w| w[0] < w[1]), "{frames:?}");
        assert!(
            frames
                .iter()
                .all(|f| (0.0..=24.0).contains(f) && f.fract() == 0.0)
        );
        // Paced at 24 frames per second at most: 24 frame times from the
        // first to the last (a lower bound, not a performance assertion).
        assert!(took >= 0.9, "{took} s");
        // Then the tab's own view, unchanged, refined to convergence.
        let after = last_state(&p.after);
        assert_eq!(after["scene"]["camera"], before["scene"]["camera"]);
        // Images being latest-only, the last preview image may follow the
        // end message, but none follows an image of the view.
        let is_preview = |m: &Msg| matches!(m, Msg::Frame(h, _) if h.path_frame.is_some());
        let is_view = |m: &Msg| matches!(m, Msg::Frame(h, _) if h.path_frame.is_none());
        let first_view = p.after.iter().position(is_view).unwrap();
        assert!(p.after[first_view..].iter().all(|m| !is_preview(m)));
        assert!(p.after.iter().filter(|m| is_preview(m)).count() <= 1);
        seq += 1;

        // A camera move stops a preview: nothing of it follows the move's
        // ack.
        record_path(&mut ws, &mut seq, &[2400.0]).await;
        for stop in [
            json!({"type": "orbit", "yaw": 5.0, "pitch": 0.0}),
            json!({"type": "stop_preview"}),
        ] {
            let preview = seq;
            send(&mut ws, json!({"seq": preview, "type": "preview_path"})).await;
            loop {
                if let Some(Msg::Frame(h, _)) = next(&mut ws).await
                    && h.path_frame.is_some()
                {
                    break;
                }
            }
            let mut stop = stop;
            stop["seq"] = json!(preview + 1);
            send(&mut ws, stop).await;
            let msgs = until_converged(&mut ws, preview + 1).await;
            let ack = msgs
                .iter()
                .position(
                    |m| matches!(m, Msg::Text(v) if v["type"] == "ack" && v["seq"] == preview + 1),
                )
                .expect("an ack");
            for m in &msgs[ack..] {
                match m {
                    Msg::Frame(h, _) => assert!(h.seq > preview && h.path_frame.is_none(), "{h:?}"),
                    Msg::Text(v) => {
                        assert!(v["type"] != "preview", "{v}");
                        assert!(v["seq"].as_u64().unwrap() > preview, "{v}");
                    }
                }
            }
            seq += 2;
        }
    });
}

type DataFrameOf = fn(f64) -> usize;

#[test]
fn a_preview_of_a_time_series_shows_the_data_frame_of_each_path_frame() {
    let s = Scratch::new("path-series");
    let mut rng = voxless::core::SmallRng(3);
    for number in [0, 10, 20] {
        let n = 400;
        let pos: Vec<f32> = (0..3 * n).map(|_| rng.f() + 0.01 * number as f32).collect();
        let file = s.0.join(format!("pos_{number:03}.npy"));
        voxless::io::write_npy_f32(&file, &[n, 3], &pos).unwrap();
    }
    let desc = voxless::SceneDesc {
        particles: Some(voxless::ParticlesDesc {
            file: Some(s.0.join("pos_*.npy").to_string_lossy().into_owned()),
            radius: Some(0.1),
            ..Default::default()
        }),
        ..Default::default()
    };
    let server = serve(desc, "127.0.0.1");
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        send(
            &mut ws,
            json!({"seq": 1, "type": "hello", "width": 64, "height": 48}),
        )
        .await;
        until_converged(&mut ws, 1).await;
        let mut seq = 2;
        record_path(&mut ws, &mut seq, &[0.0, 20.0]).await;
        // hold (the default), then nearest and stretch: the data frame
        // (0, 1, 2 of the files numbered 0, 10, 20) of path frame t.
        let expect: [(&str, DataFrameOf); 3] = [
            ("hold", |t| (t / 10.0).floor() as usize),
            ("nearest", |t| (t / 10.0 - 0.5).ceil().max(0.0) as usize),
            ("stretch", |t| (t / 10.0).round() as usize),
        ];
        for (follow, expected) in expect {
            if follow != "hold" {
                let patch = json!({"camera": {"follow": follow}});
                send(&mut ws, json!({"seq": seq, "type": "set", "patch": patch})).await;
                until_converged(&mut ws, seq).await;
                seq += 1;
            }
            let p = play(&mut ws, seq).await;
            seq += 1;
            assert!(!p.images.is_empty());
            for (t, data, _) in &p.images {
                assert_eq!(*data, expected(*t), "{follow}: path frame {t}");
            }
            // The tab stays at its own data frame.
            assert_eq!(last_state(&p.after)["frame"], json!(0));
        }
    });
}

#[test]
fn refused_keyframes_and_previews_answer_errors_and_change_nothing() {
    let s = Scratch::new("path-errors");
    let server = serve(particle_scene(&s, 500), "127.0.0.1");
    runtime().block_on(async {
        let mut ws = connect(server.addr, None).await;
        send(
            &mut ws,
            json!({"seq": 1, "type": "hello", "width": 48, "height": 32}),
        )
        .await;
        until_converged(&mut ws, 1).await;
        let refused = async |ws: &mut Ws, msg: Value, says: &str| {
            send(ws, msg).await;
            let e = until_type(ws, "error").await;
            let text = e["message"].as_str().unwrap();
            assert!(text.contains(says), "{text}");
        };
        refused(
            &mut ws,
            json!({"seq": 2, "type": "preview_path"}),
            "add two keyframes",
        )
        .await;
        send(
            &mut ws,
            json!({"seq": 3, "type": "add_keyframe", "frame": 24}),
        )
        .await;
        until_type(&mut ws, "keyframes").await;
        refused(
            &mut ws,
            json!({"seq": 4, "type": "preview_path"}),
            "at least two",
        )
        .await;
        for frame in [24.0, 10.0] {
            let msg = json!({"seq": 5, "type": "add_keyframe", "frame": frame});
            refused(&mut ws, msg, "not after the last keyframe").await;
        }
        let msg = json!({"seq": 6, "type": "add_keyframe", "frame": -1});
        refused(&mut ws, msg, "a path frame is a number").await;
        let msg = json!({"seq": 7, "type": "keyframes", "op": "shuffle"});
        refused(&mut ws, msg, "cannot read message").await;
        // Nothing changed: one keyframe, at 24.
        send(&mut ws, json!({"seq": 8, "type": "add_keyframe"})).await;
        let r = until_type(&mut ws, "keyframes").await;
        let frames: Vec<f64> = r["keyframes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|k| k["frame"].as_f64().unwrap())
            .collect();
        assert_eq!(frames, [24.0, 48.0]);
        // Keyframes the library refuses (one perspective, one
        // orthographic, set by a patch) are no path to preview.
        let mut keys = r["keyframes"].clone();
        keys[1]["orthographic"] = json!(2.0);
        let patch = json!({"camera": {"keyframes": keys}});
        send(&mut ws, json!({"seq": 9, "type": "set", "patch": patch})).await;
        until_converged(&mut ws, 9).await;
        refused(
            &mut ws,
            json!({"seq": 10, "type": "preview_path"}),
            "orthographic",
        )
        .await;
        // The tab still renders.
        send(
            &mut ws,
            json!({"seq": 11, "type": "orbit", "yaw": 3.0, "pitch": 0.0}),
        )
        .await;
        until_converged(&mut ws, 11).await;
    });
}
