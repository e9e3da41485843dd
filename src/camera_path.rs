//! Camera paths: a scene's `[[camera.keyframes]]` turned into a camera for
//! every path frame, and the data frame each path frame shows.
//!
//! The model:
//!
//! - A path is two or more keyframes at strictly increasing path frames
//!   `f₀ < f₁ < …`, each with an eye, a look-at point and an up vector
//!   (and a field of view, or an orthographic view height).
//! - **Positions** (eye and look-at) follow a cubic Hermite spline in the
//!   path frame whose tangent at a keyframe is the frame-weighted
//!   three-point slope of its neighbours (a Catmull–Rom spline with the
//!   frame numbers as knots; one-sided at the ends). It passes through
//!   every keyframe exactly and its velocity is continuous everywhere, also
//!   across keyframes spaced unevenly, so the camera never jerks.
//! - **Orientation**: the camera's up vector comes from a quaternion slerp
//!   between the keyframes' orientations (look direction and up), so the
//!   view turns by the shortest rotation and never rolls on its own; the
//!   renderer then makes it perpendicular to the look direction of the
//!   interpolated positions.
//! - **Field of view** and orthographic height follow the same spline as
//!   positions, clamped to valid values.
//! - Before the first keyframe and after the last, the camera holds.
//! - Two identical keyframes make a still camera (every tangent is zero).
//!
//! Which data frame a path frame shows ([`data_frame`]): the last one
//! numbered at or before it (hold), the nearest one, or the data frames
//! spread evenly over the path (stretch).

use voxless_scene::{
    CameraDesc, DEFAULT_PATH_FPS, FollowName, KeyframeDesc, ProjectionName, SceneDesc,
};

use crate::SceneError;
use crate::camera::{DEFAULT_UP, VIEW_FOV_DEG};

type V3 = [f64; 3];

/// The camera at one path frame (world coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathPose {
    pub eye: V3,
    pub look_at: V3,
    pub up: V3,
    /// Vertical field of view, degrees (perspective paths).
    pub fov: f64,
    /// The view's world height (orthographic paths).
    pub orthographic: Option<f64>,
}

/// A validated camera path (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    frames: Vec<f64>,
    poses: Vec<PathPose>,
    /// Each keyframe's orientation (w, x, y, z), signs chosen so that
    /// neighbours are in the same hemisphere (shortest slerp).
    quats: Vec<[f64; 4]>,
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: V3) -> V3 {
    let l = dot(a, a).sqrt();
    a.map(|v| v / l)
}

fn setting(what: String, why: impl Into<String>) -> SceneError {
    SceneError::setting(&what, why.into())
}

