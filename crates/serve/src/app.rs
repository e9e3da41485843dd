//! The server's shared state: the scene it started with, the loaded
//! volumes every tab shares, the access token, and the latest view (what
//! `/frame.png` renders).

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use voxless::autorange::Probe;
use voxless::{AnyVolume, Resolved, SceneDesc, SceneError, WorldFrame};

/// A loaded volume, where its coordinates sit in the world, and the notes
/// its loading made.
pub struct Loaded {
    pub volume: AnyVolume,
    pub frame: WorldFrame,
    pub notes: Vec<String>,
    /// The field probe the default value range, opacity and framing come
    /// from, with the clip box it was taken in: probing the data costs
    /// more than a coarse image, and camera moves do not change it.
    probe: Mutex<Option<KeptProbe>>,
}

/// A probe and the world clip box (if any) it was taken in.
type KeptProbe = (Option<[f64; 6]>, Arc<Probe>);

impl Loaded {
    pub fn new(loaded: voxless::Loaded) -> Loaded {
        Loaded {
            volume: loaded.volume,
            frame: loaded.frame,
            notes: loaded.notes,
            probe: Mutex::new(None),
        }
    }

    /// [`voxless::resolve_in`] of `desc` for this volume, probing the field
    /// once per clip box.
    pub fn resolve(&self, desc: &SceneDesc, base: &Path) -> Result<Resolved, SceneError> {
        let clip = desc.render.clip;
        let probe = {
            let mut kept = self.probe.lock().unwrap_or_else(|e| e.into_inner());
            match kept.as_ref() {
                Some((c, p)) if *c == clip => p.clone(),
                _ => {
                    let local = clip.map(|c| self.frame.box_to_local(c));
                    let p = Arc::new(Probe::of(&self.volume, local.as_ref()));
                    *kept = Some((clip, p.clone()));
                    p
                }
            }
        };
        voxless::resolve_with(&self.volume, &self.frame, desc, base, Some(&probe), None)
    }
}

/// The outcome of one load, shared by everyone who asked for it.
type LoadSlot = Arc<OnceLock<Result<Arc<Loaded>, String>>>;

/// Loaded volumes keyed by the data part of a description and the frame:
/// tabs viewing the same data share one immutable volume; a changed radius
/// scale, AMR field or time step loads another. The most recently used few
/// are kept.
pub struct Volumes {
    entries: Mutex<VecDeque<(String, LoadSlot)>>,
    capacity: usize,
}

impl Volumes {
    pub fn new(capacity: usize) -> Self {
        Volumes {
            entries: Mutex::new(VecDeque::new()),
            capacity: capacity.max(1),
        }
    }

    /// The key of `desc`'s data at `frame`: its data tables as TOML.
    pub fn key(desc: &SceneDesc, frame: usize) -> String {
        let data = SceneDesc {
            particles: desc.particles.clone(),
            amr: desc.amr.clone(),
            tets: desc.tets.clone(),
            ..Default::default()
        };
        format!(
            "{}\nframe = {frame}",
            voxless::scene_toml(&data).unwrap_or_default()
        )
    }

