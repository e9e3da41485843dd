//! The GPU backend: particle volumes rendered and projected with compute
//! shaders (WGSL through wgpu: Vulkan, Metal or DirectX 12 — one code path
//! for every vendor, and Mesa's software Vulkan, lavapipe, on machines
//! without a GPU).
//!
//! **The model.** A device integrator takes the same camera, transfer
//! function and settings as the CPU and gives the same image: within
//! 1/255 per channel for renders, 1e-5 of the peak for projections (f32
//! summation order and f32 arithmetic where the CPU uses f64 are the only
//! differences). It gets there by doing the CPU's arithmetic, not an
//! approximation of it:
//!
//! - **Renders** ([`Gpu::render_pass`]): the CPU hands each pixel sample's
//!   ray, span and first lattice boundary
//!   ([`voxless_render::device::LatticeRay`]), so rays, jitter and sample
//!   positions are the CPU's; each GPU thread walks its ray's lattice
//!   cells, evaluates Φ and Θ at the cell midpoints by a point query of the
//!   volume's BVH (uploaded as the CPU built it, clusters of particles in
//!   Hilbert order, as the attribute-aware RBF paper queries it),
//!   classifies through the transfer function's tables (post- or
//!   pre-classification), corrects opacity for the segment length, shades
//!   with the analytic gradient when a light is set, and stops at the
//!   early-termination opacity.
//! - **Projections** ([`Gpu`] as a [`SplatDevice`]): the CPU's splatter
//!   places each particle's images (periodic boxes included) and the GPU
//!   sums their columns into the pixel centres they cover — the O(particles
//!   × pixels) part — from the same column tables, a 16×16-pixel tile per
//!   workgroup over the splats binned to it.
//!
//! What the GPU does not do yet is refused with an error naming it
//! ([`voxless_render::device::device_unsupported`]): single scattering,
//! iso-surfaces, meshes, ambient occlusion, mirrors, periodic renders and
//! data kinds other than particles. The BVH is built on the CPU and
//! uploaded (the paper builds it on the GPU: the next step).
//!
//! **Invariants.** Buffers are checked against the adapter's limits before
//! they are made (an error names the limit); a device lost or a shader
//! error is an error ([`GpuError`]), and every wait has a timeout, so a
//! render never hangs on a lost device.

mod march;
mod splat;

use std::sync::Mutex;
use std::time::Duration;

pub use march::unsupported;
pub use voxless_particles::splat::SplatDevice;

/// What went wrong on the GPU side.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter found ({0}): install your GPU's Vulkan driver, or Mesa's software \
         Vulkan (Debian/Ubuntu: apt-get install mesa-vulkan-drivers libvulkan1), or render \
         with --device cpu"
    )]
    NoAdapter(String),
    #[error("the GPU ({adapter}) refused the device: {message}")]
    NoDevice { adapter: String, message: String },
    #[error(
        "{what}: {bytes} bytes in one GPU buffer, beyond the {limit} the adapter \
         ({adapter}) allows ({limit_name}): use --device cpu, a smaller image or fewer \
         particles"
    )]
    TooLarge {
        what: &'static str,
        bytes: u64,
        limit: u64,
        limit_name: &'static str,
        adapter: String,
    },
    #[error(
        "the image needs {groups:?} workgroups, beyond the {limit} a dimension the adapter \
         ({adapter}) allows (max_compute_workgroups_per_dimension): use a smaller image or \
         --device cpu"
    )]
    TooManyGroups {
        groups: [u32; 3],
        limit: u32,
        adapter: String,
    },
    #[error("the GPU ({adapter}) failed: {message}")]
    Failed { adapter: String, message: String },
    #[error("not on the GPU yet: {0} (use --device cpu, or --device auto to fall back)")]
    Unsupported(String),
}

/// One adapter wgpu found.
#[derive(Clone, Debug)]
pub struct AdapterInfo {
    pub name: String,
    /// "Vulkan", "Metal", "Dx12".
    pub backend: String,
    /// "discrete GPU", "integrated GPU", "CPU (software)", …
    pub kind: String,
    pub driver: String,
}

impl std::fmt::Display for AdapterInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({}, {}", self.name, self.backend, self.kind)?;
        if !self.driver.is_empty() {
            write!(f, ", {}", self.driver)?;
        }
        write!(f, ")")
    }
}

fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
}

