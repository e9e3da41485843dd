//! `voxless._voxless`: the native half of the Python package, a thin
//! translation layer over the `voxless` library — numpy arrays in and out,
//! scene dictionaries ↔ [`SceneDesc`], library errors ↔ Python exceptions.
//! Defaults, cameras and every algorithm live in the library; the
//! keyword-argument API is the pure-Python `voxless` package around this
//! module.
//!
//! Every description is built the CLI's way: scene tables (a dict shaped
//! like a TOML scene), then keyword arguments as the library's
//! [`SceneFlags`] (the CLI's flags, `-` as `_`) applied over them.
//! A [`Volume`] holds one loaded volume and the description it was made
//! with. Every render or projection merges a view (camera, image, transfer
//! function, render settings) over that description and resolves it with
//! [`voxless::resolve_in`] — what [`voxless::Scene`] does for the CLI, so
//! the defaults are the CLI's.
//! Volumes are immutable and shared (`Arc`), so Python threads may render
//! one volume at once; the GIL is released while the library works, and
//! Ctrl-C cancels (see [`run`]).

mod convert;
mod errors;
mod run;

/// Large arrays on huge pages where the kernel offers them (see the
/// library's `huge_pages`).
#[global_allocator]
static ALLOC: voxless::huge_pages::HugePages = voxless::huge_pages::HugePages;

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{
    PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyKeyboardInterrupt, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use voxless::{
    AmrArrays, AnyVolume, Cancelled, Image, Loaded, ParticleArrays, ProjectionDesc, ProjectionView,
    SceneDesc, SceneError, SceneFlags, Vec3, WorldFrame,
};

use errors::VoxlessError;

/// A render: premultiplied linear RGBA, the background and the notes.
type Rendered<'py> = (Bound<'py, PyArray3<f32>>, [f32; 3], Vec<String>);

/// What a Python `Volume` holds: the loaded volume (with its world frame and
/// loading notes), the description it was made with, and the directory its
/// relative paths are relative to. Views are resolved per call (nothing is
/// resolved up front: a particle volume's value range, which only renders
/// need, is probed on first use).
struct Held {
    loaded: Loaded,
    desc: SceneDesc,
    base: PathBuf,
}

impl Held {
    fn volume(&self) -> &AnyVolume {
        &self.loaded.volume
    }
    fn frame(&self) -> &WorldFrame {
        &self.loaded.frame
    }
    /// ∫ field dV in world units (see [`voxless::Scene::total_mass`]).
    fn total_mass(&self) -> Option<f64> {
        self.loaded.total_mass()
    }
    fn resolve(&self, desc: &SceneDesc) -> Result<voxless::Resolved, SceneError> {
        voxless::resolve_in(self.volume(), self.frame(), desc, &self.base)
    }
}

/// One loaded volume (particles, AMR cells or a tessellation).
#[pyclass(frozen, module = "voxless._voxless", name = "Volume")]
struct Volume {
    held: Arc<Held>,
}

/// Why library work stopped.
enum Failure {
    Scene(SceneError),
    Cancelled,
}

impl From<SceneError> for Failure {
    fn from(e: SceneError) -> Self {
        Failure::Scene(e)
    }
}
impl From<Cancelled> for Failure {
    fn from(_: Cancelled) -> Self {
        Failure::Cancelled
    }
}

fn raise(py: Python<'_>, f: Failure) -> PyErr {
    match f {
        Failure::Scene(e) => errors::scene(py, e),
        Failure::Cancelled => PyKeyboardInterrupt::new_err("voxless: cancelled"),
    }
}

/// The rows of an N×3 array.
fn rows3<T: Copy + numpy::Element>(
    py: Python<'_>,
    a: &PyReadonlyArray2<'_, T>,
    name: &str,
) -> PyResult<Vec<[T; 3]>> {
    let shape = a.shape();
    if shape[1] != 3 {
        return Err(errors::value(
            py,
            format!("{name}: expected an N×3 array, got shape {shape:?}"),
        ));
    }
    Ok(a.as_array()
        .rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2]])
        .collect())
}

fn vec1<T: Copy + numpy::Element>(a: Option<PyReadonlyArray1<'_, T>>) -> Option<Vec<T>> {
    a.map(|a| a.as_array().iter().copied().collect())
}

/// A description: the scene `tables` with the keyword arguments `flags`
/// applied over them (paths relative to `cwd`). Of the data flags, only
/// those in `data` may be given (`what` names the call in the error).
fn describe(
    tables: &Bound<'_, PyAny>,
    flags: &Bound<'_, PyAny>,
    cwd: &std::path::Path,
    what: &str,
    data: &[&str],
) -> PyResult<SceneDesc> {
    let mut desc = convert::scene_desc(tables)?;
    apply_flags(&mut desc, flags, cwd, what, data)?;
    Ok(desc)
}

