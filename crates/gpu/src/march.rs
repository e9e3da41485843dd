//! Renders on the GPU: a particle volume's emission–absorption, one pass
//! at a time (see the crate docs and `march.wgsl`).

use voxless_core::{Camera, Cancelled, Control, Range1};
use voxless_particles::{Classification, Kernel, ParticleVolume};
use voxless_render::device::{LatticeRay, device_unsupported, lattice_rays};
use voxless_render::{Film, RenderSettings};
use voxless_transfer::TransferFunction;

use crate::{Gpu, GpuError};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    n_particles: u32,
    cluster: u32,
    n_nodes: u32,
    kernel: u32,
    mode: u32,
    light_on: u32,
    early: f32,
    opacity_scale: f32,
    v_lo: f32,
    v_span: f32,
    a_lo: f32,
    a_span: f32,
    log_scale: u32,
    ambient: f32,
    light: [f32; 3],
    knots: u32,
}

/// The shader's kernel number.
fn kernel_id(k: Kernel) -> u32 {
    match k {
        Kernel::Gaussian3 | Kernel::Gaussian { .. } => 0,
        Kernel::CubicSpline => 1,
        Kernel::QuarticSpline => 2,
        Kernel::QuinticSpline => 3,
        Kernel::WendlandC2 => 4,
        Kernel::WendlandC4 => 5,
        Kernel::WendlandC6 => 6,
    }
}

/// Why `volume` cannot be rendered on the GPU with `settings`, if it
/// cannot.
pub fn unsupported(volume: &ParticleVolume, settings: &RenderSettings) -> Option<String> {
    if let Some(what) = device_unsupported(settings) {
        return Some(what.to_string());
    }
    if volume.periodic().is_some() {
        return Some("renders of a periodic box (--box)".to_string());
    }
    None
}

/// A particle volume and a transfer function uploaded for renders.
struct Uploaded {
    particles: wgpu::Buffer,
    attr: wgpu::Buffer,
    nodes: wgpu::Buffer,
    lut: wgpu::Buffer,
    params: Params,
    nominal_dt: f32,
}

impl Gpu {
    /// Renders `settings.spp` passes of `volume` into a film, as the CPU's
    /// `voxless_render::render_film` does (within 1/255 per channel; see
    /// the crate docs). Progress is reported per pass; `Ok(Err(Cancelled))`
    /// when `control` was cancelled.
    pub fn render_film(
        &self,
        volume: &ParticleVolume,
        camera: &Camera,
        tf: &TransferFunction,
        settings: &RenderSettings,
        control: &Control,
    ) -> Result<Result<Film, Cancelled>, GpuError> {
        self.render_passes(volume, camera, tf, settings, control, &mut |_| true)
    }

    /// [`Gpu::render_film`] pass by pass: after each pass `on_pass(&film)`
    /// sees it and returns whether to go on (the viewer's progressive
    /// passes).
    pub fn render_passes(
        &self,
        volume: &ParticleVolume,
        camera: &Camera,
        tf: &TransferFunction,
        settings: &RenderSettings,
        control: &Control,
        on_pass: &mut dyn FnMut(&Film) -> bool,
    ) -> Result<Result<Film, Cancelled>, GpuError> {
        if let Some(what) = unsupported(volume, settings) {
            return Err(GpuError::Unsupported(what));
        }
        let up = self.upload(volume, tf, settings)?;
        let pass_bytes = 68 * settings.width as u64 * settings.height as u64;
        let held = [&up.particles, &up.attr, &up.nodes, &up.lut]
            .iter()
            .map(|b| b.size())
            .sum::<u64>();
        self.last_bytes
            .store(held + pass_bytes, std::sync::atomic::Ordering::Relaxed);
        let mut film = Film::new(settings.width, settings.height);
        for sample in 0..settings.spp {
            if control.is_cancelled() {
                return Ok(Err(Cancelled));
            }
            let rays = lattice_rays(volume, camera, settings, up.nominal_dt, sample);
            let pixels = self.pass(&up, &rays)?;
            film.add_pass(&pixels);
            control.report(sample as u64 + 1, settings.spp as u64);
            if !on_pass(&film) {
                break;
            }
        }
        Ok(Ok(film))
    }