fn info_of(a: &wgpu::Adapter) -> AdapterInfo {
    let i = a.get_info();
    AdapterInfo {
        name: i.name,
        backend: format!("{:?}", i.backend),
        kind: match i.device_type {
            wgpu::DeviceType::DiscreteGpu => "discrete GPU",
            wgpu::DeviceType::IntegratedGpu => "integrated GPU",
            wgpu::DeviceType::VirtualGpu => "virtual GPU",
            wgpu::DeviceType::Cpu => "CPU (software)",
            wgpu::DeviceType::Other => "other",
        }
        .to_string(),
        driver: i.driver,
    }
}

/// Every adapter found (`voxless info --devices`).
pub fn adapters() -> Vec<AdapterInfo> {
    let instance = instance();
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(info_of)
        .collect()
}

/// How long one submission may take before the device counts as lost.
const TIMEOUT: Duration = Duration::from_secs(600);

/// A device and its queue, with the pipelines made on first use. Clones
/// share them.
#[derive(Clone)]
pub struct Gpu {
    inner: std::sync::Arc<Inner>,
}

impl std::ops::Deref for Gpu {
    type Target = Inner;
    fn deref(&self) -> &Inner {
        &self.inner
    }
}

/// What a [`Gpu`] holds.
pub struct Inner {
    device: wgpu::Device,
    queue: wgpu::Queue,
    info: AdapterInfo,
    limits: wgpu::Limits,
    splat: std::sync::OnceLock<wgpu::ComputePipeline>,
    march: std::sync::OnceLock<wgpu::ComputePipeline>,
    /// Set by the device-lost callback.
    lost: std::sync::Arc<Mutex<Option<String>>>,
    /// The render's workgroup shape and per-dispatch loop budget (see
    /// `march.wgsl`).
    march_shape: [u32; 2],
    march_budget: u32,
    /// Bytes of the buffers the last render held (see
    /// [`Inner::last_render_bytes`]).
    last_bytes: std::sync::atomic::AtomicU64,
}

impl Gpu {
    /// The best adapter wgpu finds (a discrete GPU before an integrated
    /// one before a software one), or an error saying what to install.
    pub fn new() -> Result<Gpu, GpuError> {
        let instance = instance();
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = info_of(&adapter);
        let limits = adapter.limits();
        let software = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("voxless"),
            required_features: wgpu::Features::empty(),
            // As large as the adapter allows: the buffers are sized by the
            // data and checked against these.
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoDevice {
            adapter: info.to_string(),
            message: e.to_string(),
        })?;
        let lost = std::sync::Arc::new(Mutex::new(None));
        let flag = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut l) = flag.lock() {
                *l = Some(format!("device lost ({reason:?}): {message}"));
            }
        });
        Ok(Gpu {
            inner: std::sync::Arc::new(Inner {
                device,
                queue,
                info,
                limits,
                splat: Default::default(),
                march: Default::default(),
                lost,
                march_shape: if software { [1, 64] } else { [8, 8] },
                // Mesa's limit of 65,535 loop iterations per SIMD group of
                // eight, with a margin for one sample's walk.
                march_budget: if software { 6144 } else { 262_144 },
                last_bytes: Default::default(),
            }),
        })
    }
}

impl Inner {
    /// The adapter this device is on.
    pub fn adapter(&self) -> &AdapterInfo {
        &self.info
    }

    fn failed(&self, message: impl Into<String>) -> GpuError {
        GpuError::Failed {
            adapter: self.info.to_string(),
            message: message.into(),
        }
    }

