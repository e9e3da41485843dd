//! One browser tab: its view (a scene description), the reader that turns
//! the page's messages into views, and the render worker that turns views
//! into images.
//!
//! Model: the tab's state *is* a [`SceneDesc`] plus a frame number — the
//! camera as explicit vectors once the user moved it, the transfer function,
//! render and light settings — so "save scene" is that description, and
//! `voxless render` of it draws what the tab shows. The reader applies each
//! message to the description at once (cheap: no data is touched), records
//! the interaction in the [`Outbox`] and hands the worker a job; the worker
//! loads (or shares) the volume, resolves the description exactly as the CLI
//! does and renders progressively. A new job cancels the running one
//! between tiles, and only the newest pending job runs next, so a burst of
//! mouse moves costs one render, not one per move. Keyframe edits change
//! the description only; a path preview is a job that plays the path
//! before rendering the view (`path`).

use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

use axum::extract::ws::{Message, WebSocket};
use futures_util::{SinkExt, StreamExt};
use serde_json::json;
use voxless::{Aabb, CancelToken, SceneDesc, WorldFrame};

use crate::app::App;
use crate::outbox::{Outbox, Outgoing, Slot};
use crate::patch;
use crate::path;
use crate::protocol::{Action, ClientMessage, MAX_VIEW_SIDE};
use crate::render::{self, Job};

/// A ParaView preset the page imported: its name and the control points it
/// becomes in the scene (sRGB colours sampled from the preset, and its
/// opacity points when it has them).
#[derive(Clone, Debug)]
pub struct ImportedPreset {
    pub name: String,
    pub colormap_points: Vec<[f32; 4]>,
    pub opacity_points: Option<Vec<[f32; 2]>>,
}

/// What the reader and the worker share about the tab.
pub struct Tab {
    pub desc: SceneDesc,
    pub frame: usize,
    /// Bounds of the volume rendered last and its world frame (camera moves
    /// turn about them).
    pub bounds: Aabb,
    pub world: WorldFrame,
    /// The value and attribute ranges resolved last (kept fixed when the
    /// frame of a time series changes, as the CLI does).
    pub value_range: Option<[f32; 2]>,
    pub attribute_range: Option<[f32; 2]>,
    pub imported: Vec<ImportedPreset>,
    /// The view that resolved last: a setting that fails to load or
    /// resolve goes back to it, so one bad patch does not stick to every
    /// later interaction.
    pub last_good: Option<(SceneDesc, usize)>,
    /// The interaction `last_good` rendered for.
    pub last_good_seq: u64,
    /// The interaction that changed a setting last.
    pub set_seq: u64,
    /// Camera moves (with their interactions) since the last setting
    /// changed: when that setting fails on the data, the view goes back to
    /// `last_good` with the moves made after it, so a move queued behind a
    /// bad setting is kept.
    pub moves_since_set: Vec<(u64, Action)>,
}

/// The pending job and the cancel token of the running one.
#[derive(Default)]
struct Pending {
    job: Option<Job>,
    cancel: CancelToken,
    shutdown: bool,
}

/// The render worker's mailbox: only the newest job waits.
#[derive(Default)]
pub struct Worker {
    pending: Mutex<Pending>,
    wake: Condvar,
}

impl Worker {
    fn lock(&self) -> std::sync::MutexGuard<'_, Pending> {
        self.pending.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Replaces the pending job and cancels the running one.
    fn submit(&self, job: Job) {
        let mut p = self.lock();
        p.cancel.cancel();
        p.cancel = CancelToken::new();
        p.job = Some(job);
        drop(p);
        self.wake.notify_one();
    }

    fn shutdown(&self) {
        let mut p = self.lock();
        p.shutdown = true;
        p.cancel.cancel();
        drop(p);
        self.wake.notify_one();
    }

    /// Waits for the next job; `None` at shutdown.
    fn take(&self) -> Option<(Job, CancelToken)> {
        let mut p = self.lock();
        loop {
            if p.shutdown {
                return None;
            }
            if let Some(job) = p.job.take() {
                return Some((job, p.cancel.clone()));
            }
            p = self.wake.wait(p).unwrap_or_else(|e| e.into_inner());
        }
    }
}