impl CameraPath {
    /// The path `camera.keyframes` describe, or `None` without keyframes.
    /// Errors name the keyframe and setting: fewer than two keyframes,
    /// frames not strictly increasing, a missing or non-finite eye or
    /// look-at, an eye on its look-at point, an up vector along the look
    /// direction, a field of view outside (0, 180), perspective and
    /// orthographic keyframes mixed.
    pub fn new(camera: &CameraDesc) -> Result<Option<CameraPath>, SceneError> {
        let Some(keys) = &camera.keyframes else {
            return Ok(None);
        };
        if keys.len() < 2 {
            return Err(SceneError::setting(
                "camera.keyframes",
                format!(
                    "a path interpolates between keyframes and needs at least two; {} given",
                    keys.len()
                ),
            ));
        }
        let ortho_camera = camera.projection == Some(ProjectionName::Orthographic);
        let ortho = keys.iter().filter(|k| k.orthographic.is_some()).count();
        if ortho != 0 && ortho != keys.len() {
            return Err(SceneError::setting(
                "camera.keyframes",
                "some keyframes are orthographic and some are not: give `orthographic` in every \
                 keyframe or in none",
            ));
        }
        let fps = camera.fps.unwrap_or(DEFAULT_PATH_FPS);
        if !(fps.is_finite() && fps > 0.0) {
            return Err(SceneError::setting(
                "camera.fps",
                format!("{fps} is not a frame rate > 0"),
            ));
        }
        let mut poses = Vec::with_capacity(keys.len());
        let mut frames: Vec<f64> = Vec::with_capacity(keys.len());
        for (i, k) in keys.iter().enumerate() {
            let name = |field: &str| format!("camera.keyframes[{i}].{field}");
            let f = match (k.frame, k.time) {
                (Some(f), None) => f,
                (None, Some(t)) => t * fps,
                _ => {
                    return Err(setting(
                        name("frame"),
                        "give each keyframe a frame or a time (seconds), one of them",
                    ));
                }
            };
            if !f.is_finite() {
                return Err(setting(name("frame"), format!("{f} is not finite")));
            }
            if i > 0 && !(f > frames[i - 1]) {
                return Err(setting(
                    name("frame"),
                    format!(
                        "{f} does not follow keyframe {} at frame {}: keyframes must be in \
                         increasing frame order",
                        i - 1,
                        frames[i - 1]
                    ),
                ));
            }
            frames.push(f);
            poses.push(pose_of(k, camera, ortho_camera, &name)?);
        }
        let mut quats: Vec<[f64; 4]> = poses.iter().map(orientation).collect();
        for i in 1..quats.len() {
            let d: f64 = (0..4).map(|c| quats[i][c] * quats[i - 1][c]).sum();
            if d < 0.0 {
                quats[i] = quats[i].map(|c| -c);
            }
        }
        Ok(Some(CameraPath {
            frames,
            poses,
            quats,
        }))
    }

    /// The first and last keyframes' frames.
    pub fn span(&self) -> (f64, f64) {
        (self.frames[0], self.frames[self.frames.len() - 1])
    }

    /// The camera at path frame `t` (see the module docs); exactly the
    /// keyframe's camera at a keyframe's frame.
    pub fn at(&self, t: f64) -> PathPose {
        let n = self.frames.len();
        if let Some(i) = self.frames.iter().position(|&f| f == t) {
            return self.poses[i];
        }
        if t <= self.frames[0] {
            return self.poses[0];
        }
        if t >= self.frames[n - 1] {
            return self.poses[n - 1];
        }
        // The segment [f_i, f_i+1] holding t.
        let i = self.frames.partition_point(|&f| f <= t) - 1;
        let (f0, f1) = (self.frames[i], self.frames[i + 1]);
        let s = (t - f0) / (f1 - f0);
        let spline = |get: &dyn Fn(&PathPose) -> f64| {
            let p: Vec<f64> = self.poses.iter().map(get).collect();
            hermite(&self.frames, &p, i, s)
        };
        let eye = std::array::from_fn(|a| spline(&|p: &PathPose| p.eye[a]));
        let look_at = std::array::from_fn(|a| spline(&|p: &PathPose| p.look_at[a]));
        let q = slerp(self.quats[i], self.quats[i + 1], s);
        let up = rotate(q, [0.0, 1.0, 0.0]);
        let fov = spline(&|p: &PathPose| p.fov).clamp(0.01, 179.0);
        let orthographic = self.poses[0].orthographic.map(|_| {
            let lo = self.poses.iter().filter_map(|p| p.orthographic);
            let floor = lo.fold(f64::INFINITY, f64::min) * 1e-3;
            spline(&|p: &PathPose| p.orthographic.unwrap_or(0.0)).max(floor)
        });
        PathPose {
            eye,
            look_at,
            up,
            fov,
            orthographic,
        }
    }

    /// `desc` with its camera set to the path's camera at frame `t`
    /// (orbit, elevation and zoom kept: they act on top of the path).
    pub fn apply(&self, desc: &SceneDesc, t: f64) -> SceneDesc {
        let p = self.at(t);
        let mut d = desc.clone();
        let c = &mut d.camera;
        c.eye = Some(p.eye);
        c.look_at = Some(p.look_at);
        c.up = Some(p.up.map(|v| v as f32));
        match p.orthographic {
            Some(h) => {
                c.projection = Some(ProjectionName::Orthographic);
                c.ortho_height = Some(h as f32);
            }
            None => c.fov = Some(p.fov as f32),
        }
        d
    }
}