/// Applies the keyword arguments `flags` over `desc` (see [`describe`]).
fn apply_flags(
    desc: &mut SceneDesc,
    flags: &Bound<'_, PyAny>,
    cwd: &std::path::Path,
    what: &str,
    data: &[&str],
) -> PyResult<()> {
    let py = flags.py();
    let flags = convert::flags(flags)?;
    if let Some(bad) = data_flags(&flags).into_iter().find(|f| !data.contains(f)) {
        return Err(PyTypeError::new_err(format!(
            "{what}() does not take {bad}=: it describes data that {what}() does not read \
             (see voxless.load for files)"
        )));
    }
    flags.apply(desc, cwd).map_err(|e| errors::scene(py, e))
}

/// The data flags among the given `flags` ([`SceneFlags::data_flags`]),
/// `box` always among them: it describes the data (a particle set's periodic
/// box, a tessellation's), whichever data it goes to.
fn data_flags(flags: &SceneFlags) -> Vec<&'static str> {
    let mut given = flags.data_flags();
    if flags.data.box_size.is_some() && !given.contains(&"box") {
        given.push("box");
    }
    given
}

/// The names of every data flag ([`SceneFlags::data_names`]), `box` among
/// them (see [`data_flags`]).
fn data_names() -> Vec<&'static str> {
    let mut names = SceneFlags::data_names();
    if !names.contains(&"box") {
        names.push("box");
    }
    names
}

/// Data flags that apply to particles from arrays.
const PARTICLE_FLAGS: &[&str] = &[
    "radius",
    "kernel",
    "kappa",
    "sigma",
    "cluster",
    "classification",
    "attribute_range",
    "species",
    "box",
    "wrap",
    "neighbours",
];
/// Data flags that apply to AMR cells from arrays.
const AMR_FLAGS: &[&str] = &["field", "color_field", "reconstruction"];
/// Data flags that apply to a tessellation from arrays.
const TET_FLAGS: &[&str] = &["particle_mass", "tet_mode", "k", "layers", "lod"];
/// Builds a volume off the GIL. The description's transfer function is
/// checked now (an unknown colormap is a construction error); the rest of
/// the view when it is used.
fn hold(
    py: Python<'_>,
    desc: SceneDesc,
    base: PathBuf,
    build: impl FnOnce(&SceneDesc) -> Result<Loaded, SceneError> + Send,
) -> PyResult<Volume> {
    let held = run::detached(py, move || -> Result<Held, SceneError> {
        voxless::transfer_function_at(&desc.transfer, &base, &mut Vec::new())?;
        let loaded = build(&desc)?;
        Ok(Held { loaded, desc, base })
    })?
    .map_err(|e| errors::scene(py, e))?;
    Ok(Volume {
        held: Arc::new(held),
    })
}

/// Particles from arrays: `positions` N×3 float32 (used as they are) or
/// float64 (recentred in float64 before they become float32); the optional
/// per-particle arrays float32 of length N; the kernel, radius, periodic
/// box, neighbour count and the like as flags (see [`describe`]).
#[pyfunction]
#[pyo3(signature = (positions, radii, weights, attribute, species, tables, flags, cwd))]
#[allow(clippy::too_many_arguments)]
fn particles(
    py: Python<'_>,
    positions: &Bound<'_, PyAny>,
    radii: Option<PyReadonlyArray1<'_, f32>>,
    weights: Option<PyReadonlyArray1<'_, f32>>,
    attribute: Option<PyReadonlyArray1<'_, f32>>,
    species: Option<PyReadonlyArray1<'_, f32>>,
    tables: &Bound<'_, PyAny>,
    flags: &Bound<'_, PyAny>,
    cwd: PathBuf,
) -> PyResult<Volume> {
    // A particles table from the start: the flags then apply to it even
    // when no other particle flag is given (`box` alone).
    let mut desc = convert::scene_desc(tables)?;
    desc.particles.get_or_insert_with(Default::default);
    apply_flags(&mut desc, flags, &cwd, "Particles", PARTICLE_FLAGS)?;
    let mut arrays = if let Ok(p) = positions.extract::<PyReadonlyArray2<'_, f64>>() {
        ParticleArrays::from_f64(&rows3(py, &p, "positions")?)
    } else if let Ok(p) = positions.extract::<PyReadonlyArray2<'_, f32>>() {
        ParticleArrays {
            positions: rows3(py, &p, "positions")?
                .into_iter()
                .map(Vec3::from_array)
                .collect(),
            ..Default::default()
        }
    } else {
        return Err(PyTypeError::new_err(
            "positions: expected an N×3 float32 or float64 numpy array",
        ));
    };
    arrays.radii = vec1(radii);
    arrays.weights = vec1(weights);
    arrays.attribute = vec1(attribute);
    arrays.species = vec1(species);
    hold(py, desc, cwd, move |d| {
        AnyVolume::from_particles(arrays, &d.particles.clone().unwrap_or_default())
    })
}