/// Serves one websocket until it closes.
pub async fn run(socket: WebSocket, app: Arc<App>) {
    let (mut sink, mut stream) = socket.split();
    let outbox = Arc::new(Outbox::new());
    let tab = Arc::new(Mutex::new(Tab {
        desc: app.initial.clone(),
        frame: 0,
        bounds: app.initial_bounds,
        world: app.initial_frame,
        value_range: None,
        attribute_range: None,
        imported: Vec::new(),
        last_good: None,
        last_good_seq: 0,
        set_seq: 0,
        moves_since_set: Vec::new(),
    }));
    let worker = Arc::new(Worker::default());

    // The writer: one message at a time from the outbox, so a slow client
    // only ever delays itself.
    let writer = {
        let outbox = outbox.clone();
        tokio::spawn(async move {
            while let Some(m) = outbox.next().await {
                let msg = match m {
                    Outgoing::Text(t) => Message::Text(t.into()),
                    Outgoing::Binary(b) => Message::Binary(b.into()),
                };
                if sink.send(msg).await.is_err() {
                    break;
                }
            }
            outbox.close();
            let _ = sink.close().await;
        })
    };

    // The render worker: a thread of its own (renders block; rayon runs
    // their tiles), so the async runtime only ever moves messages.
    let render_thread = {
        let (app, outbox, tab, worker) = (app.clone(), outbox.clone(), tab.clone(), worker.clone());
        std::thread::Builder::new()
            .name("voxless-serve-render".into())
            .spawn(move || render::worker_loop(&app, &outbox, &tab, &mut || worker.take()))
    };

    while let Some(Ok(msg)) = stream.next().await {
        if outbox.is_closed() {
            break;
        }
        match msg {
            Message::Text(text) => handle_text(&app, &outbox, &tab, &worker, text.as_str()),
            Message::Binary(_) => error(&outbox, "binary messages are not understood"),
            Message::Close(_) => break,
            Message::Ping(_) | Message::Pong(_) => {}
        }
    }
    outbox.close();
    worker.shutdown();
    let _ = writer.await;
    if let Ok(handle) = render_thread {
        let _ = tokio::task::spawn_blocking(move || handle.join()).await;
    }
}

/// An error for the page, tagged with the latest interaction so it is shown.
fn error(outbox: &Outbox, message: &str) {
    let seq = outbox.latest();
    let text = json!({"type": "error", "seq": seq, "message": message}).to_string();
    outbox.offer(Slot::Error, seq, Outgoing::Text(text));
}

/// An error answering message `seq` that changed nothing (not an
/// interaction): shown by the page like any other.
fn refuse(outbox: &Outbox, seq: u64, message: &str) {
    let seq = seq.max(outbox.latest());
    let text = json!({"type": "error", "seq": seq, "message": message}).to_string();
    outbox.offer(Slot::Error, seq, Outgoing::Text(text));
}

/// Width / height of the view `desc` asks for.
pub fn aspect(desc: &SceneDesc) -> f32 {
    let w = desc.image.width.unwrap_or(800).max(1) as f32;
    let h = desc.image.height.unwrap_or(600).max(1) as f32;
    w / h
}

fn lock(tab: &Mutex<Tab>) -> std::sync::MutexGuard<'_, Tab> {
    tab.lock().unwrap_or_else(|e| e.into_inner())
}