    /// The GPU memory the last render's buffers took: particles, attribute,
    /// BVH, transfer function, one pass's rays and image.
    pub fn last_render_bytes(&self) -> u64 {
        self.last_bytes.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The most bytes one storage buffer binding may hold on this adapter.
    pub fn max_buffer_bytes(&self) -> u64 {
        self.limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
    }

    /// An error unless `bytes` fit one storage buffer binding.
    fn check_size(&self, what: &'static str, bytes: u64) -> Result<(), GpuError> {
        let limit = self.max_buffer_bytes();
        if bytes > limit {
            return Err(GpuError::TooLarge {
                what,
                bytes,
                limit,
                limit_name: "max_storage_buffer_binding_size",
                adapter: self.info.to_string(),
            });
        }
        Ok(())
    }

    /// A read-only storage buffer holding `data` (bindings may not be
    /// empty: an empty slice gets 16 zero bytes).
    fn storage<T: bytemuck::Pod>(
        &self,
        what: &'static str,
        data: &[T],
    ) -> Result<wgpu::Buffer, GpuError> {
        use wgpu::util::DeviceExt;
        let bytes: &[u8] = bytemuck::cast_slice(data);
        self.check_size(what, bytes.len() as u64)?;
        let contents: &[u8] = if bytes.is_empty() { &[0; 16] } else { bytes };
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(what),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            }))
    }

    /// A writable storage buffer of `bytes` zeros (checked before it is
    /// made).
    fn zeroed(&self, what: &'static str, bytes: u64) -> Result<wgpu::Buffer, GpuError> {
        self.check_size(what, bytes)?;
        // wgpu zeroes new buffers.
        Ok(self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(what),
            size: bytes.max(16),
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        }))
    }

    fn uniform<T: bytemuck::Pod>(&self, what: &'static str, value: &T) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(what),
                contents: bytemuck::bytes_of(value),
                usage: wgpu::BufferUsages::UNIFORM,
            })
    }

    /// A compute pipeline from WGSL `source` (entry point `main`, its
    /// override `constants` set), with shader errors returned rather than
    /// raised.
    fn pipeline(
        &self,
        label: &'static str,
        source: &str,
        constants: &[(&str, f64)],
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = self
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                cache: None,
            });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(self.failed(format!("the {label} shader: {e}")));
        }
        Ok(pipeline)
    }

    /// The pipeline in `slot`, made from `source` on first use.
    fn pipeline_in<'a>(
        &self,
        slot: &'a std::sync::OnceLock<wgpu::ComputePipeline>,
        label: &'static str,
        source: &str,
        constants: &[(&str, f64)],
    ) -> Result<&'a wgpu::ComputePipeline, GpuError> {
        if let Some(p) = slot.get() {
            return Ok(p);
        }
        let p = self.pipeline(label, source, constants)?;
        Ok(slot.get_or_init(|| p))
    }

    /// Runs `pipeline` over `groups` workgroups with `buffers` bound in
    /// order (queued: [`Inner::read`] waits for it); errors on a
    /// validation error.
    fn run(
        &self,
        pipeline: &wgpu::ComputePipeline,
        buffers: &[&wgpu::Buffer],
        groups: [u32; 3],
    ) -> Result<(), GpuError> {
        let max = self.limits.max_compute_workgroups_per_dimension;
        if groups.iter().any(|&g| g > max) {
            return Err(GpuError::TooManyGroups {
                groups,
                limit: max,
                adapter: self.info.to_string(),
            });
        }
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let layout = pipeline.get_bind_group_layout(0);
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &layout,
            entries: &entries,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
        }
        self.queue.submit([encoder.finish()]);
        match pollster::block_on(scope.pop()) {
            Some(e) => Err(self.failed(e.to_string())),
            None => Ok(()),
        }
    }

    /// Waits for the work queued so far; errors on a lost device or a
    /// timeout.
    fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(TIMEOUT),
            })
            .map_err(|e| self.failed(format!("waiting for the GPU: {e}")))?;
        match self.lost.lock().ok().and_then(|l| l.clone()) {
            Some(lost) => Err(self.failed(lost)),
            None => Ok(()),
        }
    }

    /// The first `len` elements of `T` of `buffer`, once the work queued
    /// before is done; errors on a lost device or a timeout.
    fn read<T: bytemuck::Pod>(
        &self,
        buffer: &wgpu::Buffer,
        len: usize,
    ) -> Result<Vec<T>, GpuError> {
        let bytes = (len * std::mem::size_of::<T>()) as u64;
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: bytes.max(4),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        if bytes > 0 {
            encoder.copy_buffer_to_buffer(buffer, 0, &readback, 0, bytes);
        }
        self.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        readback.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        match rx.recv_timeout(Duration::from_secs(5)) {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(self.failed(format!("reading the result: {e}"))),
            Err(_) => return Err(self.failed("the result never came back")),
        }
        let view = readback
            .slice(..)
            .get_mapped_range()
            .map_err(|e| self.failed(format!("reading the result: {e}")))?;
        let data: Vec<T> = bytemuck::cast_slice(&view[..bytes as usize]).to_vec();
        drop(view);
        readback.unmap();
        Ok(data)
    }
}
