//! The particle volume's orthographic projections: its particles through
//! the streaming splatter ([`crate::splat`]), the same code a projection
//! streamed from a file takes. Ghosts are left out: the splatter makes the
//! periodic images itself. Chunks are fixed in size, so the image has the
//! same bits for any thread count.

use voxless_core::{Camera, Cancelled, Control};

use crate::splat::{CHUNK, SplatParticle, Splatter};

use super::ParticleVolume;

impl ParticleVolume {
    /// The column density through every pixel centre of an orthographic
    /// `camera` (row-major, row 0 at the top); `None` for other cameras,
    /// and for a part of a decomposed periodic set (its images from other
    /// parts carry no shifts; the per-pixel path clips them).
    pub(super) fn splat_projection(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        control: &Control,
    ) -> Option<Result<Vec<f32>, Cancelled>> {
        if self.settings.periodic.is_some() && self.shifts.is_empty() && self.ghosts > 0 {
            return None;
        }
        let mut splatter = Splatter::new(
            camera,
            width,
            height,
            self.settings.kernel,
            self.settings.periodic,
        )?;
        let own: Vec<usize> = (0..self.packed.len())
            .filter(|&i| !self.is_ghost(i))
            .collect();
        let chunks = own.len().div_ceil(CHUNK).max(1) as u64;
        let mut chunk = Vec::with_capacity(CHUNK.min(own.len()));
        for (k, part) in own.chunks(CHUNK).enumerate() {
            chunk.clear();
            chunk.extend(part.iter().map(|&i| SplatParticle {
                center: self.packed[i].center,
                radius: if self.packed[i].support2 > 0.0 {
                    self.radius[i]
                } else {
                    0.0
                },
                weight: self.weight[i],
            }));
            // The volume's particles passed its own checks: images fit the box.
            if splatter.add(&chunk, 0, control).is_err() || control.is_cancelled() {
                return Some(Err(Cancelled));
            }
            control.report(k as u64 + 1, chunks);
        }
        Some(Ok(splatter.finish()))
    }
}
