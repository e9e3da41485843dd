//! The common result of every particle reader: positions plus named
//! per-particle columns, one frame at a time.
//!
//! Formats that hold several frames (a LAMMPS dump, a directory of PySPH
//! outputs) report how many with their `*_frames` function and read one frame
//! per call, so a time series never holds more than one frame in memory.

/// Particles of one frame, in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParticleTable {
    /// Positions, one per particle (world units of the file), in float64 so
    /// that data far from the origin (10⁹ + a small spread) keeps its
    /// digits until the library recentres it.
    pub positions: Vec<[f64; 3]>,
    /// Named per-particle columns, each `positions.len()` long, in the order
    /// the file lists them; derived columns (e.g. `speed` = |v|) come last.
    /// Vector quantities appear as their components (`vx`, `vy`, `vz`) and, for
    /// velocities, as `speed`.
    pub columns: Vec<(String, Vec<f32>)>,
    /// Simulation time of the frame, when the file says (the scale factor
    /// in cosmological snapshots).
    pub time: Option<f64>,
    /// Redshift, when a cosmological snapshot states it.
    pub redshift: Option<f64>,
    /// The file's unit system, when it states one (SWIFT, Gadget/AREPO
    /// HDF5); positions and columns stay in these units.
    pub units: Option<crate::Units>,
    /// The simulation box (lower corner, upper corner), when the file says.
    pub domain: Option<([f64; 3], [f64; 3])>,
    /// Whether the file says the domain is periodic along every axis
    /// (LAMMPS `pp pp pp` bounds, extended XYZ `pbc="T T T"`, a SWIFT or
    /// Gadget `BoxSize`).
    pub periodic: bool,
    /// When only part of the file's particles was read (one rank's share of
    /// a parallel run): the first row read and the file's particle count.
    pub rows: Option<(usize, usize)>,
    /// Which SPH code wrote the file and the kernel it records, when the
    /// format says (SWIFT and Gadget-4 snapshots): how its smoothing
    /// lengths relate to a kernel's support.
    pub sph: Option<SphConvention>,
}

/// The SPH code behind a snapshot's smoothing lengths.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SphCode {
    /// `SmoothingLengths` = h_S with support `γ h_S` (γ per kernel).
    Swift,
    /// `SmoothingLength(s)` = the support radius H (Gadget-2/3/4, GIZMO:
    /// cubic spline by default).
    Gadget,
    /// AREPO's moving-mesh cells: no smoothing length; a cell's size comes
    /// from its volume `Masses / Density`.
    Arepo,
    /// Tipsy (ChaNGa, Gasoline): `hsmooth` = h with support 2h (cubic
    /// spline); dark and star particles carry a softening `eps`.
    Tipsy,
}

/// What a snapshot says about its kernel.
#[derive(Clone, Debug, PartialEq)]
pub struct SphConvention {
    pub code: SphCode,
    /// The kernel's name as the file writes it (SWIFT's `HydroScheme`
    /// attribute `Kernel function`, e.g. "Quintic spline (M6)").
    pub kernel: Option<String>,
}

impl ParticleTable {
    /// The column called `name` (case-insensitive).
    pub fn column(&self, name: &str) -> Option<&[f32]> {
        let wanted = name.trim();
        self.columns
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(wanted))
            .map(|(_, v)| v.as_slice())
    }

    /// The names of all columns, for error messages ("fields: a, b, c").
    pub fn column_names(&self) -> Vec<&str> {
        self.columns.iter().map(|(n, _)| n.as_str()).collect()
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Appends `speed = |(vx, vy, vz)|` when the three components exist and
    /// `speed` does not.
    pub fn derive_speed(&mut self, vx: &str, vy: &str, vz: &str) {
        if self.column("speed").is_some() {
            return;
        }
        let speed = match (self.column(vx), self.column(vy), self.column(vz)) {
            (Some(x), Some(y), Some(z)) => x
                .iter()
                .zip(y)
                .zip(z)
                .map(|((a, b), c)| (a * a + b * b + c * c).sqrt())
                .collect(),
            _ => return,
        };
        self.columns.push(("speed".into(), speed));
    }
}