/// AMR leaf cells from arrays: `cells` N×4 int32 (x, y, z, level; lower
/// corner in finest-cell units, level 0 finest), one float32 array of N
/// values per named field.
#[pyfunction]
#[pyo3(signature = (cells, fields, origin, cell_size, tables, flags, cwd))]
#[allow(clippy::too_many_arguments)]
fn amr(
    py: Python<'_>,
    cells: PyReadonlyArray2<'_, i32>,
    fields: Vec<(String, PyReadonlyArray1<'_, f32>)>,
    origin: [f64; 3],
    cell_size: f32,
    tables: &Bound<'_, PyAny>,
    flags: &Bound<'_, PyAny>,
    cwd: PathBuf,
) -> PyResult<Volume> {
    let desc = describe(tables, flags, &cwd, "AmrCells", AMR_FLAGS)?;
    let shape = cells.shape();
    if shape[1] != 4 {
        return Err(errors::value(
            py,
            format!("cells: expected an N×4 array (x, y, z, level), got shape {shape:?}"),
        ));
    }
    let arrays = AmrArrays {
        cells: cells
            .as_array()
            .rows()
            .into_iter()
            .map(|r| [r[0], r[1], r[2], r[3]])
            .collect(),
        fields: fields
            .into_iter()
            .map(|(name, v)| (name, v.as_array().iter().copied().collect()))
            .collect(),
        origin,
        cell_size,
    };
    hold(py, desc, cwd, move |d| {
        AnyVolume::from_amr(arrays, &d.amr.clone().unwrap_or_default())
    })
}

/// A phase-space tessellation of N³ float32 positions in Lagrangian order in
/// the periodic box `[0, box_size)³`.
#[pyfunction]
#[pyo3(signature = (positions, n, box_size, tables, flags, cwd))]
#[allow(clippy::too_many_arguments)]
fn tessellation(
    py: Python<'_>,
    positions: PyReadonlyArray2<'_, f32>,
    n: usize,
    box_size: f32,
    tables: &Bound<'_, PyAny>,
    flags: &Bound<'_, PyAny>,
    cwd: PathBuf,
) -> PyResult<Volume> {
    let desc = describe(tables, flags, &cwd, "Tessellation", TET_FLAGS)?;
    let positions: Vec<Vec3> = rows3(py, &positions, "positions")?
        .into_iter()
        .map(Vec3::from_array)
        .collect();
    hold(py, desc, cwd, move |d| {
        AnyVolume::from_tessellation(positions, n, box_size, &d.tets.clone().unwrap_or_default())
    })
}

/// The data the scene `tables` (paths relative to `base`) and `flags`
/// (paths relative to `cwd`) name, with its defaults.
#[pyfunction]
#[pyo3(signature = (tables, flags, base, cwd, frame=0))]
fn load(
    py: Python<'_>,
    tables: &Bound<'_, PyAny>,
    flags: &Bound<'_, PyAny>,
    base: PathBuf,
    cwd: PathBuf,
    frame: usize,
) -> PyResult<Volume> {
    let desc = describe(tables, flags, &cwd, "load", &data_names())?;
    let base_for_load = base.clone();
    hold(py, desc, base, move |d| {
        voxless::load(d, &base_for_load, frame)
    })
}

/// Projects the data the scene `tables` (paths relative to `base`) and
/// `flags` (relative to `cwd`) name without holding a volume: streamed from
/// its files when it can be, else loaded and projected (see
/// `voxless::stream::project_file`, the CLI's one-process `project`): the
/// column densities and the geometry, as [`Volume::project`].
#[pyfunction]
#[pyo3(signature = (tables, flags, base, cwd, frame=0, axis=None, normal=None, north=None, center=None, width=None, bounds=None, depth=None, pixels=None, device=None))]
#[allow(clippy::too_many_arguments)]
fn project_file<'py>(
    py: Python<'py>,
    tables: &Bound<'py, PyAny>,
    flags: &Bound<'py, PyAny>,
    base: PathBuf,
    cwd: PathBuf,
    frame: usize,
    axis: Option<usize>,
    normal: Option<[f64; 3]>,
    north: Option<[f64; 3]>,
    center: Option<[f64; 3]>,
    width: Option<[f64; 2]>,
    bounds: Option<[f64; 6]>,
    depth: Option<f64>,
    pixels: Option<&str>,
    device: Option<&str>,
) -> PyResult<(Bound<'py, PyArray2<f32>>, Bound<'py, PyDict>)> {
    let mut desc = describe(tables, flags, &cwd, "project", &data_names())?;
    let (device, device_note) = self::device(device)?;
    let projection = ProjectionDesc {
        axis,
        normal,
        north,
        center,
        width,
        bounds,
        depth,
    };
    let pixels = pixels_name(pixels)?;
    voxless::set_projection_pixels(&mut desc, pixels, &projection)
        .map_err(|e| errors::scene(py, e))?;
    let done = run::cancellable(py, move |control| -> Result<_, Failure> {
        let (w, h) = voxless::projection::image_size(&desc.image)?;
        let p = voxless::stream::project_file(
            &desc,
            &base,
            frame,
            &projection,
            (w, h),
            &device,
            control,
        )??;
        Ok((p, w, h, device_note))
    })?;
    let (p, w, h, device_note) = done.map_err(|f| raise(py, f))?;
    let notes = device_note.into_iter().chain(p.notes).collect();
    let (image, geometry) = projected(py, p.column, &p.view, (w, h), depth, notes)?;
    geometry.set_item("total_mass", p.mass)?;
    geometry.set_item("chunks", p.chunks)?;
    Ok((image, geometry))
}

