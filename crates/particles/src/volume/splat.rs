//! The particle volume's orthographic projections: its particles through
//! the streaming splatter ([`crate::splat`]), the same code a projection
//! streamed from a file takes. Ghosts are left out: the splatter makes the
//! periodic images itself. Chunks are fixed in size, so the image has the
//! same bits for any thread count.

use voxless_core::{Camera, Cancelled, Control, PixelIntegral};

use crate::ParticleError;
use crate::splat::{CHUNK, SplatDevice, SplatParticle, Splatter};

use super::ParticleVolume;

impl ParticleVolume {
    /// The column density through every pixel centre of an orthographic
    /// `camera` (row-major, row 0 at the top); `None` for other cameras,
    /// and for a part of a decomposed periodic set (it holds images from
    /// other parts; the per-pixel path clips them).
    pub(super) fn splat_projection(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Option<Result<Vec<f32>, Cancelled>> {
        self.project_with_pixels(camera, width, height, self.settings.pixels, control)
    }

    /// [`Self::splat_projection`] with each pixel integrated by `pixels`
    /// instead of the settings' rule (front-ends that choose it per
    /// projection).
    pub fn project_with_pixels(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        pixels: PixelIntegral,
        control: &Control,
    ) -> Option<Result<Vec<f32>, Cancelled>> {
        self.project_on(camera, width, height, pixels, None, control)
            .map(|r| r.map_err(|_| Cancelled))
    }

    /// [`Self::project_with_pixels`] with the plain splats summed on
    /// `device` when given (see [`SplatDevice`]). Errors: the device's, and
    /// [`ParticleError::Cancelled`].
    pub fn project_on(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        pixels: PixelIntegral,
        device: Option<&dyn SplatDevice>,
        control: &Control,
    ) -> Option<Result<Vec<f32>, ParticleError>> {
        if self.settings.periodic.is_some() && !self.own_images {
            return None;
        }
        let splatter = Splatter::new(
            camera,
            width,
            height,
            self.settings.kernel,
            self.settings.periodic,
        )?
        .with_pixels(pixels);
        let mut splatter = match device {
            Some(d) => match splatter.with_device(d) {
                Ok(s) => s,
                Err(e) => return Some(Err(e)),
            },
            None => splatter,
        };
        // The particles without their ghosts, CHUNK at a time.
        let mut own = (0..self.packed.len())
            .filter(|&i| !self.is_ghost(i))
            .map(|i| {
                let q = &self.packed[i];
                SplatParticle {
                    center: q.center,
                    radius: if q.support2 > 0.0 {
                        self.radius[i]
                    } else {
                        0.0
                    },
                    weight: self.weight[i],
                }
            });
        let chunks = self.particle_count().div_ceil(CHUNK).max(1) as u64;
        let mut chunk = Vec::with_capacity(CHUNK.min(self.particle_count()));
        for k in 0..chunks {
            chunk.clear();
            chunk.extend(own.by_ref().take(CHUNK));
            // The volume's particles passed its own checks: images fit the
            // box; what fails is the device.
            if let Err(e) = splatter.add(&chunk, 0, control) {
                return Some(Err(e));
            }
            if control.is_cancelled() {
                return Some(Err(ParticleError::Cancelled));
            }
            control.report(k + 1, chunks);
        }
        Some(splatter.finish())
    }
}