/// A keyframe's camera, its unset settings taken from `camera` and the
/// defaults.
fn pose_of(
    k: &KeyframeDesc,
    camera: &CameraDesc,
    ortho_camera: bool,
    name: &dyn Fn(&str) -> String,
) -> Result<PathPose, SceneError> {
    let point = |v: Option<[f64; 3]>, field: &str| -> Result<V3, SceneError> {
        match v {
            None => Err(setting(
                name(field),
                "every keyframe needs an eye and a look-at point",
            )),
            Some(p) if p.iter().all(|x| x.is_finite()) => Ok(p),
            Some(p) => Err(setting(name(field), format!("{p:?} is not finite"))),
        }
    };
    let eye = point(k.eye, "eye")?;
    let look_at = point(k.look_at, "look_at")?;
    let forward = sub(look_at, eye);
    if !(dot(forward, forward) > 0.0) {
        return Err(setting(name("eye"), "is on the look-at point"));
    }
    let up = k.up.or(camera.up).unwrap_or(DEFAULT_UP).map(f64::from);
    let side = cross(unit(forward), up);
    if !(dot(up, up).is_finite() && dot(side, side) > 1e-12 * dot(up, up)) {
        return Err(setting(
            name("up"),
            format!("{up:?} is zero, not finite or along the look direction"),
        ));
    }
    let fov = k.fov.or(camera.fov).unwrap_or(VIEW_FOV_DEG) as f64;
    if !(fov > 0.0 && fov < 180.0) {
        return Err(setting(name("fov"), format!("{fov}° is outside (0, 180)")));
    }
    let orthographic = match k.orthographic {
        Some(h) if !(h.is_finite() && h > 0.0) => {
            return Err(setting(
                name("orthographic"),
                format!("the view height {h} must be finite and > 0"),
            ));
        }
        Some(h) => Some(h as f64),
        None if ortho_camera => {
            return Err(setting(
                name("orthographic"),
                "the camera is orthographic: give every keyframe its view height",
            ));
        }
        None => None,
    };
    Ok(PathPose {
        eye,
        look_at,
        up,
        fov,
        orthographic,
    })
}

/// Value at `s` ∈ [0, 1] of segment `i` of the frame-knotted Catmull–Rom
/// (cubic Hermite) spline through `p` at `frames`.
fn hermite(frames: &[f64], p: &[f64], i: usize, s: f64) -> f64 {
    let n = frames.len();
    let slope = |a: usize, b: usize| (p[b] - p[a]) / (frames[b] - frames[a]);
    // dp/dframe at keyframe k: the frame-weighted mean of the slopes on
    // either side (exact for a parabola through three keyframes).
    let tangent = |k: usize| {
        if k == 0 {
            slope(0, 1)
        } else if k == n - 1 {
            slope(n - 2, n - 1)
        } else {
            let (h0, h1) = (frames[k] - frames[k - 1], frames[k + 1] - frames[k]);
            (slope(k - 1, k) * h1 + slope(k, k + 1) * h0) / (h0 + h1)
        }
    };
    let h = frames[i + 1] - frames[i];
    let (m0, m1) = (tangent(i) * h, tangent(i + 1) * h);
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * p[i]
        + (s3 - 2.0 * s2 + s) * m0
        + (-2.0 * s3 + 3.0 * s2) * p[i + 1]
        + (s3 - s2) * m1
}