/// A projection as Python gets it: the H×W image and its geometry (the
/// plane, pixel area, depth and notes; callers add the mass).
fn projected<'py>(
    py: Python<'py>,
    column: Vec<f32>,
    view: &ProjectionView,
    (w, h): (u32, u32),
    depth: Option<f64>,
    notes: Vec<String>,
) -> PyResult<(Bound<'py, PyArray2<f32>>, Bound<'py, PyDict>)> {
    let image = PyArray1::from_vec(py, column).reshape([h as usize, w as usize])?;
    let geometry = plane_geometry(py, view)?;
    geometry.set_item("pixel_area", view.pixel_area(w, h))?;
    geometry.set_item("depth", depth)?;
    geometry.set_item("notes", notes)?;
    Ok((image, geometry))
}

/// The pixel rule `pixels` names (`"centre"` or `"area"`, with the scene's
/// aliases).
fn pixels_name(pixels: Option<&str>) -> PyResult<Option<voxless::PixelsName>> {
    pixels
        .map(|p| serde_json::from_value(serde_json::Value::from(p)))
        .transpose()
        .map_err(|_| {
            PyValueError::new_err(format!(
                "pixels: {:?} is not \"centre\" or \"area\"",
                pixels.unwrap_or_default()
            ))
        })
}

/// The data flag a bare path is read with (`particles`, `amr`, `cells` or
/// `amrclaw`): the library decides, as for every front-end.
#[pyfunction]
fn data_flag_for(path: PathBuf) -> &'static str {
    voxless::data_flag_for(&path)
}

/// A TOML scene file as a dictionary.
#[pyfunction]
fn read_scene<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let desc = voxless::read_scene(&path).map_err(|e| errors::scene(py, e))?;
    convert::desc_to_python(py, &desc)
}

/// Where a projection's or slice's image lies: its centre, the unit
/// vectors of increasing column and decreasing row, the normal and the
/// world width and height.
fn plane_geometry<'py>(py: Python<'py>, view: &ProjectionView) -> PyResult<Bound<'py, PyDict>> {
    let geometry = PyDict::new(py);
    geometry.set_item("center", view.center)?;
    geometry.set_item("right", view.right)?;
    geometry.set_item("up", view.up)?;
    geometry.set_item("normal", view.normal)?;
    geometry.set_item("width", view.width)?;
    Ok(geometry)
}

impl Volume {
    /// The volume's description with a view over it: scene `tables`
    /// (camera, image, transfer, render, light), then view `flags`.
    fn view(
        &self,
        tables: &Bound<'_, PyAny>,
        flags: &Bound<'_, PyAny>,
        cwd: &std::path::Path,
        what: &str,
    ) -> PyResult<SceneDesc> {
        let mut desc = convert::with_view(&self.held.desc, tables)?;
        apply_flags(&mut desc, flags, cwd, what, &[])?;
        Ok(desc)
    }
}

/// The device `name` names (`None`: the CPU), opened once per process and
/// kept (a GPU's device and pipelines are reused by later calls); a note
/// when `auto` stands the CPU in.
fn device(name: Option<&str>) -> PyResult<(voxless::device::Device, Option<String>)> {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    use voxless::device::{Device, DeviceChoice};
    type Opened = (Device, Option<String>);
    static OPEN: OnceLock<Mutex<HashMap<String, Opened>>> = OnceLock::new();
    let choice: DeviceChoice = match name {
        None => return Ok((Device::cpu(), None)),
        Some(n) => n
            .parse()
            .map_err(|e: String| PyValueError::new_err(format!("device: {e}")))?,
    };
    let mut open = OPEN
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(d) = open.get(&choice.to_string()) {
        return Ok(d.clone());
    }
    let d = Device::open(choice).map_err(|e| PyValueError::new_err(e.to_string()))?;
    open.insert(choice.to_string(), d.clone());
    Ok(d)
}

