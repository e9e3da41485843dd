//! Camera paths in the viewer: keyframes recorded from a tab's view, and
//! the path's preview.
//!
//! Model: the keyframes are part of the tab's scene description
//! (`camera.keyframes`, with `camera.follow`), edited by the page's
//! messages, so "save scene" writes them and `voxless render saved.toml
//! --frames A..B` renders the path the page previewed. The camera math is
//! the library's ([`voxless::camera_path`]); this module only records
//! views and plays frames.
//!
//! - *Recording* a keyframe stores the camera as the tab sees it, as
//!   explicit world vectors: eye, look-at point, up, and the field of view
//!   (perspective) or the view height (orthographic). The tab's camera
//!   becomes explicit too (the same view: relative `orbit`, `elevation` and
//!   `zoom` folded in), since a path renders with those applied on top of
//!   it. Keyframes are added in increasing frame order only.
//! - *Previewing* plays every path frame from the first keyframe to the
//!   last (whole frame numbers, as `--frames` counts them) on the tab's
//!   render worker: for each, the camera of [`CameraPath::apply`] and, for
//!   a time series, the data frame of [`data_frame`], rendered as one
//!   coarse image, paced by the wall clock at [`PREVIEW_FPS`] — frames
//!   whose time has passed are skipped, the first and the last are always
//!   shown. The tab's own view is not changed by a preview.

use std::time::{Duration, Instant};

use serde_json::{Value, json};
use voxless::camera_path::{CameraPath, data_frame};
use voxless::{CameraDesc, CancelToken, CoarseBudget, KeyframeDesc, ProjectionName, SceneDesc};

use crate::app::App;
use crate::outbox::{Outbox, Outgoing, Slot};
use crate::protocol::{Action, KeyframeOp};
use crate::render::{self, Job};
use crate::session::{Tab, aspect};

/// Path frames between a keyframe and the next when the page gives none.
pub const KEYFRAME_STEP: f64 = 24.0;
/// Path frames per second a preview plays at (at most).
pub const PREVIEW_FPS: f64 = 24.0;
/// Most keyframes one path holds (bounded input).
pub const MAX_KEYFRAMES: usize = 1000;
/// Largest path frame a keyframe may be at (path frames are counted one by
/// one; far beyond this, consecutive frames are no longer distinct).
pub const MAX_FRAME: f64 = 1e9;

/// The `keyframes` message: the tab's keyframes and the frame the next one
/// gets by default.
pub fn keyframes_message(seq: u64, desc: &SceneDesc) -> Value {
    let keys = desc.camera.keyframes.as_deref().unwrap_or_default();
    json!({
        "type": "keyframes",
        "seq": seq,
        "keyframes": keys,
        "next_frame": next_frame(keys, &desc.camera),
        "follow": desc.camera.follow,
    })
}

/// The path frame a keyframe of `camera` is at (its frame, or its time at
/// the camera's rate; the viewer records frames).
fn key_frame(k: &KeyframeDesc, camera: &CameraDesc) -> f64 {
    k.path_frame(camera.fps.unwrap_or(voxless::DEFAULT_PATH_FPS))
        .unwrap_or(0.0)
}

/// The frame a keyframe added without one gets.
fn next_frame(keys: &[KeyframeDesc], camera: &CameraDesc) -> f64 {
    keys.last()
        .map_or(0.0, |k| key_frame(k, camera) + KEYFRAME_STEP)
}

/// Applies a keyframe action (`add_keyframe` or `keyframes`) to the tab.
/// On error the tab is unchanged.
pub fn edit(t: &mut Tab, action: &Action) -> Result<(), String> {
    match action {
        Action::AddKeyframe { frame } => add(t, *frame)?,
        Action::Keyframes { op } => {
            let keys = &mut t.desc.camera.keyframes;
            match op {
                KeyframeOp::RemoveLast => {
                    if let Some(k) = keys.as_mut() {
                        k.pop();
                    }
                }
                KeyframeOp::Clear => *keys = None,
            }
            if keys.as_ref().is_some_and(Vec::is_empty) {
                *keys = None;
            }
        }
        _ => return Ok(()),
    }
    // The view a failed render goes back to keeps the path as edited (and
    // so needs an explicit camera too).
    let keyframes = t.desc.camera.keyframes.clone();
    let (bounds, world) = (t.bounds, t.world);
    if let Some((d, _)) = &mut t.last_good {
        d.camera.keyframes = keyframes;
        if d.camera.keyframes.is_some()
            && let Ok(c) = explicit(&d.camera, bounds, world, aspect(d))
        {
            d.camera = c;
        }
    }
    Ok(())
}

