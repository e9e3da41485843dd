//! [`Pose`]: the camera an interactive front-end moves — orbit, pan and
//! zoom — written back into a [`CameraDesc`], so the view a user reached
//! is a scene description like any other (`voxless render` of it draws the
//! same image).
//!
//! Model: a pose is an eye, a look-at point (the orbit centre) and an up
//! vector, plus the orthographic view height when the projection is
//! orthographic — in the volume's own coordinates, with the [`WorldFrame`]
//! that places them in the world. [`Pose::of`] resolves a description
//! exactly as [`crate::resolve_in`] does (default framing, orbit, elevation
//! and zoom applied); [`Pose::write`] stores the pose as explicit world
//! `eye`, `look_at`, `up` (and `ortho_height`) and clears the relative
//! `orbit`, `elevation` and `zoom`, so resolving the written description
//! gives the pose's camera again.
//!
//! Invariants: orbiting keeps the distance to the look-at point; the eye
//! never passes over the pole (elevation stays within ±89.9° of the plane
//! normal to `up`, as [`CameraDesc::elevation`] does); panning moves eye and
//! look-at point together; zooming never changes the view direction.

use voxless_core::{Aabb, Camera, Projection, Vec3};
use voxless_scene::{CameraDesc, ProjectionName};

use crate::camera::ViewAdjust;
use crate::{SceneError, WorldFrame};

/// An explicit camera pose (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Eye and look-at point in the volume's coordinates.
    pub eye: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    /// World-space view height of an orthographic camera; `None` for
    /// perspective.
    pub ortho_height: Option<f32>,
    /// Where the volume's coordinates sit in the world.
    pub frame: WorldFrame,
}

impl Pose {
    /// The pose `c` describes for data in `bounds` (the volume's
    /// coordinates, placed in the world by `frame`), seen in an image of
    /// `aspect` = width / height (the default framing depends on it).
    pub fn of(
        c: &CameraDesc,
        bounds: &Aabb,
        aspect: f32,
        frame: &WorldFrame,
    ) -> Result<Pose, SceneError> {
        let camera = crate::camera::camera(c, bounds, aspect, frame)?;
        let look_at = c
            .look_at
            .map(|p| frame.to_local(p))
            .unwrap_or(bounds.center());
        // The up vector the camera was resolved with: the default (+z),
        // or +y where an explicit eye looks straight along it.
        let up = match c.up {
            Some(u) => Vec3::from_array(u),
            None if c.eye.is_some() && camera.forward.z.abs() > 0.999 => Vec3::new(0.0, 1.0, 0.0),
            None => Vec3::from_array(crate::camera::DEFAULT_UP),
        };
        let ortho_height = match camera.projection {
            Projection::Orthographic { half_height, .. } => Some(2.0 * half_height),
            Projection::Perspective { .. } => None,
        };
        Ok(Pose {
            eye: camera.eye,
            look_at,
            up,
            ortho_height,
            frame: *frame,
        })
    }

    /// Turns the eye about the look-at point: `yaw_deg` about the up vector
    /// (positive: towards the camera's right, as [`CameraDesc::orbit`]),
    /// then `pitch_deg` towards the up vector (as [`CameraDesc::elevation`],
    /// clamped short of the pole).
    pub fn orbit(&self, yaw_deg: f32, pitch_deg: f32) -> Pose {
        if !(yaw_deg.is_finite() && pitch_deg.is_finite()) {
            return *self;
        }
        let adjust = ViewAdjust {
            orbit: yaw_deg,
            elevation: pitch_deg,
            zoom: 1.0,
        };
        Pose {
            eye: adjust.place_eye(self.eye, self.look_at, self.up, false),
            ..*self
        }
    }

    /// Moves eye and look-at point together across the view: `dx` to the
    /// camera's right and `dy` up, both in units of the view's height at the
    /// look-at point (so a drag across the whole image height moves the
    /// data by exactly that height, whatever the distance or projection).
    pub fn pan(&self, dx: f32, dy: f32, fov_y_deg: f32) -> Pose {
        let Ok(cam) = Camera::look_at(
            self.eye,
            self.look_at,
            self.up,
            Projection::Perspective { fov_y_deg: 30.0 },
        ) else {
            return *self;
        };
        // The height of the view at the look-at distance: what one unit of
        // dx or dy is in world units.
        let height = match self.ortho_height {
            Some(h) => h,
            None => {
                let d = (self.look_at - self.eye).length();
                2.0 * d * (0.5 * fov_y_deg.clamp(1e-3, 179.0).to_radians()).tan()
            }
        };
        let shift = cam.right * (dx * height) + cam.up * (dy * height);
        if !(shift.is_finite() && dx.is_finite() && dy.is_finite()) {
            return *self;
        }
        Pose {
            eye: self.eye + shift,
            look_at: self.look_at + shift,
            ..*self
        }
    }

    /// Zooms by `factor` (> 1: closer): the eye's distance to the look-at
    /// point is divided by it, or the orthographic view height is.
    pub fn zoom(&self, factor: f32) -> Pose {
        if !(factor.is_finite() && factor > 0.0) {
            return *self;
        }
        match self.ortho_height {
            Some(h) => Pose {
                ortho_height: Some(h / factor),
                ..*self
            },
            None => Pose {
                eye: self.look_at + (self.eye - self.look_at) * (1.0 / factor),
                ..*self
            },
        }
    }

    /// Writes the pose into `c` as explicit vectors (see the module docs);
    /// field of view and projection stay as they are.
    pub fn write(&self, c: &mut CameraDesc) {
        c.eye = Some(self.frame.to_world(self.eye));
        c.look_at = Some(self.frame.to_world(self.look_at));
        c.up = Some(self.up.to_array());
        c.orbit = None;
        c.elevation = None;
        c.zoom = None;
        if let Some(h) = self.ortho_height {
            c.projection = Some(ProjectionName::Orthographic);
            c.ortho_height = Some(h);
        }
    }
}

/// Orbits the camera `c` describes for `view` = (the volume's bounds, the
/// image's aspect ratio, its world frame) — see [`Pose::orbit`] — and
/// writes the result back as explicit vectors.
pub fn orbit_camera(
    c: &mut CameraDesc,
    view: (&Aabb, f32, &WorldFrame),
    yaw_deg: f32,
    pitch_deg: f32,
) -> Result<(), SceneError> {
    Pose::of(c, view.0, view.1, view.2)?
        .orbit(yaw_deg, pitch_deg)
        .write(c);
    Ok(())
}

/// Pans the camera `c` describes (see [`Pose::pan`]).
pub fn pan_camera(
    c: &mut CameraDesc,
    view: (&Aabb, f32, &WorldFrame),
    dx: f32,
    dy: f32,
) -> Result<(), SceneError> {
    let fov = c.fov.unwrap_or(30.0);
    Pose::of(c, view.0, view.1, view.2)?
        .pan(dx, dy, fov)
        .write(c);
    Ok(())
}

/// Zooms the camera `c` describes (see [`Pose::zoom`]).
pub fn zoom_camera(
    c: &mut CameraDesc,
    view: (&Aabb, f32, &WorldFrame),
    factor: f32,
) -> Result<(), SceneError> {
    Pose::of(c, view.0, view.1, view.2)?.zoom(factor).write(c);
    Ok(())
}
