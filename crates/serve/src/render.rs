//! The render worker of a tab, and the converged render behind
//! `/frame.png`.
//!
//! A job is one view (description + frame) for one interaction `seq`. The
//! worker loads or shares the volume, resolves the description (the same
//! defaults as the CLI), then renders progressively: a coarse JPEG first
//! (its pixel count adapted to the measured speed, see
//! [`voxless::CoarseBudget`]), then each full-resolution pass (JPEG) and
//! the converged image as PNG. While the user drags, only the coarse image
//! is made. Every image is offered to the outbox with the job's `seq`, so
//! none is sent once a newer interaction arrived; the worker also stops as
//! soon as it sees one. A job with a camera path plays its preview first
//! (`path`), coarse images only, then renders its view.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use serde_json::json;
use voxless::histogram::Histogram;
use voxless::{
    AnyVolume, CancelToken, CoarseBudget, Control, Film, RenderSettings, Resolved, SceneDesc, Stage,
};

use crate::app::{App, Loaded};
use crate::encode;
use crate::outbox::{Outbox, Outgoing, Slot};
use crate::path;
use crate::protocol::{FrameHeader, pack_frame};
use crate::session::Tab;

/// Target time of a coarse image, seconds (the first-image latency goal is
/// 100 ms; encoding and transfer take the rest).
const COARSE_TARGET_SECS: f64 = 0.06;
/// Histogram lattice (samples per axis) and bins.
const HIST_SAMPLES: usize = 40;
const HIST_BINS: usize = 128;
/// Minimum milliseconds between progress messages.
const PROGRESS_EVERY_MS: u64 = 50;

/// One view to render for one interaction.
#[derive(Clone, Debug)]
pub struct Job {
    pub seq: u64,
    pub desc: SceneDesc,
    pub frame: usize,
    /// Render the coarse image first.
    pub coarse: bool,
    /// The user is dragging: the coarse image only.
    pub drag: bool,
    /// When the interaction arrived (for the frames' latency).
    pub received: Instant,
    /// A camera path to preview before rendering the view.
    pub path: Option<Arc<path::Plan>>,
}

/// What the worker remembers between jobs.
struct Memory {
    budget: CoarseBudget,
    /// What the last histogram was computed for.
    histogram_key: Option<String>,
    histogram: Option<Histogram>,
}

/// Runs jobs from `next` until it returns `None`.
pub fn worker_loop(
    app: &App,
    outbox: &Outbox,
    tab: &Mutex<Tab>,
    next: &mut dyn FnMut() -> Option<(Job, CancelToken)>,
) {
    let mut memory = Memory {
        budget: CoarseBudget::new(COARSE_TARGET_SECS, 64 * 64),
        histogram_key: None,
        histogram: None,
    };
    while let Some((job, cancel)) = next() {
        if !outbox.is_current(job.seq) {
            continue;
        }
        let _busy = app.busy();
        let job = match &job.path {
            Some(plan) => {
                if !path::play(app, outbox, &job, plan, &cancel, &mut memory.budget) {
                    continue;
                }
                // The preview ended by itself: the view, as if just asked for.
                Job {
                    received: Instant::now(),
                    path: None,
                    ..job.clone()
                }
            }
            None => job,
        };
        let mut job = job;
        // A setting that failed on the data may leave a view to render:
        // the last good settings with the camera moved since.
        while let Some(next) = run_job(app, outbox, tab, &job, &cancel, &mut memory) {
            if !outbox.is_current(next.seq) || cancel.is_cancelled() {
                break;
            }
            job = next;
        }
    }
}

fn taken(slot: Mutex<Option<Job>>) -> Option<Job> {
    slot.into_inner().unwrap_or_else(|e| e.into_inner())
}

fn text(v: serde_json::Value) -> Outgoing {
    Outgoing::Text(v.to_string())
}