/// One text message: parse, apply to the tab's view, queue a render.
fn handle_text(app: &App, outbox: &Outbox, tab: &Mutex<Tab>, worker: &Worker, text: &str) {
    let received = Instant::now();
    let msg: ClientMessage = match serde_json::from_str(text) {
        Ok(m) => m,
        Err(e) => {
            let shown: String = text.chars().take(60).collect();
            return error(outbox, &format!("cannot read message '{shown}…': {e}"));
        }
    };
    let seq = msg.seq;
    // Answers that change no image do not count as interactions: they must
    // not drop the images of the view on screen.
    match &msg.action {
        Action::SaveScene => {
            let t = lock(tab);
            let desc = voxless::with_absolute_paths(&t.desc, &app.base);
            drop(t);
            let reply = match voxless::scene_toml(&desc) {
                Ok(toml) => json!({"type": "scene", "seq": seq, "toml": toml}),
                Err(e) => json!({"type": "error", "seq": seq, "message": e.to_string()}),
            };
            outbox.offer(
                Slot::Scene,
                seq.max(outbox.latest()),
                Outgoing::Text(reply.to_string()),
            );
            return;
        }
        Action::ColormapImport { json } => {
            let reply = match patch::import_presets(json) {
                Ok(presets) => {
                    let names: Vec<String> = presets.iter().map(|p| p.name.clone()).collect();
                    let mut t = lock(tab);
                    t.imported.retain(|p| !names.contains(&p.name));
                    t.imported.extend(presets);
                    json!({"type": "imported", "seq": seq, "names": names})
                }
                Err(e) => json!({"type": "error", "seq": seq, "message": e}),
            };
            outbox.offer(
                Slot::Scene,
                seq.max(outbox.latest()),
                Outgoing::Text(reply.to_string()),
            );
            return;
        }
        Action::AddKeyframe { .. } | Action::Keyframes { .. } => {
            let mut t = lock(tab);
            let reply = match path::edit(&mut t, &msg.action) {
                Ok(()) => path::keyframes_message(seq, &t.desc),
                Err(e) => {
                    drop(t);
                    return refuse(outbox, seq, &e);
                }
            };
            drop(t);
            outbox.offer(
                Slot::Keyframes,
                seq.max(outbox.latest()),
                Outgoing::Text(reply.to_string()),
            );
            return;
        }
        _ => {}
    }
    // A preview that cannot play is refused before it stops the view's
    // render.
    let preview = match &msg.action {
        Action::PreviewPath => match path::plan(app, &lock(tab)) {
            Ok(plan) => Some(Arc::new(plan)),
            Err(e) => return refuse(outbox, seq, &e),
        },
        _ => None,
    };
    let ack = json!({"type": "ack", "seq": seq}).to_string();
    if !outbox.interaction(seq, Outgoing::Text(ack)) {
        return error(
            outbox,
            &format!("message seq {seq} is not newer than the last one; ignored"),
        );
    }
    let mut t = lock(tab);
    let before = (t.desc.clone(), t.frame);
    if let Err(e) = apply(app, &mut t, &msg.action) {
        (t.desc, t.frame) = before;
        drop(t);
        return error(outbox, &e);
    }
    match &msg.action {
        Action::Set { .. } => {
            t.moves_since_set.clear();
            t.set_seq = seq;
        }
        a @ (Action::Orbit { .. } | Action::Pan { .. } | Action::Zoom { .. } | Action::Reset) => {
            t.moves_since_set.push((seq, a.clone()))
        }
        _ => {}
    }
    if matches!(msg.action, Action::Hello { .. }) {
        // The keyframes the scene came with.
        let list = path::keyframes_message(seq, &t.desc).to_string();
        outbox.offer(Slot::Keyframes, seq, Outgoing::Text(list));
    }
    if let Some(plan) = &preview {
        let playing = plan.message(seq, "playing", None).to_string();
        outbox.offer(Slot::Preview, seq, Outgoing::Text(playing));
    }
    let job = Job {
        seq,
        desc: t.desc.clone(),
        frame: t.frame,
        coarse: !matches!(msg.action, Action::EndDrag),
        drag: msg.action.dragging(),
        received,
        path: preview,
    };
    drop(t);
    app.set_current(&job.desc, job.frame);
    worker.submit(job);
}

/// Applies one action to the tab's view.
pub fn apply(app: &App, t: &mut Tab, action: &Action) -> Result<(), String> {
    let aspect = aspect(&t.desc);
    let (bounds, world) = (t.bounds, t.world);
    let view = (&bounds, aspect, &world);
    let cam = &mut t.desc.camera;
    match action {
        Action::Hello { width, height } | Action::Resize { width, height } => {
            let side = |v: u32| v.clamp(1, MAX_VIEW_SIDE);
            t.desc.image.width = Some(side(*width));
            t.desc.image.height = Some(side(*height));
        }
        Action::Orbit { yaw, pitch, .. } => {
            voxless::pose::orbit_camera(cam, view, *yaw, *pitch).map_err(|e| e.to_string())?;
        }
        Action::Pan { dx, dy, .. } => {
            voxless::pose::pan_camera(cam, view, *dx, *dy).map_err(|e| e.to_string())?;
        }
        Action::Zoom { factor, .. } => {
            voxless::pose::zoom_camera(cam, view, *factor).map_err(|e| e.to_string())?;
        }
        Action::EndDrag => {}
        Action::Reset => path::reset_camera(&app.initial.camera, t)?,
        Action::Set { patch } => {
            let desc = patch::apply_patch(app, &t.desc, &t.imported, patch)?;
            // Settings wrong whatever the data are refused here, so they
            // never become the view (nor a job queued behind it); what
            // depends on the data is found by the worker, which goes back
            // to the last view that rendered.
            voxless::check_settings(&desc).map_err(|e| e.to_string())?;
            t.desc = desc;
        }
        Action::Frame { frame } => {
            if *frame >= app.frames {
                return Err(format!(
                    "frame {frame} does not exist: the data has {} frame(s)",
                    app.frames
                ));
            }
            // Ranges stay as resolved for the first frame shown, so the
            // sequence does not flicker (as `voxless render --frames`).
            if t.desc.transfer.value_range.is_none() {
                t.desc.transfer.value_range = t.value_range;
            }
            if let (Some(p), Some(r)) = (&mut t.desc.particles, t.attribute_range) {
                p.attribute_range.get_or_insert(r);
            }
            t.frame = *frame;
        }
        // A preview plays on the worker; stopping one renders the view.
        Action::PreviewPath | Action::StopPreview => {}
        Action::SaveScene
        | Action::ColormapImport { .. }
        | Action::AddKeyframe { .. }
        | Action::Keyframes { .. } => {}
    }
    Ok(())
}