/// The rotation taking the camera's frame (x right, y up, −z forward) to
/// the pose's, as a unit quaternion (w, x, y, z).
fn orientation(p: &PathPose) -> [f64; 4] {
    let f = unit(sub(p.look_at, p.eye));
    let r = unit(cross(f, p.up));
    let u = cross(r, f);
    let back = f.map(|v| -v);
    // Columns r, u, back of the rotation matrix m[row][col].
    let m = [
        [r[0], u[0], back[0]],
        [r[1], u[1], back[1]],
        [r[2], u[2], back[2]],
    ];
    let tr = m[0][0] + m[1][1] + m[2][2];
    let q = if tr > 0.0 {
        let s = (tr + 1.0).sqrt() * 2.0;
        [
            0.25 * s,
            (m[2][1] - m[1][2]) / s,
            (m[0][2] - m[2][0]) / s,
            (m[1][0] - m[0][1]) / s,
        ]
    } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
        let s = (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt() * 2.0;
        [
            (m[2][1] - m[1][2]) / s,
            0.25 * s,
            (m[0][1] + m[1][0]) / s,
            (m[0][2] + m[2][0]) / s,
        ]
    } else if m[1][1] > m[2][2] {
        let s = (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt() * 2.0;
        [
            (m[0][2] - m[2][0]) / s,
            (m[0][1] + m[1][0]) / s,
            0.25 * s,
            (m[1][2] + m[2][1]) / s,
        ]
    } else {
        let s = (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt() * 2.0;
        [
            (m[1][0] - m[0][1]) / s,
            (m[0][2] + m[2][0]) / s,
            (m[1][2] + m[2][1]) / s,
            0.25 * s,
        ]
    };
    let l = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    q.map(|c| c / l)
}

/// Spherical linear interpolation of unit quaternions in one hemisphere.
fn slerp(a: [f64; 4], b: [f64; 4], s: f64) -> [f64; 4] {
    let d: f64 = (0..4).map(|c| a[c] * b[c]).sum::<f64>().clamp(-1.0, 1.0);
    let (wa, wb) = if d > 1.0 - 1e-12 {
        (1.0 - s, s)
    } else {
        let th = d.acos();
        let st = th.sin();
        (((1.0 - s) * th).sin() / st, (s * th).sin() / st)
    };
    let q: [f64; 4] = std::array::from_fn(|c| wa * a[c] + wb * b[c]);
    let l = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    q.map(|c| c / l)
}

/// `v` rotated by the unit quaternion `q`.
fn rotate(q: [f64; 4], v: V3) -> V3 {
    let (w, u) = (q[0], [q[1], q[2], q[3]]);
    let t = cross(u, v).map(|c| 2.0 * c);
    let ut = cross(u, t);
    std::array::from_fn(|a| v[a] + w * t[a] + ut[a])
}

/// The data frame path frame `t` shows, of the data's frame `numbers`
/// (sorted; see [`crate::frame_numbers`]), for a path spanning `span`.
pub fn data_frame(
    t: f64,
    numbers: &[usize],
    follow: Option<FollowName>,
    span: (f64, f64),
) -> usize {
    let last = numbers.len() - 1;
    let nearest = |x: f64| {
        let mut best = 0;
        for (k, &n) in numbers.iter().enumerate() {
            if (n as f64 - x).abs() < (numbers[best] as f64 - x).abs() {
                best = k;
            }
        }
        numbers[best]
    };
    match follow.unwrap_or(FollowName::Hold) {
        FollowName::Hold => {
            let k = numbers.partition_point(|&n| n as f64 <= t);
            numbers[k.saturating_sub(1)]
        }
        FollowName::Nearest => nearest(t),
        FollowName::Stretch => {
            let (a, b) = span;
            let s = if b > a {
                ((t - a) / (b - a)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            numbers[(s * last as f64).round() as usize]
        }
    }
}

/// The most frames one sequence renders (a typo such as `0..10000000`
/// is refused before any work, not started).
pub const MAX_FRAMES: usize = 1_000_000;

/// What a sequence renders: its frames, each a path frame (the number its
/// output is numbered by) and the data frame it shows, in order, and the
/// camera path when the scene has one.
#[derive(Clone, Debug)]
pub struct Sequence {
    pub frames: Vec<(usize, usize)>,
    pub path: Option<CameraPath>,
    /// A turntable of this many frames: frame k orbits the camera by
    /// 360°·k/n on top of the scene's orbit (and path).
    pub turntable: Option<usize>,
    /// What the plan noticed (a range reaching past the data).
    pub notes: Vec<String>,
}

impl Sequence {
    /// The distinct data frames shown, in order.
    pub fn data_frames(&self) -> Vec<usize> {
        let mut d: Vec<usize> = self.frames.iter().map(|f| f.1).collect();
        d.dedup();
        d
    }

    /// Whether the camera moves from frame to frame.
    pub fn moves(&self) -> bool {
        self.path.is_some() || self.turntable.is_some()
    }

    /// `desc` as frame `t` shows it: the path's camera, turned by the
    /// turntable's orbit.
    pub fn desc_at(&self, desc: &SceneDesc, t: usize) -> SceneDesc {
        let mut d = match &self.path {
            Some(p) => p.apply(desc, t as f64),
            None => desc.clone(),
        };
        if let Some(n) = self.turntable {
            let start = desc.camera.orbit.unwrap_or(0.0);
            d.camera.orbit = Some(start + 360.0 * t as f32 / n as f32);
        }
        d
    }
}

/// A turntable of `n` frames (numbered 0..n) of data frame `frame`: a full
/// orbit about the look-at point, on top of the scene's camera (and of its
/// camera path, whose frames 0..n it follows).
pub fn turntable(desc: &SceneDesc, n: usize, frame: usize) -> Result<Sequence, SceneError> {
    if n == 0 || n > MAX_FRAMES {
        return Err(SceneError::setting(
            "--turntable",
            format!("{n} frames; a turntable has 1..={MAX_FRAMES}"),
        ));
    }
    Ok(Sequence {
        frames: (0..n).map(|k| (k, frame)).collect(),
        path: CameraPath::new(&desc.camera)?,
        turntable: Some(n),
        notes: Vec::new(),
    })
}

/// The frames `range` (A..B, inclusive) of `desc` (paths relative to
/// `base`) renders. Without a camera path: the data frames numbered in the
/// range (an error when none is, a note when the range reaches past the
/// data). With one: every path frame A..B, each showing the data frame
/// `camera.follow` picks ([`data_frame`]).
pub fn sequence(
    desc: &SceneDesc,
    base: &std::path::Path,
    range: std::ops::RangeInclusive<usize>,
) -> Result<Sequence, SceneError> {
    let numbers = crate::frame_numbers(desc, base)?;
    let path = CameraPath::new(&desc.camera)?;
    let list = crate::frames::list_numbers;
    let mut notes = Vec::new();
    let frames: Vec<(usize, usize)> = match &path {
        Some(p) => {
            let n = range.end() - range.start() + 1;
            if n > MAX_FRAMES {
                return Err(SceneError::setting(
                    "--frames",
                    format!("{n} path frames; at most {MAX_FRAMES} are rendered in one run"),
                ));
            }
            let follow = desc.camera.follow;
            range
                .map(|t| (t, data_frame(t as f64, &numbers, follow, p.span())))
                .collect()
        }
        None => {
            let frames: Vec<(usize, usize)> = numbers
                .iter()
                .filter(|n| range.contains(n))
                .map(|&n| (n, n))
                .collect();
            if frames.is_empty() {
                return Err(SceneError::setting(
                    "--frames",
                    format!(
                        "{}..{}: no frame is numbered in that range; the data has frames {}",
                        range.start(),
                        range.end(),
                        list(&numbers)
                    ),
                ));
            }
            if range.start() < &numbers[0] || range.end() > &numbers[numbers.len() - 1] {
                let shown: Vec<usize> = frames.iter().map(|f| f.0).collect();
                notes.push(format!(
                    "--frames {}..{} reaches past the data, whose frames in that range are {}",
                    range.start(),
                    range.end(),
                    list(&shown)
                ));
            }
            frames
        }
    };
    Ok(Sequence {
        frames,
        path,
        turntable: None,
        notes,
    })
}

#[cfg(test)]
#[path = "tests/camera_path.rs"]
mod tests;
