//! The particle volume's orthographic projections: its particles through
//! the streaming splatter ([`crate::splat`]), the same code a projection
//! streamed from a file takes. Ghosts are left out: the splatter makes the
//! periodic images itself. Chunks are fixed in size, so the image has the
//! same bits for any thread count.

use voxless_core::{Camera, Cancelled, Control, PixelIntegral};

use crate::splat::{CHUNK, SplatParticle, Splatter};

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
        if self.settings.periodic.is_some() && !self.own_images {
            return None;
        }
        let mut splatter = Splatter::new(
            camera,
            width,
            height,
            self.settings.kernel,
            self.settings.periodic,
        )?
        .with_pixels(pixels);
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
            // The volume's particles passed its own checks: images fit the box.
            if splatter.add(&chunk, 0, control).is_err() || control.is_cancelled() {
                return Some(Err(Cancelled));
            }
            control.report(k + 1, chunks);
        }
        Some(Ok(splatter.finish()))
    }
}
