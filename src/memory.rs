//! Volumes from arrays in memory — the same constructors the file loaders
//! use, so in-memory data gets the same data defaults (a radius from the
//! particle spacing, …) and, through [`crate::resolve`], the same view
//! defaults. Errors name the array at fault (`positions: particle 3 has a
//! non-finite coordinate`).

use std::path::{Path, PathBuf};

use voxless_core::Vec3;
use voxless_particles::ParticleData;
use voxless_scene::{AmrDesc, ParticlesDesc, TetsDesc};

use crate::load::{self, AmrArrays, Loaded};
use crate::{AnyVolume, SceneError, WorldFrame};

/// Particle arrays in memory, one entry per particle.
///
/// Positions are in `frame`'s local coordinates (the world itself by
/// default); radii and weights are in world units. Building a volume places
/// the particles in the frame the placement policy picks for their extent
/// ([`WorldFrame::fit`]): for everyday data that is the world frame, and
/// the arrays are used as they are.
#[derive(Clone, Debug, Default)]
pub struct ParticleArrays {
    /// Positions in `frame`'s coordinates.
    pub positions: Vec<Vec3>,
    /// Where the positions' frame lies in the world (the world frame by
    /// default; [`ParticleArrays::from_f64`] picks one for the data).
    pub frame: WorldFrame,
    /// Per-particle radius parameter in world units (else the description's
    /// `radius`, else one estimated from the particle spacing).
    pub radii: Option<Vec<f32>>,
    /// Per-particle weights (masses for the cubic spline), world units.
    pub weights: Option<Vec<f32>>,
    /// A per-particle scalar attribute (colour).
    pub attribute: Option<Vec<f32>>,
    /// Per-particle species numbers: the description's `species` keeps one,
    /// and its `materials` split the particles by them.
    pub species: Option<Vec<f32>>,
}

/// The names errors give the arrays.
fn array_files() -> Vec<(&'static str, PathBuf)> {
    ["radii", "weights", "attribute"]
        .into_iter()
        .map(|w| (w, PathBuf::from(w)))
        .collect()
}

impl ParticleArrays {
    /// Particles at float64 world positions, placed in the frame the
    /// placement policy picks for them ([`WorldFrame::fit`]) in float64
    /// before they become float32, so positions far from zero (10⁹ + a
    /// small spread) keep their digits and positions of any scale keep
    /// their range; everyday data stays in the world frame, bit for bit.
    pub fn from_f64(positions: &[[f64; 3]]) -> ParticleArrays {
        let frame = WorldFrame::fit_points(positions);
        ParticleArrays {
            positions: positions.iter().map(|&p| frame.to_local(p)).collect(),
            frame,
            ..Default::default()
        }
    }

    /// The particles whose species is `species` (a number).
    fn keep(&self, species: &str) -> Result<ParticleArrays, SceneError> {
        let Some(types) = &self.species else {
            return Err(SceneError::setting(
                "particles.species",
                "a species was asked for, but the arrays give none (species = [...])",
            ));
        };
        let want: f32 = species.trim().parse().map_err(|_| {
            SceneError::setting(
                "particles.species",
                format!("'{species}' is not a species number"),
            )
        })?;
        let rows: Vec<usize> = (0..types.len()).filter(|&i| types[i] == want).collect();
        if rows.is_empty() {
            return Err(SceneError::data(
                "species",
                format!("no particle has species {species}"),
            ));
        }
        let pick = |v: &Option<Vec<f32>>| v.as_ref().map(|v| rows.iter().map(|&i| v[i]).collect());
        Ok(ParticleArrays {
            positions: rows.iter().map(|&i| self.positions[i]).collect(),
            frame: self.frame,
            radii: pick(&self.radii),
            weights: pick(&self.weights),
            attribute: pick(&self.attribute),
            species: pick(&self.species),
        })
    }

    fn check_lengths(&self) -> Result<(), SceneError> {
        let n = self.positions.len();
        for (name, v) in [
            ("radii", &self.radii),
            ("weights", &self.weights),
            ("attribute", &self.attribute),
            ("species", &self.species),
        ] {
            if let Some(v) = v
                && v.len() != n
            {
                return Err(SceneError::data(
                    name,
                    format!("{} values for {n} positions", v.len()),
                ));
            }
        }
        Ok(())
    }

    /// The arrays placed in the frame the policy picks for their reach
    /// (positions grown by the largest given radius' support): the same
    /// arrays when that is their own frame.
    fn placed(self, desc: &ParticlesDesc) -> ParticleArrays {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.positions {
            let w = self.frame.to_world(*p);
            for a in 0..3 {
                lo[a] = lo[a].min(w[a]);
                hi[a] = hi[a].max(w[a]);
            }
        }
        let kernel = match desc.kernel {
            Some(
                voxless_scene::KernelName::CubicSpline
                | voxless_scene::KernelName::WendlandC2
                | voxless_scene::KernelName::WendlandC4
                | voxless_scene::KernelName::WendlandC6,
            ) => 2.0,
            Some(voxless_scene::KernelName::QuarticSpline) => 2.5,
            Some(voxless_scene::KernelName::QuinticSpline) => 3.0,
            Some(voxless_scene::KernelName::Gaussian) => desc.sigma.unwrap_or(2.0) as f64,
            _ => 1.0,
        };
        let radius = match (desc.radius, &self.radii) {
            (Some(r), _) => r as f64,
            (None, Some(r)) => r.iter().fold(0.0f32, |m, &v| m.max(v)) as f64,
            (None, None) => 0.0,
        };
        let grow = if radius.is_finite() {
            kernel * radius
        } else {
            0.0
        };
        let fitted = WorldFrame::fit(lo.map(|v| v - grow), hi.map(|v| v + grow));
        if fitted == self.frame || self.positions.is_empty() {
            return self;
        }
        let positions = self
            .positions
            .iter()
            .map(|&p| fitted.to_local(self.frame.to_world(p)))
            .collect();
        ParticleArrays {
            positions,
            frame: fitted,
            ..self
        }
    }

