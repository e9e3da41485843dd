//! `voxless serve` in a real headless browser (Chromium over WebDriver):
//! the page shows the dam-break frame, a drag orbits to a new image, a
//! transfer-function change gives another, and `voxless render` of the
//! scene the page saves draws the page's converged image (≤ 1/255).
//!
//! Needs `chromedriver` (Debian: `chromium-driver`) and `chromium` on PATH
//! and the shared data next to the repository; without them it prints a
//! notice and passes (fails instead when `VOXLESS_REQUIRE_BROWSER` is set,
//! as CI does). `VOXLESS_SCREENSHOT=FILE` also saves a screenshot of the
//! page (the README's).

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::actions::{InputSource, MOUSE_BUTTON_LEFT, MouseActions, PointerAction};
use fantoccini::{Client, ClientBuilder, Locator};
use serde_json::{Value, json};
use voxless_core::testing::{prerequisite, shared_data};

/// Liveness bound of each wait (never a performance assertion).
const PATIENCE: Duration = Duration::from_secs(240);

/// An executable on PATH.
fn on_path(name: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

/// Kills the child when dropped.
struct Kill(Child);
impl Drop for Kill {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Polls `script` (a JS expression) until it is truthy; returns its value.
async fn wait_for(c: &Client, script: &str) -> Value {
    let start = Instant::now();
    loop {
        let v = c
            .execute(&format!("return {script};"), vec![])
            .await
            .unwrap();
        if !(v.is_null() || v == Value::Bool(false)) {
            return v;
        }
        let errors = c
            .execute("return window.voxless ? window.voxless.errors : []", vec![])
            .await
            .unwrap();
        assert!(
            errors.as_array().is_none_or(|e| e.is_empty()),
            "the page reports {errors}"
        );
        assert!(start.elapsed() < PATIENCE, "waited too long for {script}");
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
}

/// Waits for a converged image newer than `after` (an interaction seq) and
/// returns its seq and decoded pixels.
async fn converged_after(c: &Client, after: u64) -> (u64, Vec<u8>) {
    let cond = format!(
        "window.voxless && window.voxless.converged && window.voxless.last.seq > {after} \
         && window.voxless.last"
    );
    let last = wait_for(c, &cond).await;
    let b64 = c
        .execute_async(
            "const done = arguments[arguments.length - 1]; window.voxless.convergedPng().then(done);",
            vec![],
        )
        .await
        .unwrap();
    let bytes = decode_base64(b64.as_str().expect("a converged image"));
    (last["seq"].as_u64().unwrap(), decode_png(&bytes))
}

fn decode_base64(s: &str) -> Vec<u8> {
    let val = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        _ => 63,
    };
    let bytes: Vec<u8> = s.bytes().filter(|&c| c != b'=').map(val).collect();
    bytes
        .chunks(4)
        .flat_map(|q| {
            let n = q.iter().fold(0u32, |a, &v| a << 6 | v as u32) << (6 * (4 - q.len()));
            let b = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
            b.into_iter().take(q.len() - 1)
        })
        .collect()
}

fn decode_png(bytes: &[u8]) -> Vec<u8> {
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    buf
}

/// Fraction of pixels that differ by more than 8/255 in some channel.
fn changed(a: &[u8], b: &[u8]) -> f64 {
    if a.len() != b.len() {
        return 1.0;
    }
    let px = a.len() / 3;
    let n = (0..px)
        .filter(|&i| (0..3).any(|c| a[3 * i + c].abs_diff(b[3 * i + c]) > 8))
        .count();
    n as f64 / px as f64
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_orbits_edits_and_saves_a_scene_the_cli_reproduces() {
    let (driver, chromium) = (
        on_path("chromedriver"),
        on_path("chromium").or_else(|| on_path("chromium-browser")),
    );
    let what = "chromedriver and chromium on PATH";
    let (true, Some(driver), Some(chromium)) = (
        prerequisite(
            driver.is_some() && chromium.is_some(),
            "VOXLESS_REQUIRE_BROWSER",
            what,
        ),
        driver,
        chromium,
    ) else {
        return;
    };
    // An unoptimised server renders the dam break at page size in minutes,
    // not seconds, so the test's patience is meant for release builds.
    if cfg!(debug_assertions) && std::env::var_os("VOXLESS_REQUIRE_BROWSER").is_none() {
        eprintln!(
            "notice: the browser test runs in release builds (cargo test --release); skipping"
        );
        return;
    }
    let Some(data) = shared_data("sph-dam-break/npy_01000") else {
        return;
    };
    let scratch = std::env::temp_dir().join(format!("voxless-browser-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).unwrap();
    let file = |n: &str| data.join(n).to_string_lossy().into_owned();

    // The server, on a free port it prints.
    let mut serve = Kill(
        Command::new(env!("CARGO_BIN_EXE_voxless"))
            .args(["serve", "--particles", &file("positions.npy")])
            .args(["--radii", &file("h.npy"), "--weights", &file("mass.npy")])
            .args([
                "--kernel",
                "cubic-spline",
                "--attribute",
                &file("speed.npy"),
            ])
            .args(["--spp", "2", "--port", "0"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let mut line = String::new();
    BufReader::new(serve.0.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let url = line
        .split_whitespace()
        .find(|w| w.starts_with("http://"))
        .unwrap_or_else(|| panic!("no URL in '{line}'"))
        .to_string();

    let port = free_port();
    let _driver = Kill(
        Command::new(driver)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let caps: serde_json::Map<String, Value> = serde_json::from_value(json!({
        "goog:chromeOptions": {
            "binary": chromium,
            "args": ["--headless=new", "--no-sandbox", "--disable-gpu",
                     "--disable-dev-shm-usage", "--window-size=1200,800"]
        }
    }))
    .unwrap();
    let start = Instant::now();
    let c = loop {
        match ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
            .capabilities(caps.clone())
            .connect(&format!("http://127.0.0.1:{port}"))
            .await
        {
            Ok(c) => break c,
            Err(e) if start.elapsed() < Duration::from_secs(30) => {
                let _ = e;
                tokio::time::sleep(Duration::from_millis(300)).await;
            }
            Err(e) => panic!("chromedriver did not start: {e}"),
        }
    };

    c.goto(&url).await.unwrap();
    c.execute("window.voxless.noDownloads = true;", vec![])
        .await
        .unwrap();
    let (seq0, first) = converged_after(&c, 0).await;

    // Drag across the middle of the view: orbit.
    let drag = MouseActions::new("mouse".into())
        .then(PointerAction::MoveTo {
            duration: None,
            x: 400.0,
            y: 380.0,
        })
        .then(PointerAction::Down {
            button: MOUSE_BUTTON_LEFT,
        })
        .then(PointerAction::MoveBy {
            duration: Some(Duration::from_millis(150)),
            x: 60.0,
            y: 10.0,
        })
        .then(PointerAction::MoveBy {
            duration: Some(Duration::from_millis(150)),
            x: 60.0,
            y: 10.0,
        })
        .then(PointerAction::Up {
            button: MOUSE_BUTTON_LEFT,
        });
    c.perform_actions(drag).await.unwrap();
    let (seq1, orbited) = converged_after(&c, seq0).await;
    let moved = changed(&first, &orbited);
    assert!(moved > 0.01, "orbiting changed {moved:.3} of the image");

    // A transfer-function change: opacity only where the values are high.
    c.find(Locator::Id("opHigh"))
        .await
        .unwrap()
        .click()
        .await
        .unwrap();
    let (_, edited) = converged_after(&c, seq1).await;
    let tf = changed(&orbited, &edited);
    assert!(
        tf > 0.01,
        "the transfer function changed {tf:.3} of the image"
    );

    if let Some(shot) = std::env::var_os("VOXLESS_SCREENSHOT") {
        std::fs::write(shot, c.screenshot().await.unwrap()).unwrap();
    }

    // Save the scene; the CLI renders the same image.
    c.find(Locator::Id("saveScene"))
        .await
        .unwrap()
        .click()
        .await
        .unwrap();
    let toml = wait_for(&c, "window.voxless.scene").await;
    let scene = scratch.join("saved.toml");
    std::fs::write(&scene, toml.as_str().unwrap()).unwrap();
    let out = scratch.join("cli.png");
    let run = Command::new(env!("CARGO_BIN_EXE_voxless"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let cli = decode_png(&std::fs::read(&out).unwrap());
    assert_eq!(cli.len(), edited.len(), "same size");
    let max = cli
        .iter()
        .zip(&edited)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(
        max <= 1,
        "voxless render differs from the page by {max}/255"
    );
    c.close().await.unwrap();
    let _ = std::fs::remove_dir_all(&scratch);
}