#[pymethods]
impl Volume {
    /// Renders with the view (scene `tables`, then view `flags`) over the
    /// volume's description on `device` (`"cpu"`, `"gpu"`, `"auto"`): an
    /// H×W×4 float32 array of premultiplied linear RGBA, the background
    /// colour (linear RGB) and the notes of resolving the view.
    #[pyo3(signature = (tables, flags, cwd, device=None))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        tables: &Bound<'py, PyAny>,
        flags: &Bound<'py, PyAny>,
        cwd: PathBuf,
        device: Option<&str>,
    ) -> PyResult<Rendered<'py>> {
        let desc = self.view(tables, flags, &cwd, "render")?;
        let (device, device_note) = self::device(device)?;
        let held = self.held.clone();
        let done = run::cancellable(py, move |control| -> Result<_, Failure> {
            let mut r = held.resolve(&desc)?;
            // The CLI's checks: absurd work before, no surface or nothing
            // visible after.
            if let Some(note) = r.check_work(held.volume(), held.frame(), &desc)? {
                r.notes.push(note);
            }
            r.notes.extend(device_note);
            let mut notes = Vec::new();
            let film = device.render_film(held.volume(), &r, control, &mut notes)??;
            r.notes.extend(notes);
            let image = film.resolve();
            let bounds = held.frame().box_to_world(held.volume().bounds());
            r.check_image(bounds, film.stats(), &image)?;
            Ok((image, r.background, r.notes))
        })?;
        let (image, background, notes) = done.map_err(|f| raise(py, f))?;
        Ok((rgba_array(py, &image)?, background, notes))
    }

    /// Column density `∫ field dt` per pixel (H×W float32, row 0 at the top)
    /// along an axis or a normal (see `voxless::projection`), at the view's
    /// image size (`flags` may give `size`), and the projection's geometry.
    #[pyo3(signature = (flags, axis=None, normal=None, north=None, center=None, width=None, bounds=None, depth=None, pixels=None, device=None))]
    #[allow(clippy::too_many_arguments)]
    fn project<'py>(
        &self,
        py: Python<'py>,
        flags: &Bound<'py, PyAny>,
        axis: Option<usize>,
        normal: Option<[f64; 3]>,
        north: Option<[f64; 3]>,
        center: Option<[f64; 3]>,
        width: Option<[f64; 2]>,
        bounds: Option<[f64; 6]>,
        depth: Option<f64>,
        pixels: Option<&str>,
        device: Option<&str>,
    ) -> PyResult<(Bound<'py, PyArray2<f32>>, Bound<'py, PyDict>)> {
        let (device, device_note) = self::device(device)?;
        let mut desc = self.held.desc.clone();
        apply_flags(&mut desc, flags, &self.held.base, "project", &[])?;
        let projection = ProjectionDesc {
            axis,
            normal,
            north,
            center,
            width,
            bounds,
            depth,
        };
        // The pixel rule: particles choose it per projection; a
        // tessellation's is part of how it was opened.
        // The scene's names (aliases included).
        let pixels = pixels_name(pixels)?;
        if pixels.is_some() && desc.tets.is_some() {
            return Err(PyValueError::new_err(
                "pixels: a tessellation's pixel rule is chosen when it is opened (tets.pixels \
                 in its scene), not per projection",
            ));
        }
        // The CLI's refusals: pixel areas integrate whole lines, not a
        // slab, of particles or tessellations only.
        voxless::set_projection_pixels(&mut desc, pixels, &projection)
            .map_err(|e| errors::scene(py, e))?;
        let rule = pixels.map(|p| voxless::projection::pixel_integral(Some(p)));
        let held = self.held.clone();
        let done = run::cancellable(py, move |control| -> Result<_, Failure> {
            let size = voxless::projection::image_size(&desc.image)?;
            let mut notes: Vec<String> = device_note.into_iter().collect();
            let (view, column) =
                held.loaded
                    .project_on(&projection, size, rule, &device, control, &mut notes)??;
            Ok((column, view, size, notes))
        })?;
        let (column, view, size, notes) = done.map_err(|f| raise(py, f))?;
        let (image, geometry) = projected(py, column, &view, size, depth, notes)?;
        geometry.set_item("total_mass", self.held.total_mass())?;
        Ok((image, geometry))
    }

    /// The field on a plane (see `voxless::slice`): H×W float32 (row 0 at
    /// the top; NaN outside AMR cells), the quantity's name and the plane's
    /// geometry — exactly what `sample` gives at the pixel centres.
    #[pyo3(signature = (flags, axis=None, normal=None, north=None, center=None, width=None, quantity=None, area=false))]
    #[allow(clippy::too_many_arguments)]
    fn slice<'py>(
        &self,
        py: Python<'py>,
        flags: &Bound<'py, PyAny>,
        axis: Option<usize>,
        normal: Option<[f64; 3]>,
        north: Option<[f64; 3]>,
        center: Option<[f64; 3]>,
        width: Option<[f64; 2]>,
        quantity: Option<String>,
        area: bool,
    ) -> PyResult<(Bound<'py, PyArray2<f32>>, String, Bound<'py, PyDict>)> {
        let mut desc = self.held.desc.clone();
        apply_flags(&mut desc, flags, &self.held.base, "slice", &[])?;
        let slice = voxless::slice::SliceDesc {
            plane: ProjectionDesc {
                axis,
                normal,
                north,
                center,
                width,
                ..Default::default()
            },
            quantity,
            pixels: if area {
                voxless::slice::SlicePixels::Area
            } else {
                voxless::slice::SlicePixels::Centre
            },
        };
        let held = self.held.clone();
        let done = run::detached(py, move || -> Result<_, voxless::SceneError> {
            let (w, h) = voxless::projection::image_size(&desc.image)?;
            let fields = held.volume().fields();
            let bounds = held.volume().bounds();
            let space = voxless::slice::Space {
                fields: &fields,
                bounds: &bounds,
                frame: held.frame(),
            };
            let mut sample = |pts: &[[f64; 3]]| -> Result<_, voxless::SceneError> {
                let local: Vec<Vec3> = pts.iter().map(|&p| held.frame().to_local(p)).collect();
                Ok(Some(held.volume().sample_points(&local, false)))
            };
            let (view, name, values) =
                voxless::slice::slice_with(&space, &desc, &slice, (w, h), &mut sample, &|_, _| {})?;
            Ok((view, name, values.unwrap_or_default(), w, h))
        })?;
        let (view, name, values, w, h) = done.map_err(|e| errors::scene(py, e))?;
        let image = PyArray1::from_vec(py, values).reshape([h as usize, w as usize])?;
        Ok((image, name, plane_geometry(py, &view)?))
    }

    /// Renders path frames `first..=last` of the view's camera path (scene
    /// `tables` with `camera.keyframes`, then view `flags`) into the movie
    /// `output` (.mp4, .webm, .gif; see `voxless::movie`): the number of
    /// frames encoded, how many were rendered (the rest resumed from disk)
    /// and the notes.
    #[pyo3(signature = (tables, flags, cwd, output, first, last, fps=24.0, quality=80, keep_frames=false))]
    #[allow(clippy::too_many_arguments)]
    fn movie(
        &self,
        py: Python<'_>,
        tables: &Bound<'_, PyAny>,
        flags: &Bound<'_, PyAny>,
        cwd: PathBuf,
        output: PathBuf,
        first: usize,
        last: usize,
        fps: f64,
        quality: u32,
        keep_frames: bool,
    ) -> PyResult<(usize, usize, Vec<String>)> {
        let mut desc = self.view(tables, flags, &cwd, "movie")?;
        desc.camera.fps.get_or_insert(fps);
        let output = cwd.join(output);
        let held = self.held.clone();
        let done = run::cancellable(py, move |control| -> Result<_, Failure> {
            let settings = voxless::movie::MovieSettings { fps, quality };
            let mut notes = Vec::new();
            let path = voxless::camera_path::CameraPath::new(&desc.camera)?;
            if last < first || last - first >= voxless::camera_path::MAX_FRAMES {
                return Err(voxless::SceneError::setting(
                    "frames",
                    format!(
                        "{first}..{last} is not a range of at most {} frames",
                        voxless::camera_path::MAX_FRAMES
                    ),
                )
                .into());
            }
            let frames: Vec<usize> = (first..=last).collect();
            let at = |t: usize| match &path {
                Some(p) => p.apply(&desc, t as f64),
                None => desc.clone(),
            };
            let mut r = held.resolve(&at(first))?;
            let size = (r.settings.width, r.settings.height);
            let plan: Vec<(usize, usize)> = frames.iter().map(|&t| (t, 0)).collect();
            let stamp = voxless::movie::stamp(&desc, &plan, size);
            let mut movie = voxless::movie::MovieWriter::start(
                &output,
                frames.len(),
                &stamp,
                size,
                &settings,
                keep_frames,
                &mut notes,
            )?;
            let mut rendered = 0;
            for (k, &t) in frames.iter().enumerate() {
                if movie.has(k) {
                    movie.put(k, None)?;
                    continue;
                }
                r.reaim(&at(t), held.frame())?;
                let image = r.render_film(held.volume(), control)?.resolve();
                movie.put(k, Some(&image.to_srgb8(r.background)))?;
                rendered += 1;
            }
            let (n, _) = movie.finish()?;
            notes.extend(r.notes);
            Ok((n, rendered, notes))
        })?;
        done.map_err(|f| raise(py, f))
    }

    /// The fields at N×3 float64 world `points`: an N×k float32 array and
    /// the k column names.
    #[pyo3(signature = (points, gradient=false))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f64>,
        gradient: bool,
    ) -> PyResult<(Bound<'py, PyArray2<f32>>, Vec<String>)> {
        let pts = rows3(py, &points, "points")?;
        if let Some(i) = pts.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(errors::value(
                py,
                format!("points: point {i} has a non-finite coordinate"),
            ));
        }
        self.held
            .volume()
            .fields()
            .check_gradient(gradient)
            .map_err(|e| errors::value(py, e.to_string()))?;
        let held = self.held.clone();
        let n = pts.len();
        // World points into the volume's frame (as Scene::sample does).
        let values = run::detached(py, move || {
            let local: Vec<Vec3> = pts.iter().map(|&p| held.frame().to_local(p)).collect();
            held.volume().sample_points(&local, gradient)
        })?;
        let columns = self.held.volume().sample_columns(gradient);
        let k = columns.len();
        let array = PyArray1::from_vec(py, values).reshape([n, k])?;
        Ok((array, columns))
    }

    /// What the view resolves to: image size, camera (world eye and look
    /// direction), transfer-function range and scale, notes.
    fn describe<'py>(
        &self,
        py: Python<'py>,
        tables: &Bound<'py, PyAny>,
        flags: &Bound<'py, PyAny>,
        cwd: PathBuf,
    ) -> PyResult<Bound<'py, PyDict>> {
        let desc = self.view(tables, flags, &cwd, "describe")?;
        let held = &self.held;
        // Resolving may probe the data (a particle volume's value range).
        let r = run::detached(py, || held.resolve(&desc))?.map_err(|e| errors::scene(py, e))?;
        let d = PyDict::new(py);
        let st = &r.settings;
        d.set_item("size", (st.width, st.height))?;
        d.set_item("spp", st.spp)?;
        d.set_item("eye", held.frame().to_world(r.camera.eye))?;
        d.set_item("forward", r.camera.forward.to_array())?;
        d.set_item("up", r.camera.up.to_array())?;
        d.set_item("value_range", (st.value_range.lo, st.value_range.hi))?;
        d.set_item("log_scale", st.log_scale)?;
        d.set_item("opacity_scale", st.opacity_scale)?;
        d.set_item("background", r.background)?;
        d.set_item("notes", r.notes)?;
        Ok(d)
    }

    /// The names of the columns `sample` returns.
    #[pyo3(signature = (gradient=false))]
    fn columns(&self, gradient: bool) -> Vec<String> {
        self.held.volume().sample_columns(gradient)
    }

    /// "particles", "AMR cells", "phase-space tessellation" or
    /// "multi-material particles".
    #[getter]
    fn kind(&self) -> &'static str {
        self.held.volume().kind()
    }

    /// World bounds: ((x0, y0, z0), (x1, y1, z1)).
    #[getter]
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let b = self.held.volume().bounds();
        (
            self.held.frame().to_world(b.min),
            self.held.frame().to_world(b.max),
        )
    }

    /// World position of the volume's local origin.
    #[getter]
    fn origin(&self) -> [f64; 3] {
        self.held.frame().origin
    }

    /// World length of one local unit (a power of two; 1 for data of
    /// everyday extent).
    #[getter]
    fn scale(&self) -> f64 {
        self.held.frame().scale
    }

    /// The data's value range (the transfer function's default).
    #[getter]
    fn value_range(&self, py: Python<'_>) -> PyResult<(f32, f32)> {
        // Probed on first use for particles: off the GIL.
        let r = run::detached(py, || self.held.volume().value_range())?;
        Ok((r.lo, r.hi))
    }

    /// ∫ field dV in world units when the data kind knows it exactly (else
    /// None).
    #[getter]
    fn total_mass(&self) -> Option<f64> {
        self.held.total_mass()
    }

    /// Every particle's radius parameter in world units, in the input's row
    /// order (float32): the smoothing length h of the SPH kernels, the
    /// support of gaussian3, σ of gaussian — given, estimated, or found from
    /// the neighbours. Particle volumes only (one set of particles).
    #[getter]
    fn smoothing_lengths<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let held = &self.held;
        if !matches!(held.volume(), AnyVolume::Particles(_)) {
            return Err(errors::value(
                py,
                format!(
                    "smoothing_lengths: only particles (one set, not materials) have \
                     smoothing lengths; this volume is {}",
                    held.volume().kind()
                ),
            ));
        }
        let lengths = run::detached(py, || held.volume().smoothing_lengths(held.frame()))?
            .map_err(|e| errors::scene(py, e))?;
        Ok(PyArray1::from_vec(py, lengths))
    }

    /// Defaults chosen from the data when it was loaded.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.held.loaded.notes.clone()
    }

    /// The scene description the volume was made with, as a dict.
    #[getter]
    fn desc<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        convert::desc_to_python(py, &self.held.desc)
    }
}