    /// Whether `desc`'s data at `frame` is loaded (or being loaded).
    pub fn contains(&self, desc: &SceneDesc, frame: usize) -> bool {
        let key = Self::key(desc, frame);
        self.lock().iter().any(|(k, _)| *k == key)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, VecDeque<(String, LoadSlot)>> {
        self.entries.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The volume of `desc`'s data at `frame` (the `frame`-th of the
    /// series, whatever number its file carries), loading it (once, however
    /// many ask at the same time) when it is not kept. Blocks: call it off
    /// the async runtime.
    pub fn get(&self, desc: &SceneDesc, base: &Path, frame: usize) -> Result<Arc<Loaded>, String> {
        let key = Self::key(desc, frame);
        let slot = {
            let mut entries = self.lock();
            let slot = match entries.iter().position(|(k, _)| *k == key) {
                Some(i) => entries.remove(i).map(|e| e.1).unwrap_or_default(),
                None => LoadSlot::default(),
            };
            // Most recent at the front; the least recent falls off the end.
            entries.push_front((key, slot.clone()));
            entries.truncate(self.capacity);
            slot
        };
        slot.get_or_init(|| {
            // The page counts frames 0..frames; files of a sequence are
            // numbered by their names (0, 250, … for PySPH outputs).
            let number = voxless::frame_numbers(desc, base)
                .ok()
                .and_then(|n| n.get(frame).copied())
                .unwrap_or(frame);
            // Tessellations get their coarser levels of detail: the coarse
            // images draw from them (a tessellation's render costs its
            // tets, whatever the image size).
            let mut desc = desc.clone();
            if let Some(t) = desc.tets.as_mut() {
                t.lod_levels.get_or_insert(COARSE_LOD_LEVELS);
            }
            voxless::load(&desc, base, number)
                .map(|l| {
                    // A large particle set's preview (its coarse images) is
                    // merged now, not on the first camera move.
                    if let voxless::AnyVolume::Particles(v) = &l.volume {
                        let _ = v.preview();
                    }
                    Arc::new(Loaded::new(l))
                })
                .map_err(|e| e.to_string())
        })
        .clone()
    }
}

/// Levels of detail a tessellation is loaded with for the coarse images
/// (the coarsest holds 1/512 of the tets; the three together 1/7 more memory).
const COARSE_LOD_LEVELS: usize = 3;

/// Everything the tabs share.
pub struct App {
    /// Directory relative paths of the scene are relative to.
    pub base: PathBuf,
    /// Where full-resolution passes render (see [`crate::Options::device`]).
    pub device: voxless::device::Device,
    /// The scene the server started with (every tab's first view; the
    /// page's reset goes back to its camera).
    pub initial: SceneDesc,
    /// Bounds of the initial volume and its world frame (camera moves turn
    /// about them until a tab has rendered its own).
    pub initial_bounds: voxless::Aabb,
    pub initial_frame: WorldFrame,
    /// Frames of the data (1 unless a time series).
    pub frames: usize,
    pub volumes: Volumes,
    /// The access token every request must carry, when bound beyond
    /// loopback.
    pub token: Option<String>,
    /// Whether the server listens on loopback only (then Host headers must
    /// name loopback: no DNS rebinding).
    pub loopback: bool,
    /// Columns of the particle file a tab may colour by (`particles.attribute`).
    pub particle_columns: Vec<String>,
    /// Colormap presets of the scene's colormap file: (file, preset names).
    pub colormap_file: Option<(String, Vec<String>)>,
    /// The view of the tab that changed last, and its frame.
    pub current: Mutex<(SceneDesc, usize)>,
    /// Renders running now (tabs' workers and `/frame.png`): what a closed
    /// tab or a dropped request must bring back to zero.
    pub busy: AtomicUsize,
}

/// Counts one running render in [`App::busy`] while it lives.
pub struct BusyGuard<'a>(&'a AtomicUsize);

impl Drop for BusyGuard<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

impl App {
    pub fn current(&self) -> (SceneDesc, usize) {
        self.current
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }

    pub fn set_current(&self, desc: &SceneDesc, frame: usize) {
        *self.current.lock().unwrap_or_else(|e| e.into_inner()) = (desc.clone(), frame);
    }

    /// Marks a render as running until the guard drops.
    pub fn busy(&self) -> BusyGuard<'_> {
        self.busy.fetch_add(1, Ordering::SeqCst);
        BusyGuard(&self.busy)
    }
}

/// The names of the presets in a ParaView preset file (an object or an
/// array of objects with `Name`), or of its one colour list.
pub fn preset_names(text: &str, path: &Path) -> Result<Vec<String>, String> {
    let value: serde_json::Value = serde_json::from_str(text).map_err(|e| e.to_string())?;
    let items = match &value {
        serde_json::Value::Array(items) => items.clone(),
        other => vec![other.clone()],
    };
    let names: Vec<String> = items
        .iter()
        .filter_map(|i| i.get("Name").and_then(|n| n.as_str()).map(String::from))
        .collect();
    if names.is_empty() {
        // A plain colour list: one colormap, named after the file.
        let m =
            voxless::transfer::parse_colormap_json(text, None, path).map_err(|e| e.to_string())?;
        return Ok(vec![m.name]);
    }
    Ok(names)
}

#[cfg(test)]
mod tests {
    use super::*;
    use voxless::{ParticleArrays, ParticlesDesc, Vec3};

    /// The kept probe gives what probing afresh gives: the same camera and
    /// settings as `voxless::resolve_in`, after camera moves and a changed
    /// clip box.
    #[test]
    fn a_kept_probe_resolves_as_a_fresh_one() {
        let positions = (0..400)
            .map(|i| {
                let t = i as f32 * 0.37;
                Vec3::new(t.sin() * 2.0, (t * 1.3).cos(), (t * 0.7).sin() * 0.5)
            })
            .collect();
        let arrays = ParticleArrays {
            positions,
            ..Default::default()
        };
        let loaded =
            Loaded::new(AnyVolume::from_particles(arrays, &ParticlesDesc::default()).unwrap());
        let base = Path::new(".");
        let mut desc = SceneDesc::default();
        desc.image.width = Some(32);
        desc.image.height = Some(24);
        let mut views = vec![desc.clone()];
        desc.camera.eye = Some([5.0, 1.0, 2.0]);
        desc.camera.look_at = Some([0.0, 0.0, 0.0]);
        views.push(desc.clone());
        desc.render.clip = Some([-1.0, -1.0, -1.0, 1.0, 1.0, 1.0]);
        views.push(desc.clone());
        desc.camera.eye = Some([0.0, 6.0, 1.0]);
        views.push(desc);
        for d in &views {
            let kept = loaded.resolve(d, base).unwrap();
            let fresh = voxless::resolve_in(&loaded.volume, &loaded.frame, d, base).unwrap();
            assert_eq!(kept.camera, fresh.camera);
            assert_eq!(kept.settings, fresh.settings);
            assert_eq!(kept.framed, fresh.framed);
        }
    }
}