    fn upload(
        &self,
        volume: &ParticleVolume,
        tf: &TransferFunction,
        settings: &RenderSettings,
    ) -> Result<Uploaded, GpuError> {
        let d = volume.device_particles();
        let nodes: Vec<[u32; 8]> = d
            .bvh
            .nodes()
            .iter()
            .map(|n| {
                let f = |v: f32| v.to_bits();
                [
                    f(n.min[0]),
                    f(n.min[1]),
                    f(n.min[2]),
                    f(n.max[0]),
                    f(n.max[1]),
                    f(n.max[2]),
                    n.primitive(),
                    n.is_leaf() as u32,
                ]
            })
            .collect();
        let attr_range = settings.attribute_range.unwrap_or(Range1::new(0.0, 1.0));
        let (mode, attr): (u32, Vec<f32>) = match (d.attribute, volume.settings().classification) {
            (None, _) => (0, Vec::new()),
            (Some(a), Classification::Post) => (1, a.to_vec()),
            // Each particle's colour, as the CPU's prepared context
            // classifies it.
            (Some(_), Classification::Pre) => (
                2,
                volume
                    .preclassify(&|s| tf.color(attr_range.normalize(s)))
                    .iter()
                    .flat_map(|c| c.to_array())
                    .collect(),
            ),
        };
        let knots = tf.knots();
        let light = settings.light;
        let params = Params {
            width: settings.width,
            height: settings.height,
            n_particles: d.packed.len() as u32,
            cluster: d.cluster_size as u32,
            n_nodes: nodes.len() as u32,
            kernel: kernel_id(volume.settings().kernel),
            mode,
            light_on: light.is_some() as u32,
            early: settings.early_termination,
            opacity_scale: settings.opacity_scale,
            v_lo: settings.value_range.lo,
            v_span: settings.value_range.span(),
            a_lo: attr_range.lo,
            a_span: attr_range.span(),
            log_scale: settings.log_scale as u32,
            ambient: light.map_or(0.0, |l| l.ambient),
            light: light.map_or([0.0; 3], |l| l.direction.to_array()),
            knots: knots.len() as u32,
        };
        Ok(Uploaded {
            particles: self.storage("the particles", &d.packed)?,
            attr: self.storage("the particle attribute", &attr)?,
            nodes: self.storage("the BVH", &nodes)?,
            lut: self.storage("the transfer function", &knots)?,
            params,
            nominal_dt: d.nominal_dt,
        })
    }

    /// One pass over `rays` (one per pixel, row-major): dispatches of a
    /// bounded amount of work each (see `march.wgsl`, BUDGET) until every
    /// ray is done.
    fn pass(&self, up: &Uploaded, rays: &[LatticeRay]) -> Result<Vec<[f32; 4]>, GpuError> {
        let words: Vec<[f32; 12]> = rays
            .iter()
            .map(|r| {
                [
                    r.origin[0],
                    r.origin[1],
                    r.origin[2],
                    r.t0,
                    r.dir[0],
                    r.dir[1],
                    r.dir[2],
                    r.dt,
                    r.lo,
                    r.hi,
                    0.0,
                    0.0,
                ]
            })
            .collect();
        let n = rays.len() as u64;
        let rays_buf = self.storage("the rays", &words)?;
        let out = self.zeroed("the image", 16 * n)?;
        let next = self.zeroed("the rays' progress", 4 * n)?;
        let pending = self.zeroed("the count of unfinished rays", 4)?;
        let params = self.uniform("render parameters", &up.params);
        let [wx, wy] = self.march_shape;
        let shape = [
            ("WX", wx as f64),
            ("WY", wy as f64),
            ("BUDGET", self.march_budget as f64),
        ];
        let pipeline =
            self.pipeline_in(&self.march, "march", include_str!("march.wgsl"), &shape)?;
        let (w, h) = (up.params.width, up.params.height);
        let bind = [
            &params,
            &rays_buf,
            &up.particles,
            &up.attr,
            &up.nodes,
            &up.lut,
            &out,
            &next,
            &pending,
        ];
        // Every dispatch moves each unfinished ray on by at least one
        // cell, so the rays' cells bound the dispatches.
        let most = rays.iter().map(cells).max().unwrap_or(0) + 2;
        for _ in 0..most {
            self.queue.write_buffer(&pending, 0, &[0; 4]);
            self.run(pipeline, &bind, [w.div_ceil(wx), h.div_ceil(wy), 1])?;
            let left = self.read::<u32>(&pending, 1)?;
            if left.first().copied().unwrap_or(0) == 0 {
                return self.read::<[f32; 4]>(&out, rays.len());
            }
        }
        Err(self.failed("the march did not finish (a ray never advanced)"))
    }
}

/// The lattice cells of `r` (as the shader bounds them).
fn cells(r: &LatticeRay) -> u64 {
    if r.lo < r.hi && r.dt > 0.0 {
        ((r.hi - r.t0) / r.dt + 2.0).min(1e8) as u64
    } else {
        0
    }
}
