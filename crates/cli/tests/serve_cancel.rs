//! `voxless serve`: a `/frame.png` whose client leaves stops rendering (its
//! film freed) instead of running to the end, and the server says so.

use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// Waits for a line of the server's stderr containing `what`; `None` after
/// `patience` (the test then fails: nothing here measures speed).
fn line_with(lines: &mpsc::Receiver<String>, what: &str, patience: Duration) -> Option<String> {
    let end = std::time::Instant::now() + patience;
    while let Some(left) = end.checked_duration_since(std::time::Instant::now()) {
        match lines.recv_timeout(left) {
            Ok(l) if l.contains(what) => return Some(l),
            Ok(_) => {}
            Err(_) => return None,
        }
    }
    None
}

#[test]
fn a_dropped_frame_png_request_stops_its_render() {
    let dir = std::env::temp_dir().join(format!("voxless-serve-cancel-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // 200k particles: a 4096² image at 64 samples a pixel takes minutes on
    // two cores, so a render that ran to the end would not say "stopped".
    let mut rng = voxless::core::SmallRng(3);
    let pos: Vec<f32> = (0..3 * 200_000).map(|_| rng.f()).collect();
    let file = dir.join("p.npy");
    voxless::io::write_npy_f32(&file, &[200_000, 3], &pos).unwrap();
    let mut server = Command::new(env!("CARGO_BIN_EXE_voxless"))
        .args(["serve", "--particles"])
        .arg(&file)
        .args(["--port", "0", "--spp", "64"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (tx, lines) = mpsc::channel();
    for stream in [
        Box::new(server.stdout.take().unwrap()) as Box<dyn std::io::Read + Send>,
        Box::new(server.stderr.take().unwrap()),
    ] {
        let tx = tx.clone();
        std::thread::spawn(move || {
            for l in BufReader::new(stream).lines().map_while(Result::ok) {
                let _ = tx.send(l);
            }
        });
    }
    let patience = Duration::from_secs(120);
    let url = line_with(&lines, "http://127.0.0.1:", patience).expect("the server's address");
    let port: u16 = url
        .split("http://127.0.0.1:")
        .nth(1)
        .and_then(|r| r.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|p| p.parse().ok())
        .expect("a port");
    {
        let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
        write!(
            s,
            "GET /frame.png?width=4096&height=4096 HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
        )
        .unwrap();
        // Long enough for the render to start; then the client leaves.
        std::thread::sleep(Duration::from_millis(1500));
    }
    let stopped = line_with(&lines, "render stopped: its client left", patience);
    let _ = server.kill();
    let _ = server.wait();
    let _ = std::fs::remove_dir_all(&dir);
    let line = stopped.expect("the dropped render stopped");
    assert!(line.contains("4096×4096"), "{line}");
}