/// Records the tab's camera as a keyframe at `frame` (see the module docs).
fn add(t: &mut Tab, frame: Option<f64>) -> Result<(), String> {
    let mut keys = t.desc.camera.keyframes.clone().unwrap_or_default();
    let frame = frame.unwrap_or_else(|| next_frame(&keys, &t.desc.camera));
    if !(frame.is_finite() && (0.0..=MAX_FRAME).contains(&frame)) {
        return Err(format!(
            "keyframe frame {frame}: a path frame is a number from 0 to {MAX_FRAME}"
        ));
    }
    if let Some(last) = keys.last()
        && !(frame > key_frame(last, &t.desc.camera))
    {
        return Err(format!(
            "keyframe frame {frame} is not after the last keyframe's ({}): keyframes are \
             added in increasing frame order (remove the last one to record it again)",
            key_frame(last, &t.desc.camera)
        ));
    }
    if keys.len() >= MAX_KEYFRAMES {
        return Err(format!("a path holds at most {MAX_KEYFRAMES} keyframes"));
    }
    let camera = explicit(&t.desc.camera, t.bounds, t.world, aspect(&t.desc))?;
    let orthographic = if camera.projection == Some(ProjectionName::Orthographic) {
        camera.ortho_height
    } else {
        None
    };
    let mut key = KeyframeDesc {
        frame: Some(frame),
        time: None,
        eye: camera.eye,
        look_at: camera.look_at,
        up: camera.up,
        fov: None,
        orthographic,
    };
    // The field of view the camera renders with (its own or the default),
    // as the library resolves it: a path of this keyframe held still.
    let still = CameraDesc {
        keyframes: Some(vec![
            KeyframeDesc {
                frame: Some(0.0),
                ..key.clone()
            },
            KeyframeDesc {
                frame: Some(1.0),
                ..key.clone()
            },
        ]),
        ..camera.clone()
    };
    let pose = match CameraPath::new(&still) {
        Ok(Some(p)) => p.at(0.0),
        Ok(None) => unreachable!("two keyframes given"),
        Err(e) => return Err(format!("this view cannot be a keyframe: {e}")),
    };
    if orthographic.is_none() {
        key.fov = Some(pose.fov as f32);
    }
    keys.push(key);
    let mut camera = camera;
    camera.keyframes = Some(keys);
    // The whole path must be one the library takes (no mixed projections).
    if camera.keyframes.as_ref().is_some_and(|k| k.len() >= 2) {
        CameraPath::new(&camera).map_err(|e| e.to_string())?;
    }
    t.desc.camera = camera;
    Ok(())
}

/// `camera` as explicit world vectors for data in `bounds` placed by
/// `world`, seen at `aspect` (the same view; see [`voxless::Pose`]):
/// unchanged when it is explicit already, so no digits are lost.
fn explicit(
    camera: &CameraDesc,
    bounds: voxless::Aabb,
    world: voxless::WorldFrame,
    aspect: f32,
) -> Result<CameraDesc, String> {
    let c = camera;
    let ortho = c.projection == Some(ProjectionName::Orthographic);
    let done = c.eye.is_some()
        && c.look_at.is_some()
        && c.up.is_some()
        && c.orbit.is_none()
        && c.elevation.is_none()
        && c.zoom.is_none()
        && (!ortho || c.ortho_height.is_some());
    let mut out = c.clone();
    if !done {
        voxless::Pose::of(c, &bounds, aspect, &world)
            .map_err(|e| e.to_string())?
            .write(&mut out);
    }
    Ok(out)
}

/// The reset view: the camera the server started with, keeping the tab's
/// keyframes (and `follow`). A path recorded in the tab needs an explicit
/// camera (see the module docs).
pub fn reset_camera(initial: &CameraDesc, t: &mut Tab) -> Result<(), String> {
    let keyframes = t.desc.camera.keyframes.take();
    let recorded = keyframes.is_some() && keyframes != initial.keyframes;
    let mut camera = initial.clone();
    camera.keyframes = keyframes;
    camera.follow = t.desc.camera.follow;
    if recorded {
        camera = explicit(&camera, t.bounds, t.world, aspect(&t.desc))?;
    }
    t.desc.camera = camera;
    Ok(())
}

/// A preview to play: the path and the description its frames start from.
#[derive(Clone, Debug)]
pub struct Plan {
    pub path: CameraPath,
    pub desc: SceneDesc,
}

impl Plan {
    /// How many path frames it shows: every whole frame from the first
    /// keyframe's to the last's, or the two keyframes' own frames when no
    /// whole frame lies between them.
    fn count(&self) -> u64 {
        let (first, last) = self.path.span();
        let (a, b) = (first.ceil(), last.floor());
        if a <= b { (b - a) as u64 + 1 } else { 2 }
    }

    /// The `i`-th path frame shown.
    fn frame(&self, i: u64) -> f64 {
        let (first, last) = self.path.span();
        let (a, b) = (first.ceil(), last.floor());
        match (a <= b, i) {
            (true, _) => a + i as f64,
            (false, 0) => first,
            (false, _) => last,
        }
    }

    /// The `preview` message opening (`playing`) or ending (`done`) it.
    pub fn message(&self, seq: u64, state: &str, shown: Option<u64>) -> Value {
        let (first, last) = self.path.span();
        json!({
            "type": "preview",
            "seq": seq,
            "state": state,
            "first": first,
            "last": last,
            "frames": self.count(),
            "shown": shown,
        })
    }
}