fn run_job(
    app: &App,
    outbox: &Outbox,
    tab: &Mutex<Tab>,
    job: &Job,
    cancel: &CancelToken,
    memory: &mut Memory,
) -> Option<Job> {
    let seq = job.seq;
    // What to render after a failure: the last good view with the camera
    // moves made since the failing setting (rendered once; if it fails
    // too, the view stays the last good one).
    let follow_up: Mutex<Option<Job>> = Mutex::new(None);
    let fail = |message: String| {
        // Back to the view that rendered last (unless the page moved on):
        // the next interaction starts from it, not from the failed setting.
        let mut t = tab.lock().unwrap_or_else(|e| e.into_inner());
        let mut message = message;
        if t.desc == job.desc
            && t.frame == job.frame
            && let Some((desc, frame)) = t.last_good.clone()
        {
            (t.desc, t.frame) = (desc.clone(), frame);
            // Moves made after the last good view are made again when a
            // setting changed after it too (else the moves themselves
            // failed); moves before a setting are cleared with it.
            let after = t.last_good_seq;
            let setting_failed = t.set_seq > after;
            let moves: Vec<crate::protocol::Action> = std::mem::take(&mut t.moves_since_set)
                .into_iter()
                .filter(|m| setting_failed && m.0 > after)
                .map(|m| m.1)
                .collect();
            let replayed = !moves.is_empty()
                && moves
                    .iter()
                    .all(|m| crate::session::apply(app, &mut t, m).is_ok());
            if replayed {
                message.push_str(
                    " (the view is back to the last settings that rendered, with the camera \
                     moved since)",
                );
                *follow_up.lock().unwrap_or_else(|e| e.into_inner()) = Some(Job {
                    desc: t.desc.clone(),
                    frame: t.frame,
                    received: Instant::now(),
                    ..job.clone()
                });
            } else {
                (t.desc, t.frame) = (desc, frame);
                message.push_str(" (the view is back to the last one that rendered)");
            }
            app.set_current(&t.desc, t.frame);
        }
        drop(t);
        outbox.offer(
            Slot::Error,
            seq,
            text(json!({"type": "error", "seq": seq, "message": message})),
        );
    };
    if !app.volumes.contains(&job.desc, job.frame) {
        outbox.offer(
            Slot::Progress,
            seq,
            text(
                json!({"type": "progress", "seq": seq, "stage": "loading", "done": 0, "total": 1}),
            ),
        );
    }
    let loaded = match app.volumes.get(&job.desc, &app.base, job.frame) {
        Ok(l) => l,
        Err(e) => {
            fail(e);
            return taken(follow_up);
        }
    };
    if !outbox.is_current(seq) {
        return None;
    }
    let resolved = match loaded.resolve(&job.desc, &app.base) {
        Ok(r) => r,
        Err(e) => {
            fail(e.to_string());
            return taken(follow_up);
        }
    };
    // The CLI's refusal of absurd work (a step far below the data's
    // scale, a sampling rate of 10⁹), before anything renders.
    if let Err(e) = resolved.check_work(&loaded.volume, &loaded.frame, &job.desc) {
        fail(e.to_string());
        return taken(follow_up);
    }
    let previous_good = {
        let mut t = tab.lock().unwrap_or_else(|e| e.into_inner());
        let previous = (t.last_good.clone(), t.last_good_seq);
        t.last_good = Some((job.desc.clone(), job.frame));
        t.last_good_seq = job.seq;
        // Moves before the previous good view can never be made again
        // (the image check may still restore that one): a tab that only
        // moves keeps a short list.
        let before = previous.1;
        t.moves_since_set.retain(|m| m.0 > before);
        // What the default camera framed (the part of the data the
        // transfer function shows), so camera moves start from that view.
        t.bounds = resolved.framed;
        t.world = loaded.frame;
        let vr = resolved.settings.value_range;
        t.value_range = Some([vr.lo, vr.hi]);
        t.attribute_range = resolved.settings.attribute_range.map(|r| [r.lo, r.hi]);
        previous
    };

    let last_progress = AtomicU64::new(0);
    let stage_name = Mutex::new("coarse");
    let progress = |done: u64, total: u64| {
        // Throttled: a message per tile would only fill the socket.
        let now = job.received.elapsed().as_millis() as u64;
        let last = last_progress.load(Ordering::Relaxed);
        if done < total && now < last + PROGRESS_EVERY_MS {
            return;
        }
        last_progress.store(now, Ordering::Relaxed);
        let stage = *stage_name.lock().unwrap_or_else(|e| e.into_inner());
        outbox.offer(
            Slot::Progress,
            seq,
            text(json!({"type": "progress", "seq": seq, "stage": stage, "done": done, "total": total})),
        );
    };
    let control = Control::new()
        .with_cancel(cancel.clone())
        .with_progress(&progress);
    let settings = &resolved.settings;
    let full = settings.width as u64 * settings.height as u64;
    let coarse = job.coarse.then(|| memory.budget.pixels(full));
    let mut state_sent = false;
    let mut send_state = |memory: &mut Memory| {
        if !state_sent {
            state_sent = true;
            let msg = state_message(app, job, &loaded, &resolved, memory, tab);
            outbox.offer(Slot::State, seq, text(msg));
        }
    };
    // A periodic box is drawn as an outline over the image.
    let outline = match &loaded.volume {
        voxless::AnyVolume::Particles(v) => v.periodic(),
        _ => None,
    };
    let outline = outline.map(|b| (resolved.camera, b));
    let mut budget = memory.budget.clone();
    let mut failed = false;
    let mut device_notes = Vec::new();
    let result = voxless::render_progressive_on(
        &app.device,
        &loaded.volume,
        (&resolved.camera, &resolved.tf, settings),
        (coarse, Some(&mut budget)),
        &control,
        &mut device_notes,
        &mut |stage, film, at| {
            *stage_name.lock().unwrap_or_else(|e| e.into_inner()) = "full";
            let converged = stage.is_converged();
            // The CLI's checks of a finished image, before it is sent:
            // iso-surfaces asked for but absent, or nothing visible at all
            // (a value range above the data, a camera or clip box away from
            // it) — an error, not a black "converged" image; the tab goes
            // back to the view that rendered before.
            if converged {
                let bounds = loaded.frame.box_to_world(loaded.volume.bounds());
                let image = film.resolve();
                if let Err(e) = resolved.check_image(bounds, film.stats(), &image) {
                    {
                        let mut t = tab.lock().unwrap_or_else(|e| e.into_inner());
                        if t.last_good.as_ref() == Some(&(job.desc.clone(), job.frame)) {
                            (t.last_good, t.last_good_seq) = previous_good.clone();
                        }
                    }
                    failed = true;
                    fail(e.to_string());
                    return false;
                }
            }
            let bg = resolved.background;
            if !send_frame(outbox, job, (stage, film, at), outline, bg, converged, None) {
                return false;
            }
            // The controls follow the first image.
            send_state(memory);
            !job.drag && outbox.is_current(seq)
        },
    );
    memory.budget = budget;
    // Where `--device auto` put the CPU in, said once in the terminal.
    for n in device_notes {
        static SAID: Mutex<Vec<String>> = Mutex::new(Vec::new());
        let mut said = SAID.lock().unwrap_or_else(|e| e.into_inner());
        if !said.contains(&n) {
            eprintln!("note: {n}");
            said.push(n);
        }
    }
    // A device that fails (or a render `--device gpu` cannot do) fails the
    // view as any error does.
    let result = match result {
        Ok(r) => r,
        Err(e) => {
            fail(e.to_string());
            return taken(follow_up);
        }
    };
    if result.is_ok() && !failed && outbox.is_current(seq) {
        send_state(memory);
        if !job.drag {
            send_histogram(outbox, job, &loaded, settings, memory);
        }
    }
    taken(follow_up)
}