/// An image as an H×W×4 float32 array.
fn rgba_array<'py>(py: Python<'py>, image: &Image) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let (w, h) = (image.width as usize, image.height as usize);
    PyArray1::from_vec(py, image.to_rgba_f32()).reshape([h, w, 4])
}

/// An H×W×4 array back into an [`Image`].
fn image_of(py: Python<'_>, rgba: &PyReadonlyArray3<'_, f32>) -> PyResult<Image> {
    let shape = rgba.shape();
    if shape[2] != 4 {
        return Err(errors::value(
            py,
            format!("image: expected an H×W×4 RGBA array, got shape {shape:?}"),
        ));
    }
    let flat: Vec<f32> = rgba.as_array().iter().copied().collect();
    Ok(Image {
        width: shape[1] as u32,
        height: shape[0] as u32,
        pixels: flat
            .chunks_exact(4)
            .map(|p| [p[0], p[1], p[2], p[3]])
            .collect(),
    })
}

/// Premultiplied linear RGBA over an opaque linear `background`, as H×W×3
/// 8-bit sRGB (what the CLI writes to PNG).
#[pyfunction]
fn srgb8<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    background: [f32; 3],
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    let image = image_of(py, &rgba)?;
    let (w, h) = (image.width as usize, image.height as usize);
    PyArray1::from_vec(py, image.to_srgb8(background)).reshape([h, w, 3])
}