    fn into_data(self) -> ParticleData {
        ParticleData {
            positions: self.positions,
            radii: self.radii,
            attribute: self.attribute,
            weights: self.weights,
        }
    }
}

/// One species' particle volume from the arrays.
fn particle_volume(
    arrays: &ParticleArrays,
    desc: &ParticlesDesc,
    notes: &mut Vec<String>,
) -> Result<voxless_particles::ParticleVolume, SceneError> {
    let arrays = match &desc.species {
        Some(s) => arrays.keep(&s.0)?,
        None => arrays.clone(),
    };
    let (frame, source) = (arrays.frame, Path::new("positions"));
    let mut data = arrays.into_data();
    // A periodic box and radii from neighbours, as a file's particles get them.
    let periodic = if desc.periodic_box.is_some() || desc.neighbours.is_some() {
        let mut world: Vec<[f64; 3]> = data.positions.iter().map(|&q| frame.to_world(q)).collect();
        let kernel = load::particles::kernel_of(
            desc,
            desc.kernel.unwrap_or(voxless_scene::KernelName::Gaussian3),
        );
        let b = load::periodic::settle(
            desc,
            None,
            &mut world,
            &mut data.radii,
            (false, true),
            kernel,
            source,
            notes,
        )?;
        if b.is_some() {
            data.positions = world.iter().map(|&q| frame.to_local(q)).collect();
        }
        b
    } else {
        None
    };
    let local = load::particles::local_box(periodic.as_ref(), &frame);
    load::particles::build_particles(data, desc, None, local, notes, frame.scale)
        .map_err(|e| e.blame(PathBuf::from("positions"), &array_files()))
}

impl AnyVolume {
    /// Particles from arrays, with `desc`'s settings (kernel, radius,
    /// cluster size, classification, maps, a species or materials; its
    /// file fields are not used) and the data's defaults; the notes say
    /// which defaults were chosen, and the frame is the arrays'.
    pub fn from_particles(
        arrays: ParticleArrays,
        desc: &ParticlesDesc,
    ) -> Result<Loaded, SceneError> {
        arrays.check_lengths()?;
        // One frame for every species and material.
        let arrays = arrays.placed(desc);
        let mut notes = Vec::new();
        let volume = match &desc.materials {
            Some(mats) => {
                load::materials::check_species(desc)?;
                let v = load::materials::build_materials(desc, mats, &mut notes, &mut |d, n| {
                    particle_volume(&arrays, d, n)
                })?;
                AnyVolume::Materials(Box::new(v))
            }
            None => AnyVolume::Particles(Box::new(particle_volume(&arrays, desc, &mut notes)?)),
        };
        Ok(Loaded {
            volume,
            frame: arrays.frame,
            notes,
        })
    }

    /// AMR leaf cells from arrays, with `desc`'s field choices and
    /// reconstruction (its file fields are not used); the frame's origin is
    /// the arrays' (or the description's) origin.
    pub fn from_amr(arrays: AmrArrays, desc: &AmrDesc) -> Result<Loaded, SceneError> {
        let (v, frame) = load::build_amr(arrays, desc, Path::new("cells"))?;
        Ok(Loaded {
            volume: AnyVolume::Amr(Box::new(v)),
            frame,
            notes: Vec::new(),
        })
    }

    /// A phase-space tessellation of N³ world positions in Lagrangian order
    /// (`(i·N + j)·N + k`, k fastest) in the periodic box `[0, box_size)³`,
    /// with `desc`'s particle mass and level of detail. Positions outside
    /// the box are an error naming the particle.
    pub fn from_tessellation(
        positions: Vec<Vec3>,
        n: usize,
        box_size: f32,
        desc: &TetsDesc,
    ) -> Result<Loaded, SceneError> {
        let grid = load::WorldGrid {
            n,
            box_size: box_size as f64,
            positions: positions
                .into_iter()
                .map(|p| p.to_array().map(f64::from))
                .collect(),
        };
        let t = TetsDesc {
            lagrangian: Some(n),
            box_size: Some(box_size),
            ..desc.clone()
        };
        let source = Path::new("positions");
        load::tets::check_grid(&grid, source)?;
        let (v, frame) = load::tets::build_world(grid, &t, source)?;
        Ok(Loaded {
            volume: AnyVolume::Tets(Box::new(v)),
            frame,
            notes: Vec::new(),
        })
    }
}