/// One coarse image of `job`'s view (a frame of a path preview: path
/// frame `path_frame`, data frame `job.frame`), with no state, histogram or
/// refinement. Ok(false) when it was stopped or is no longer wanted; Err
/// when the view cannot be rendered.
pub fn coarse_image(
    app: &App,
    outbox: &Outbox,
    job: &Job,
    cancel: &CancelToken,
    budget: &mut CoarseBudget,
    path_frame: f64,
) -> Result<bool, String> {
    let seq = job.seq;
    if !app.volumes.contains(&job.desc, job.frame) {
        let msg =
            json!({"type": "progress", "seq": seq, "stage": "loading", "done": 0, "total": 1});
        outbox.offer(Slot::Progress, seq, text(msg));
    }
    let loaded = app.volumes.get(&job.desc, &app.base, job.frame)?;
    if !outbox.is_current(seq) {
        return Ok(false);
    }
    let resolved = loaded
        .resolve(&job.desc, &app.base)
        .map_err(|e| e.to_string())?;
    let settings = &resolved.settings;
    let coarse = budget.pixels(settings.width as u64 * settings.height as u64);
    let outline = match &loaded.volume {
        AnyVolume::Particles(v) => v.periodic().map(|b| (resolved.camera, b)),
        _ => None,
    };
    let control = Control::new().with_cancel(cancel.clone());
    let mut sent = false;
    let result = voxless::render_progressive_on(
        &app.device,
        &loaded.volume,
        (&resolved.camera, &resolved.tf, settings),
        (Some(coarse), Some(&mut *budget)),
        &control,
        &mut Vec::new(),
        &mut |stage, film, at| {
            // The first image only: a view too small for a coarse stage
            // gives its first pass instead.
            let bg = resolved.background;
            let shows = Some((path_frame, job.frame));
            sent = send_frame(outbox, job, (stage, film, at), outline, bg, false, shows);
            false
        },
    );
    match result {
        Ok(r) => Ok(r.is_ok() && sent),
        Err(e) => Err(e.to_string()),
    }
}

