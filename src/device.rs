//! Where renders and projections run: the CPU, or the GPU backend (cargo
//! feature `gpu`, crate `voxless-gpu`). Every front-end chooses with the
//! same [`DeviceChoice`] (`--device cpu|gpu|auto`, Python `device=`), and the
//! scene is the same either way: the device gets the camera, transfer
//! function and settings the CPU would.
//!
//! - `cpu` (the default): the CPU integrators.
//! - `gpu`: the GPU, or an error — no adapter (naming what to install), a
//!   build without the feature, or a render the GPU does not do yet
//!   (naming the setting).
//! - `auto`: the GPU where there is one and it does the render, else the
//!   CPU, with a note saying which and why.

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use voxless_core::{Camera, Cancelled, Control, PixelIntegral};
use voxless_render::{Film, RenderSettings};
use voxless_transfer::TransferFunction;

use crate::{AnyVolume, Resolved, SceneError};

/// Which device a front-end asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DeviceChoice {
    #[default]
    Cpu,
    Gpu,
    Auto,
}

impl FromStr for DeviceChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "cpu" => Ok(DeviceChoice::Cpu),
            "gpu" => Ok(DeviceChoice::Gpu),
            "auto" => Ok(DeviceChoice::Auto),
            _ => Err(format!("unknown device {s:?}: cpu, gpu or auto")),
        }
    }
}

impl fmt::Display for DeviceChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DeviceChoice::Cpu => "cpu",
            DeviceChoice::Gpu => "gpu",
            DeviceChoice::Auto => "auto",
        })
    }
}

/// An opened device (see the module docs).
#[derive(Clone)]
pub struct Device {
    choice: DeviceChoice,
    /// See [`Device::last_on_gpu`].
    on_gpu: Arc<AtomicBool>,
    #[cfg(feature = "gpu")]
    gpu: Option<voxless_gpu::Gpu>,
}

impl fmt::Debug for Device {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Device({}: {})", self.choice, self.name())
    }
}

/// The adapters the GPU backend finds, one line each (`voxless info
/// --devices`); a line saying why there are none.
pub fn adapters() -> Vec<String> {
    #[cfg(feature = "gpu")]
    {
        let found: Vec<String> = voxless_gpu::adapters()
            .iter()
            .map(|a| a.to_string())
            .collect();
        if found.is_empty() {
            vec![voxless_gpu::GpuError::NoAdapter("none listed".into()).to_string()]
        } else {
            found
        }
    }
    #[cfg(not(feature = "gpu"))]
    vec![NO_FEATURE.to_string()]
}

#[cfg(not(feature = "gpu"))]
const NO_FEATURE: &str = "this voxless was built without the GPU backend: \
    build with `cargo build --release --features gpu`";

impl Device {
    /// The CPU.
    pub fn cpu() -> Device {
        Device {
            choice: DeviceChoice::Cpu,
            on_gpu: Default::default(),
            #[cfg(feature = "gpu")]
            gpu: None,
        }
    }

    /// Opens the device `choice` names; with `auto`, a note when the CPU
    /// stands in for a missing GPU.
    pub fn open(choice: DeviceChoice) -> Result<(Device, Option<String>), SceneError> {
        let mut device = Device::cpu();
        device.choice = choice;
        if choice == DeviceChoice::Cpu {
            return Ok((device, None));
        }
        #[cfg(feature = "gpu")]
        match voxless_gpu::Gpu::new() {
            Ok(gpu) => {
                device.gpu = Some(gpu);
                Ok((device, None))
            }
            Err(e) if choice == DeviceChoice::Gpu => {
                Err(SceneError::setting("device", e.to_string()))
            }
            Err(e) => Ok((device, Some(format!("device auto: on the CPU ({e})")))),
        }
        #[cfg(not(feature = "gpu"))]
        match choice {
            DeviceChoice::Gpu => Err(SceneError::setting("device", NO_FEATURE)),
            _ => Ok((
                device,
                Some(format!("device auto: on the CPU ({NO_FEATURE})")),
            )),
        }
    }

    /// What was asked for.
    pub fn choice(&self) -> DeviceChoice {
        self.choice
    }

    /// The device in messages: "CPU" or the adapter.
    pub fn name(&self) -> String {
        #[cfg(feature = "gpu")]
        if let Some(g) = &self.gpu {
            return format!("GPU {}", g.adapter());
        }
        "CPU".to_string()
    }

    /// Whether work goes to a GPU at all.
    pub fn is_gpu(&self) -> bool {
        #[cfg(feature = "gpu")]
        return self.gpu.is_some();
        #[cfg(not(feature = "gpu"))]
        false
    }