/// [`srgb8`] encoded as PNG bytes.
#[pyfunction]
fn png<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    background: [f32; 3],
) -> PyResult<Bound<'py, PyBytes>> {
    let image = image_of(py, &rgba)?;
    let mut out = Vec::new();
    voxless::io::write_png_rgb8_to(
        &mut out,
        std::path::Path::new("image"),
        image.width,
        image.height,
        &image.to_srgb8(background),
    )
    .map_err(|e| errors::scene(py, e.into()))?;
    Ok(PyBytes::new(py, &out))
}

/// The built-in colormap names.
#[pyfunction]
fn colormaps() -> Vec<&'static str> {
    voxless::transfer::COLORMAP_NAMES.to_vec()
}

/// Flag names, data flag names, and each constructor's data flags.
type FlagNames = (
    Vec<String>,
    Vec<&'static str>,
    Vec<(&'static str, &'static [&'static str])>,
);

/// The names of the keyword arguments that are the library's flags (the
/// CLI's flags, `-` as `_`), those of them that describe data, and the data
/// flags each in-memory constructor takes.
#[pyfunction]
fn flag_names() -> FlagNames {
    let constructors = vec![
        ("Particles", PARTICLE_FLAGS),
        ("AmrCells", AMR_FLAGS),
        ("Tessellation", TET_FLAGS),
    ];
    (SceneFlags::names(), data_names(), constructors)
}

/// The image's up direction a projection along `normal` gets by default
/// (yt's rule).
#[pyfunction]
fn default_north(normal: [f64; 3]) -> [f64; 3] {
    voxless::projection::default_north(normal)
}

#[pymodule]
fn _voxless(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Volume>()?;
    m.add("VoxlessError", m.py().get_type::<VoxlessError>())?;
    m.add_function(wrap_pyfunction!(particles, m)?)?;
    m.add_function(wrap_pyfunction!(amr, m)?)?;
    m.add_function(wrap_pyfunction!(tessellation, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(project_file, m)?)?;
    m.add_function(wrap_pyfunction!(read_scene, m)?)?;
    m.add_function(wrap_pyfunction!(data_flag_for, m)?)?;
    m.add_function(wrap_pyfunction!(srgb8, m)?)?;
    m.add_function(wrap_pyfunction!(png, m)?)?;
    m.add_function(wrap_pyfunction!(colormaps, m)?)?;
    m.add_function(wrap_pyfunction!(default_north, m)?)?;
    m.add_function(wrap_pyfunction!(flag_names, m)?)?;
    Ok(())
}