/// Encodes and offers one image (of a path preview: `shows` the path and
/// data frames); false when it is no longer wanted.
fn send_frame(
    outbox: &Outbox,
    job: &Job,
    (stage, film, at): (Stage, &Film, &RenderSettings),
    outline: Option<(voxless::core::Camera, voxless::core::Aabb)>,
    background: [f32; 3],
    converged: bool,
    shows: Option<(f64, usize)>,
) -> bool {
    if !outbox.is_current(job.seq) {
        return false;
    }
    let mut image = film.resolve();
    if let Some((camera, b)) = &outline {
        voxless::core::draw_box_outline(&mut image, camera, b, [0.7, 0.7, 0.7, 0.5]);
    }
    let encoded = match encode::encode(&image, background, converged) {
        Ok(e) => e,
        Err(_) => return false,
    };
    let header = FrameHeader {
        seq: job.seq,
        stage: match stage {
            Stage::Coarse => "coarse".into(),
            _ if converged => "converged".into(),
            _ => "pass".into(),
        },
        mime: encoded.mime.into(),
        width: at.width,
        height: at.height,
        passes: film.passes(),
        spp: at.spp,
        ms: job.received.elapsed().as_secs_f64() * 1e3,
        path_frame: shows.map(|s| s.0),
        data_frame: shows.map(|s| s.1),
    };
    outbox.offer(
        Slot::Image,
        job.seq,
        Outgoing::Binary(pack_frame(&header, &encoded.bytes)),
    )
}

/// What a histogram depends on: the data, value range, scale and clip box.
fn histogram_key(job: &Job, st: &RenderSettings) -> String {
    format!(
        "{}|{:?}|{}|{:?}",
        crate::app::Volumes::key(&job.desc, job.frame),
        st.value_range,
        st.log_scale,
        st.clip
    )
}

/// The histogram of the view, computed after its image converged (it costs
/// a little, and the image should not wait for it) unless it is known.
fn send_histogram(
    outbox: &Outbox,
    job: &Job,
    loaded: &Loaded,
    st: &RenderSettings,
    memory: &mut Memory,
) {
    let key = histogram_key(job, st);
    if memory.histogram_key.as_deref() == Some(key.as_str()) {
        return;
    }
    let h = voxless::field_histogram(&loaded.volume, st, HIST_BINS, HIST_SAMPLES);
    let msg = json!({"type": "histogram", "seq": job.seq, "histogram": h});
    memory.histogram = Some(h);
    memory.histogram_key = Some(key);
    outbox.offer(Slot::Histogram, job.seq, text(msg));
}

