//! Projections on the GPU: the device side of the particle splatter
//! (see [`SplatDevice`]). Each chunk's plain splats are binned to
//! 16×16-pixel tiles on the CPU (a counting sort that keeps their order)
//! and summed by one workgroup per tile into an image that stays on the
//! device until the projection is finished.

use voxless_particles::splat::{DeviceImage, PlainSplat, SplatDevice};
use voxless_particles::{Kernel, ParticleError};

use crate::{Gpu, GpuError};

/// Pixels per tile side (the shader's workgroup size).
const TILE: u32 = 16;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    tiles_x: u32,
    sph: u32,
    last: f32,
    _pad: [u32; 3],
}

/// A [`PlainSplat`] as the shader reads it (16 words).
fn words(s: &PlainSplat) -> [u32; 16] {
    let f = |v: f32| v.to_bits();
    [
        f(s.cx),
        f(s.cy),
        f(s.ax),
        f(s.ay),
        f(s.scale),
        f(s.g_exp),
        f(s.g_erf),
        f(s.support2),
        f(s.pw2),
        f(s.ph2),
        s.rows[0],
        s.rows[1],
        s.cols[0],
        s.cols[1],
        0,
        0,
    ]
}

fn device_error(e: GpuError) -> ParticleError {
    ParticleError::Device(e.to_string())
}

impl SplatDevice for Gpu {
    fn begin(
        &self,
        width: u32,
        height: u32,
        kernel: Kernel,
    ) -> Result<Box<dyn DeviceImage>, ParticleError> {
        let bytes = 4 * width as u64 * height as u64;
        let image = self
            .zeroed("the projection image", bytes)
            .map_err(device_error)?;
        let table = kernel.sph_table().unwrap_or(&[0.0, 0.0]);
        let table = self
            .storage("the column table", table)
            .map_err(device_error)?;
        Ok(Box::new(GpuImage {
            gpu: self.clone(),
            width,
            height,
            sph: kernel.sph_table().is_some(),
            last: kernel.sph_table().map_or(0, |t| t.len() - 1) as f32,
            image,
            table,
        }))
    }
}

/// An image being summed on the GPU.
struct GpuImage {
    gpu: Gpu,
    width: u32,
    height: u32,
    sph: bool,
    /// The column table's last position (the Gaussians: unused).
    last: f32,
    image: wgpu::Buffer,
    table: wgpu::Buffer,
}

impl DeviceImage for GpuImage {
    fn add(&mut self, splats: &[PlainSplat]) -> Result<(), ParticleError> {
        if splats.is_empty() {
            return Ok(());
        }
        let tiles_x = self.width.div_ceil(TILE);
        let tiles_y = self.height.div_ceil(TILE);
        let (start, members) = bin(splats, tiles_x, tiles_y);
        let gpu = &self.gpu;
        let run = || -> Result<(), GpuError> {
            gpu.wait()?;
            let words: Vec<[u32; 16]> = splats.iter().map(words).collect();
            let splats = gpu.storage("the splats", &words)?;
            let start = gpu.storage("the tile lists", &start)?;
            let members = gpu.storage("the tile lists", &members)?;
            let params = gpu.uniform(
                "splat parameters",
                &Params {
                    width: self.width,
                    height: self.height,
                    tiles_x,
                    sph: self.sph as u32,
                    last: self.last,
                    _pad: [0; 3],
                },
            );
            let pipeline = gpu.pipeline_in(&gpu.splat, "splat", include_str!("splat.wgsl"), &[])?;
            // Queued: this chunk's sums run while the CPU places the next
            // one, which waits for them first (one chunk's buffers in
            // flight: the stream's memory stays bounded).
            gpu.run(
                pipeline,
                &[&params, &splats, &start, &members, &self.table, &self.image],
                [tiles_x, tiles_y, 1],
            )
        };
        run().map_err(device_error)
    }

    fn finish(self: Box<Self>) -> Result<Vec<f32>, ParticleError> {
        let pixels = self.width as usize * self.height as usize;
        self.gpu.read(&self.image, pixels).map_err(device_error)
    }
}

/// The splats of each tile, in order: tile `t`'s are
/// `members[start[t]..start[t + 1]]` (a counting sort).
fn bin(splats: &[PlainSplat], tiles_x: u32, tiles_y: u32) -> (Vec<u32>, Vec<u32>) {
    let tiles = (tiles_x * tiles_y) as usize;
    let span = |s: &PlainSplat| {
        let (x0, x1) = (s.cols[0] / TILE, (s.cols[1].max(1) - 1) / TILE);
        let (y0, y1) = (s.rows[0] / TILE, (s.rows[1].max(1) - 1) / TILE);
        (x0, x1.min(tiles_x - 1), y0, y1.min(tiles_y - 1))
    };
    let mut start = vec![0u32; tiles + 1];
    for s in splats {
        let (x0, x1, y0, y1) = span(s);
        for ty in y0..=y1 {
            for tx in x0..=x1 {
                start[(ty * tiles_x + tx) as usize + 1] += 1;
            }
        }
    }
    for t in 0..tiles {
        start[t + 1] += start[t];
    }
    let mut fill = start.clone();
    let mut members = vec![0u32; start[tiles] as usize];
    for (i, s) in splats.iter().enumerate() {
        let (x0, x1, y0, y1) = span(s);
        for ty in y0..=y1 {
            for tx in x0..=x1 {
                let t = (ty * tiles_x + tx) as usize;
                members[fill[t] as usize] = i as u32;
                fill[t] += 1;
            }
        }
    }
    (start, members)
}
