//! Volumes from arrays in memory — the same constructors the file loaders
//! use, so in-memory data gets the same data defaults (a radius from the
//! particle spacing, …) and, through [`crate::resolve`], the same view
//! defaults. Errors name the array at fault (`positions: particle 3 has a
//! non-finite coordinate`).

use std::path::{Path, PathBuf};

use voxless_core::Vec3;
use voxless_particles::ParticleData;
use voxless_scene::{AmrDesc, ParticlesDesc, TetsDesc};

use crate::load::{self, AmrArrays};
use crate::{AnyVolume, SceneError};

/// Particle arrays in memory, one entry per particle.
#[derive(Clone, Debug, Default)]
pub struct ParticleArrays {
    pub positions: Vec<Vec3>,
    /// Per-particle radius parameter (else the description's `radius`, else
    /// one estimated from the particle spacing).
    pub radii: Option<Vec<f32>>,
    /// Per-particle weights (masses for the cubic spline).
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
    load::particles::build_particles(arrays.into_data(), desc, false, notes)
        .map_err(|e| e.blame(PathBuf::from("positions"), &array_files()))
}

impl AnyVolume {
    /// Particles from arrays, with `desc`'s settings (kernel, radius,
    /// cluster size, classification, maps, a species or materials; its
    /// file fields are not used) and the data's defaults; the notes say
    /// which defaults were chosen.
    pub fn from_particles(
        arrays: ParticleArrays,
        desc: &ParticlesDesc,
    ) -> Result<(AnyVolume, Vec<String>), SceneError> {
        arrays.check_lengths()?;
        let mut notes = Vec::new();
        let volume = match &desc.materials {
            Some(mats) => {
                if desc.species.is_some() {
                    return Err(SceneError::setting(
                        "particles.species",
                        "give the species per material, not both",
                    ));
                }
                let v = load::materials::build_materials(desc, mats, &mut notes, &mut |d, n| {
                    particle_volume(&arrays, d, n)
                })?;
                AnyVolume::Materials(Box::new(v))
            }
            None => AnyVolume::Particles(Box::new(particle_volume(&arrays, desc, &mut notes)?)),
        };
        Ok((volume, notes))
    }

    /// AMR leaf cells from arrays, with `desc`'s field choices and
    /// reconstruction (its file fields are not used).
    pub fn from_amr(arrays: AmrArrays, desc: &AmrDesc) -> Result<AnyVolume, SceneError> {
        Ok(AnyVolume::Amr(Box::new(load::build_amr(
            arrays,
            desc,
            Path::new("cells"),
        )?)))
    }

    /// A phase-space tessellation of N³ positions in Lagrangian order
    /// (`(i·N + j)·N + k`, k fastest) in the periodic box `[0, box_size)³`,
    /// with `desc`'s particle mass and level of detail.
    pub fn from_tessellation(
        positions: Vec<Vec3>,
        n: usize,
        box_size: f32,
        desc: &TetsDesc,
    ) -> Result<AnyVolume, SceneError> {
        let t = TetsDesc {
            lagrangian: Some(n),
            box_size: Some(box_size),
            ..desc.clone()
        };
        let grid = load::tets::grid_of(positions, &t)?;
        Ok(AnyVolume::Tets(Box::new(load::tets::build_tets(
            &grid,
            &t,
            Path::new("positions"),
        )?)))
    }
}