/// The `state` message: what the page's controls show for this view.
fn state_message(
    app: &App,
    job: &Job,
    loaded: &Loaded,
    resolved: &Resolved,
    memory: &mut Memory,
    tab: &Mutex<Tab>,
) -> serde_json::Value {
    let st = &resolved.settings;
    let volume = &loaded.volume;
    let key = histogram_key(job, st);
    let histogram = memory
        .histogram
        .as_ref()
        .filter(|_| memory.histogram_key.as_deref() == Some(key.as_str()));
    // Positions the page shows and edits (clip box) are world positions.
    let b = volume.bounds();
    let (lo, hi) = (loaded.frame.to_world(b.min), loaded.frame.to_world(b.max));
    let tf = &resolved.tf;
    let colors: Vec<[f32; 3]> = (0..64)
        .map(|i| tf.colormap().srgb(i as f32 / 63.0))
        .collect();
    let opacity: Vec<[f32; 2]> = tf
        .opacity_map()
        .0
        .points()
        .iter()
        .map(|&(x, y)| [x, y])
        .collect();
    let unit = |v: f32| {
        if st.log_scale {
            v.max(f32::MIN_POSITIVE).log10()
        } else {
            v
        }
    };
    let (fields, field, color_field) = match volume {
        AnyVolume::Amr(v) => {
            let names = v.field_names().to_vec();
            let a = job.desc.amr.clone().unwrap_or_default();
            let field = a.field.clone().or_else(|| names.first().cloned());
            (names, field, a.color_field)
        }
        _ => (Vec::new(), None, None),
    };
    let mut colormaps: Vec<serde_json::Value> = voxless::transfer::COLORMAP_NAMES
        .iter()
        .map(|n| json!({"name": n, "source": "builtin"}))
        .collect();
    if let Some((file, names)) = &app.colormap_file {
        colormaps.extend(
            names
                .iter()
                .map(|n| json!({"name": n, "source": "file", "file": file})),
        );
    }
    let t = tab.lock().unwrap_or_else(|e| e.into_inner());
    colormaps.extend(
        t.imported
            .iter()
            .map(|p| json!({"name": p.name, "source": "imported"})),
    );
    drop(t);
    json!({
        "type": "state",
        "seq": job.seq,
        "kind": volume.kind(),
        "frames": app.frames,
        "frame": job.frame,
        "scene": job.desc,
        "value_range": [st.value_range.lo, st.value_range.hi],
        "log_scale": st.log_scale,
        "attribute_range": st.attribute_range.map(|r| [r.lo, r.hi]),
        "opacity_points": opacity,
        "colors": colors,
        "colormaps": colormaps,
        "fields": fields,
        "columns": app.particle_columns,
        "attribute": job.desc.particles.as_ref().and_then(|p| p.attribute.clone()),
        "initial_attribute": app.initial.particles.as_ref().and_then(|p| p.attribute.clone()),
        "field": field,
        "color_field": color_field,
        "iso": st.iso.iter().map(|&v| unit(v)).collect::<Vec<f32>>(),
        "clip": job.desc.render.clip,
        "bounds": [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]],
        "shade": st.light.is_some(),
        "shadows": st.scatter.is_some(),
        "spp": st.spp,
        "opacity_scale": st.opacity_scale,
        "width": st.width,
        "height": st.height,
        "histogram": histogram,
        "notes": loaded.notes.iter().chain(&resolved.notes).collect::<Vec<_>>(),
    })
}

/// `/frame.png`: the latest view (or the initial one) at `width`×`height`
/// (the view's own size when not given), all passes, as PNG bytes.
pub fn frame_png(
    app: &App,
    width: Option<u32>,
    height: Option<u32>,
    cancel: &CancelToken,
) -> Result<Vec<u8>, String> {
    let _busy = app.busy();
    let (mut desc, frame) = app.current();
    if let Some(w) = width {
        desc.image.width = Some(w);
    }
    if let Some(h) = height {
        desc.image.height = Some(h);
    }
    let loaded = app.volumes.get(&desc, &app.base, frame)?;
    let resolved = loaded
        .resolve(&desc, &app.base)
        .map_err(|e| e.to_string())?;
    // The CLI's checks: absurd work refused, an image of nothing an error.
    resolved
        .check_work(&loaded.volume, &loaded.frame, &desc)
        .map_err(|e| e.to_string())?;
    let control = Control::new().with_cancel(cancel.clone());
    let film = app
        .device
        .render_film(&loaded.volume, &resolved, &control, &mut Vec::new())
        .map_err(|e| e.to_string())?
        .map_err(|e| e.to_string())?;
    let image = film.resolve();
    let bounds = loaded.frame.box_to_world(loaded.volume.bounds());
    resolved
        .check_image(bounds, film.stats(), &image)
        .map_err(|e| e.to_string())?;
    let image = encode::encode(&image, resolved.background, true).map_err(|e| e.to_string())?;
    Ok(image.bytes)
}