/// The preview of the tab's path, or why there is none.
pub fn plan(app: &App, t: &Tab) -> Result<Plan, String> {
    let path = match CameraPath::new(&t.desc.camera) {
        Ok(Some(p)) => p,
        Ok(None) => {
            return Err(
                "no camera path to preview: add two keyframes or more first (Add keyframe)".into(),
            );
        }
        Err(e) => return Err(format!("cannot preview the path: {e}")),
    };
    let mut desc = t.desc.clone();
    if app.frames > 1 {
        // The ranges of the view on screen, so the data frames the path
        // shows do not flicker (as the frame slider and `--frames` do).
        if desc.transfer.value_range.is_none() {
            desc.transfer.value_range = t.value_range;
        }
        if let (Some(p), Some(r)) = (&mut desc.particles, t.attribute_range) {
            p.attribute_range.get_or_insert(r);
        }
    }
    Ok(Plan { path, desc })
}

/// Plays `plan` for interaction `job.seq` (see the module docs). True when
/// it ended by itself (all frames shown, or a frame that failed: an
/// `error`), then the `done` message is sent; false when it was stopped.
pub fn play(
    app: &App,
    outbox: &Outbox,
    job: &Job,
    plan: &Plan,
    cancel: &CancelToken,
    budget: &mut CoarseBudget,
) -> bool {
    let seq = job.seq;
    let stopped = || cancel.is_cancelled() || !outbox.is_current(seq);
    // A time series: the data frame each path frame shows (the page counts
    // frames 0..frames, the library by the numbers the files carry).
    let numbers = if app.frames > 1 {
        voxless::frame_numbers(&plan.desc, &app.base).ok()
    } else {
        None
    };
    let (follow, span) = (plan.desc.camera.follow, plan.path.span());
    let count = plan.count();
    let start = Instant::now();
    let (mut next, mut shown) = (0u64, 0u64);
    let mut failed = None;
    while next < count {
        if stopped() {
            return false;
        }
        let due = (start.elapsed().as_secs_f64() * PREVIEW_FPS) as u64;
        if due < next {
            // Ahead of the clock: wait for this frame's time, watching for
            // a stop.
            let at = start + Duration::from_secs_f64(next as f64 / PREVIEW_FPS);
            let wait = at.saturating_duration_since(Instant::now());
            std::thread::sleep(wait.min(Duration::from_millis(10)));
            continue;
        }
        if next > 0 {
            // Behind: on to the frame the clock is at (the last one at most).
            next = due.min(count - 1);
        }
        let t = plan.frame(next);
        let frame = numbers
            .as_ref()
            .filter(|n| !n.is_empty())
            .and_then(|n| {
                let number = data_frame(t, n, follow, span);
                n.iter().position(|&x| x == number)
            })
            .unwrap_or(job.frame);
        let one = Job {
            seq,
            desc: plan.path.apply(&plan.desc, t),
            frame,
            coarse: true,
            drag: true,
            received: Instant::now(),
            path: None,
        };
        match render::coarse_image(app, outbox, &one, cancel, budget, t) {
            Ok(true) => shown += 1,
            Ok(false) => return false,
            Err(e) => {
                failed = Some(format!("path frame {t}: {e}"));
                break;
            }
        }
        next += 1;
    }
    if stopped() {
        return false;
    }
    if let Some(message) = failed {
        let msg = json!({"type": "error", "seq": seq, "message": message});
        outbox.offer(Slot::Error, seq, Outgoing::Text(msg.to_string()));
    }
    let done = plan.message(seq, "done", Some(shown));
    outbox.offer(Slot::Preview, seq, Outgoing::Text(done.to_string()));
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(first: f64, last: f64) -> Plan {
        let key = |frame: f64, x: f64| KeyframeDesc {
            frame: Some(frame),
            eye: Some([x, -5.0, 1.0]),
            look_at: Some([0.0, 0.0, 0.0]),
            ..Default::default()
        };
        let mut desc = SceneDesc::default();
        desc.camera.keyframes = Some(vec![key(first, 0.0), key(last, 2.0)]);
        let path = CameraPath::new(&desc.camera).unwrap().unwrap();
        Plan { path, desc }
    }

    fn frames(p: &Plan) -> Vec<f64> {
        (0..p.count()).map(|i| p.frame(i)).collect()
    }

    #[test]
    fn a_preview_shows_the_whole_path_frames_from_the_first_keyframe_to_the_last() {
        let p = plan(0.0, 24.0);
        assert_eq!(p.count(), 25);
        assert_eq!((p.frame(0), p.frame(24)), (0.0, 24.0));
        assert_eq!(frames(&plan(0.5, 3.2)), [1.0, 2.0, 3.0]);
        assert_eq!(frames(&plan(7.0, 8.0)), [7.0, 8.0]);
        // No whole frame between: the keyframes' own.
        assert_eq!(frames(&plan(0.25, 0.75)), [0.25, 0.75]);
        let m = p.message(3, "playing", None);
        assert_eq!(
            (m["first"].as_f64(), m["last"].as_f64()),
            (Some(0.0), Some(24.0))
        );
        assert_eq!(m["frames"], 25);
    }
}