    /// The GPU for a render of `volume` with `settings`: `Ok(None)` for the
    /// CPU (asked for, or standing in under `auto`, with the reason in
    /// `notes`); an error when `gpu` was asked for and it cannot do it.
    #[cfg(feature = "gpu")]
    fn gpu_for_render<'a>(
        &'a self,
        volume: &'a AnyVolume,
        settings: &RenderSettings,
        notes: &mut Vec<String>,
    ) -> Result<Option<(&'a voxless_gpu::Gpu, &'a voxless_particles::ParticleVolume)>, SceneError>
    {
        let Some(gpu) = &self.gpu else {
            return Ok(None);
        };
        let why = match volume {
            AnyVolume::Particles(v) => match voxless_gpu::unsupported(v, settings) {
                None => return Ok(Some((gpu, v))),
                Some(what) => what,
            },
            other => format!(
                "{} volumes (the GPU backend renders particles)",
                other.kind()
            ),
        };
        if self.choice == DeviceChoice::Gpu {
            return Err(SceneError::setting(
                "device",
                voxless_gpu::GpuError::Unsupported(why).to_string(),
            ));
        }
        notes.push(format!(
            "device auto: rendering on the CPU (not on the GPU yet: {why})"
        ));
        Ok(None)
    }

    /// Renders `volume` with `view` (all `spp` passes) on this device into
    /// a film; `notes` gets what a front-end should say (the CPU standing
    /// in). The outer error is the device's; the inner, a cancelled render.
    pub fn render_film(
        &self,
        volume: &AnyVolume,
        view: &Resolved,
        control: &Control,
        notes: &mut Vec<String>,
    ) -> Result<Result<Film, Cancelled>, SceneError> {
        let (camera, tf, settings) = (&view.camera, &view.tf, &view.settings);
        self.render_passes(volume, camera, tf, settings, control, notes, &mut |_| true)
    }

    /// Renders pass by pass on this device: after each pass `on_pass(&film)`
    /// sees it and returns whether to go on. The outer error is the
    /// device's (or a render `gpu` cannot do); the inner, a cancelled render.
    #[allow(clippy::too_many_arguments)]
    pub fn render_passes(
        &self,
        volume: &AnyVolume,
        camera: &Camera,
        tf: &TransferFunction,
        settings: &RenderSettings,
        control: &Control,
        notes: &mut Vec<String>,
        on_pass: &mut dyn FnMut(&Film) -> bool,
    ) -> Result<Result<Film, Cancelled>, SceneError> {
        self.on_gpu.store(false, Ordering::Relaxed);
        #[cfg(feature = "gpu")]
        if let Some((gpu, v)) = self.gpu_for_render(volume, settings, notes)? {
            self.on_gpu.store(true, Ordering::Relaxed);
            return gpu
                .render_passes(v, camera, tf, settings, control, on_pass)
                .map_err(|e| SceneError::setting("device", e.to_string()));
        }
        let _ = notes;
        Ok(volume.render_passes(camera, tf, settings, control, on_pass))
    }

    /// Whether the last render or projection on this device ran on the
    /// GPU (`auto` may have put the CPU in; a front-end's report says
    /// where it ran).
    pub fn last_on_gpu(&self) -> bool {
        self.on_gpu.load(Ordering::Relaxed)
    }

    /// The GPU memory the last render on this device held in buffers
    /// (particles, BVH, one pass's rays and image); `None` on the CPU.
    pub fn gpu_bytes(&self) -> Option<u64> {
        #[cfg(feature = "gpu")]
        if let Some(g) = &self.gpu {
            return Some(g.last_render_bytes());
        }
        None
    }

    /// The device that sums a particle projection's splats, when it is
    /// the GPU.
    pub fn splat_device(&self) -> Option<&dyn voxless_particles::splat::SplatDevice> {
        #[cfg(feature = "gpu")]
        if let Some(g) = &self.gpu {
            return Some(g);
        }
        None
    }

    /// An error when `gpu` was asked for and a projection of `volume`
    /// cannot use it (particle projections of whole lines splat; `slab`
    /// names what keeps this one from it); under `auto`, the note saying
    /// the CPU stands in.
    pub fn check_projection(
        &self,
        volume: &AnyVolume,
        slab: Option<&str>,
        notes: &mut Vec<String>,
    ) -> Result<(), SceneError> {
        self.on_gpu.store(false, Ordering::Relaxed);
        if !self.is_gpu() {
            return Ok(());
        }
        let why = match (volume, slab) {
            (AnyVolume::Particles(_), None) => {
                self.on_gpu.store(true, Ordering::Relaxed);
                return Ok(());
            }
            (AnyVolume::Particles(_), Some(what)) => what.to_string(),
            (other, _) => format!(
                "{} projections (the GPU backend projects particles)",
                other.kind()
            ),
        };
        if self.choice == DeviceChoice::Gpu {
            return Err(SceneError::setting(
                "device",
                format!("not on the GPU yet: {why}"),
            ));
        }
        notes.push(format!(
            "device auto: projecting on the CPU (not on the GPU yet: {why})"
        ));
        Ok(())
    }
}

/// A particle volume's projection with its splats summed on `device`
/// (`None`: not a splatted projection, take the volume's own path); the
/// outer error is the device's, the inner a cancelled projection.
pub(crate) fn project_particles(
    volume: &AnyVolume,
    camera: &voxless_core::Camera,
    (w, h): (u32, u32),
    pixels: Option<PixelIntegral>,
    device: &Device,
    control: &Control,
) -> Option<Result<Result<Vec<f32>, Cancelled>, SceneError>> {
    let (AnyVolume::Particles(v), Some(d)) = (volume, device.splat_device()) else {
        return None;
    };
    let pixels = pixels.unwrap_or(v.settings().pixels);
    Some(
        match v.project_on(camera, w, h, pixels, Some(d), control)? {
            Ok(image) => Ok(Ok(image)),
            Err(voxless_particles::ParticleError::Cancelled) => Ok(Err(Cancelled)),
            Err(e) => Err(SceneError::setting("device", e.to_string())),
        },
    )
}
