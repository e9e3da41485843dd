//! Shared by the protocol tests: a small particle scene on disk, a server
//! on a free port, a websocket client and raw HTTP requests.
#![allow(dead_code)]

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::PathBuf;
use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use serde_json::Value;
use tokio_tungstenite::tungstenite::Message;
use voxless::{ParticlesDesc, SceneDesc};
use voxless_serve::{FrameHeader, Options, Running, unpack_frame};

/// Liveness bound of every wait (a hang fails the test instead of blocking
/// CI; never a performance assertion).
pub const PATIENCE: Duration = Duration::from_secs(120);

pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("voxless-serve-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A few thousand particles in a slab, with an attribute, as .npy files.
pub fn particle_scene(s: &Scratch, n: usize) -> SceneDesc {
    let mut rng = voxless::core::SmallRng(5);
    let mut pos = Vec::with_capacity(3 * n);
    let mut attr = Vec::with_capacity(n);
    for _ in 0..n {
        let p = [rng.f(), 0.5 * rng.f(), 0.8 * rng.f()];
        pos.extend(p);
        attr.push(p[0] + p[1]);
    }
    let (pp, ap) = (s.0.join("pos.npy"), s.0.join("attr.npy"));
    voxless::io::write_npy_f32(&pp, &[n, 3], &pos).unwrap();
    voxless::io::write_npy_f32(&ap, &[n], &attr).unwrap();
    SceneDesc {
        particles: Some(ParticlesDesc {
            file: Some(pp.to_string_lossy().into_owned()),
            attribute: Some(ap.to_string_lossy().into_owned()),
            radius: Some(0.08),
            ..Default::default()
        }),
        ..Default::default()
    }
}

/// Serves `desc` on a free loopback port (or `host`).
pub fn serve(desc: SceneDesc, host: &str) -> Running {
    let prepared = voxless_serve::prepare(desc, PathBuf::from(".")).unwrap();
    Running::start(
        prepared,
        &Options {
            host: host.into(),
            port: 0,
            token: None,
            ..Default::default()
        },
    )
    .unwrap()
}

pub type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// A message from the server.
#[derive(Debug)]
pub enum Msg {
    Text(Value),
    Frame(FrameHeader, Vec<u8>),
}

pub async fn connect(addr: SocketAddr, token: Option<&str>) -> Ws {
    let url = match token {
        Some(t) => format!("ws://{addr}/ws?token={t}"),
        None => format!("ws://{addr}/ws"),
    };
    tokio_tungstenite::connect_async(url).await.unwrap().0
}

pub async fn send(ws: &mut Ws, v: Value) {
    ws.send(Message::Text(v.to_string().into())).await.unwrap();
}

/// The next message; `None` when the socket closed.
pub async fn next(ws: &mut Ws) -> Option<Msg> {
    loop {
        let m = tokio::time::timeout(PATIENCE, ws.next())
            .await
            .expect("the server answers")?;
        match m.ok()? {
            Message::Text(t) => return Some(Msg::Text(serde_json::from_str(&t).unwrap())),
            Message::Binary(b) => {
                let (h, img) = unpack_frame(&b).expect("a frame");
                return Some(Msg::Frame(h, img.to_vec()));
            }
            Message::Close(_) => return None,
            _ => {}
        }
    }
}

/// Messages until a converged frame for `seq` (all of them, in order).
pub async fn until_converged(ws: &mut Ws, seq: u64) -> Vec<Msg> {
    let mut out = Vec::new();
    loop {
        let m = next(ws).await.expect("socket open");
        if let Msg::Text(v) = &m
            && v["type"] == "error"
            && v["seq"] == seq
        {
            panic!("error for seq {seq}: {v}");
        }
        let done = matches!(&m, Msg::Frame(h, _) if h.seq == seq && h.stage == "converged");
        out.push(m);
        if done {
            return out;
        }
    }
}

/// Messages until the error for `seq`, whose text it returns; a converged
/// image for `seq` before it fails the test (an error, not a black image).
pub async fn until_error(ws: &mut Ws, seq: u64) -> String {
    loop {
        match next(ws).await.expect("socket open") {
            Msg::Text(v) if v["type"] == "error" && v["seq"] == seq => {
                return v["message"].as_str().unwrap_or_default().to_string();
            }
            Msg::Frame(h, _) => assert!(
                h.seq != seq || h.stage != "converged",
                "a converged image for {seq}, which should be an error"
            ),
            _ => {}
        }
    }
}

/// Status code of `GET path` sent as is (no normalisation), with `extra`
/// header lines.
pub fn status(addr: SocketAddr, path: &str, extra: &str) -> u16 {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(PATIENCE)).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n{extra}Connection: close\r\n\r\n"
    )
    .unwrap();
    let mut buf = Vec::new();
    let _ = s.read_to_end(&mut buf);
    String::from_utf8_lossy(&buf[..buf.len().min(64)])
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0)
}
