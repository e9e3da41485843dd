//! The websocket protocol between the page and the server.
//!
//! **Client → server**: JSON text messages, each with a sequence number
//! `seq` that increases with every interaction of that tab:
//!
//! ```json
//! {"seq": 1, "type": "hello", "width": 1024, "height": 768}
//! {"seq": 2, "type": "orbit", "yaw": 3.5, "pitch": -1.0, "drag": true}
//! {"seq": 3, "type": "pan", "dx": 0.01, "dy": 0.0, "drag": true}
//! {"seq": 4, "type": "zoom", "factor": 1.1, "drag": false}
//! {"seq": 5, "type": "end_drag"}
//! {"seq": 6, "type": "set", "patch": {"transfer": {"colormap": "magma"}}}
//! {"seq": 7, "type": "frame", "frame": 3}
//! {"seq": 8, "type": "reset"}
//! {"seq": 9, "type": "resize", "width": 800, "height": 600}
//! {"seq": 10, "type": "colormap_import", "json": "[{\"Name\": …}]"}
//! {"seq": 11, "type": "save_scene"}
//! {"seq": 12, "type": "add_keyframe", "frame": 48}
//! {"seq": 13, "type": "keyframes", "op": "remove_last"}
//! {"seq": 14, "type": "keyframes", "op": "clear"}
//! {"seq": 15, "type": "preview_path"}
//! {"seq": 16, "type": "stop_preview"}
//! ```
//!
//! **Camera paths** (see `path`): the keyframes live in the tab's scene
//! description (`camera.keyframes`), so "save scene" writes them as
//! `[[camera.keyframes]]`. `add_keyframe` records the current camera (eye,
//! look-at point, up, field of view or orthographic view height) at path
//! frame `frame` — when left out, the last keyframe's frame + 24 (0 for the
//! first) — which must come after the last keyframe's. `keyframes` removes
//! the last one or all. Each answers with a `keyframes` message —
//! `{"type": "keyframes", "seq": 12, "keyframes": [{"frame": 48, "eye": …}],
//! "next_frame": 72, "follow": null}`, the list as the scene file holds it
//! and the frame the next one gets by default — as does `hello` (a scene
//! may come with keyframes); a refused one answers `error`. None of them
//! changes the image, so none is an interaction.
//!
//! `preview_path` (an interaction) plays the path: every path frame from
//! the first keyframe to the last, the camera from
//! `voxless::camera_path::CameraPath::apply` and, for a time series, the
//! data frame `camera.follow` picks, as coarse images only, at up to 24
//! frames per second (frames are skipped when rendering is slower). Its
//! images carry the `path_frame` (and `data_frame`) they show. A `preview`
//! message with `"state": "playing"` comes before its images, one with
//! `"state": "done"` ends it, and the tab's own view (unchanged by the
//! preview) renders as after any interaction; images being latest-only,
//! the last preview image may follow `done`, but none follows an image of
//! the view. Any newer interaction stops it — `stop_preview` is one that
//! only renders the tab's view. Fewer than two keyframes, or keyframes the
//! library refuses, answer `error` and leave the view alone.
//!
//! **Server → client**: JSON text messages (`ack`, `state`, `progress`,
//! `error`, `scene`, `imported`, `keyframes`, `preview`) and binary image
//! frames. Every message carries the `seq` of the interaction it answers;
//! an image is only ever sent for the latest interaction received (see
//! `outbox`). A binary frame is a 4-byte little-endian length, a JSON
//! [`FrameHeader`] of that length, then the image file (JPEG or PNG).

use serde::{Deserialize, Serialize};

/// Largest text message the server reads (a colormap file included).
pub const MAX_MESSAGE_BYTES: usize = 256 * 1024;

/// Largest view the page may ask for, per side.
pub const MAX_VIEW_SIDE: u32 = 4096;

/// A message from the page.
#[derive(Clone, Debug, Deserialize, PartialEq)]
pub struct ClientMessage {
    pub seq: u64,
    #[serde(flatten)]
    pub action: Action,
}

/// What the page asks for.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Action {
    /// First message: the size of the image element in device pixels.
    Hello {
        width: u32,
        height: u32,
    },
    Resize {
        width: u32,
        height: u32,
    },
    /// Degrees about the up vector and towards it.
    Orbit {
        yaw: f32,
        pitch: f32,
        #[serde(default)]
        drag: bool,
    },
    /// Fractions of the view height.
    Pan {
        dx: f32,
        dy: f32,
        #[serde(default)]
        drag: bool,
    },
    Zoom {
        factor: f32,
        #[serde(default)]
        drag: bool,
    },
    /// The drag ended: refine the view it reached.
    EndDrag,
    /// Back to the view the server started with.
    Reset,
    /// A partial scene description merged into the tab's (see
    /// `session::apply_patch` for what may be patched).
    Set {
        patch: serde_json::Value,
    },
    /// A frame of a time series.
    Frame {
        frame: usize,
    },
    /// A ParaView preset file (JSON text) to pick colormaps from.
    ColormapImport {
        json: String,
    },
    /// Asks for the view as a scene file.
    SaveScene,
    /// Records the current camera as a keyframe at path frame `frame`
    /// (default: the last keyframe's + 24, or 0).
    AddKeyframe {
        #[serde(default)]
        frame: Option<f64>,
    },
    /// Edits the keyframes.
    Keyframes {
        op: KeyframeOp,
    },
    /// Plays the camera path as coarse images.
    PreviewPath,
    /// Stops a preview: renders the tab's own view.
    StopPreview,
}

/// An edit of the keyframe list.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum KeyframeOp {
    RemoveLast,
    Clear,
}

impl Action {
    /// Whether the action changes the image (and so gets a new render).
    pub fn renders(&self) -> bool {
        !matches!(
            self,
            Action::SaveScene
                | Action::ColormapImport { .. }
                | Action::AddKeyframe { .. }
                | Action::Keyframes { .. }
        )
    }
    /// Whether the user is in the middle of a drag (coarse images only).
    pub fn dragging(&self) -> bool {
        matches!(
            self,
            Action::Orbit { drag: true, .. }
                | Action::Pan { drag: true, .. }
                | Action::Zoom { drag: true, .. }
        )
    }
}

/// The JSON header of a binary image frame.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FrameHeader {
    pub seq: u64,
    /// "coarse", "pass" or "converged".
    pub stage: String,
    /// "image/jpeg" or "image/png".
    pub mime: String,
    pub width: u32,
    pub height: u32,
    /// Passes in the image and the passes asked for.
    pub passes: u32,
    pub spp: u32,
    /// Milliseconds from the interaction's arrival to this image (for a
    /// path preview: from the start of this image).
    pub ms: f64,
    /// The path frame a preview image shows and the data frame (0, 1, …
    /// as `frame` counts them) it shows (absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_frame: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data_frame: Option<usize>,
}

/// Packs a header and an image file into one binary message.
pub fn pack_frame(header: &FrameHeader, image: &[u8]) -> Vec<u8> {
    let json = serde_json::to_vec(header).unwrap_or_default();
    let mut out = Vec::with_capacity(4 + json.len() + image.len());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(image);
    out
}

/// Splits a binary message into its header and image file.
pub fn unpack_frame(data: &[u8]) -> Option<(FrameHeader, &[u8])> {
    let len = u32::from_le_bytes(data.get(..4)?.try_into().ok()?) as usize;
    let json = data.get(4..4 + len)?;
    let header = serde_json::from_slice(json).ok()?;
    Some((header, &data[4 + len..]))
}
