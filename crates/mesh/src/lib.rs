//! Triangle meshes rendered beside volumes: the simulation's geometry (a
//! tank, an obstacle, an aircraft) drawn opaque, with the volume integrated
//! only up to the nearest surface along each ray (ExaBricks §7).
//!
//! The model:
//! - [`Mesh`] is what a file holds: vertices, triangles (vertex indices)
//!   and optional per-vertex fields. [`Mesh::validate`] names the first bad
//!   index or non-finite vertex.
//! - [`Surfaces`] is what a render uses: every mesh of a scene merged, with
//!   a colour per vertex ([`Paint`]), smooth normals per triangle corner
//!   (area weighted over the faces around the vertex, creases sharper than
//!   40° kept, so a box stays flat-shaded) and a BVH over the
//!   triangles' boxes. It is an `Arc` handle: cloning is free, equality is
//!   identity.
//! - Rays ask for the [`Surfaces::nearest`] hit (closest-hit BVH traversal,
//!   front to back, pruning behind the nearest hit so far) or whether
//!   anything is hit at all ([`Surfaces::occluded`], for shadow and
//!   ambient-occlusion rays). Triangles are tested watertight
//!   ([`triangle`]): no ray slips between two triangles that share an edge.
//! - Instances (mirror images) are the caller's: it reflects the ray, asks,
//!   and reflects the hit's normal back (see `voxless-render`).
//!
//! Invariants: every triangle's indices are in range and every vertex is
//! finite (checked when building); hit normals are unit length and face the
//! ray; hit distances are strictly inside the asked range.

pub mod triangle;

use std::sync::Arc;

use rayon::prelude::*;

use voxless_bvh::Bvh;
use voxless_core::{Aabb, Range1, Ray, Vec3};

use triangle::{RayFrame, intersect};

/// Why a mesh cannot be used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    #[error("triangle {triangle} refers to vertex {vertex}, but there are {vertices} vertices")]
    Index {
        triangle: usize,
        vertex: u32,
        vertices: usize,
    },
    #[error("vertex {0} is not finite")]
    NonFinite(usize),
    #[error("field `{name}` has {got} values for {vertices} vertices")]
    FieldLength {
        name: String,
        got: usize,
        vertices: usize,
    },
    #[error("the mesh has no triangles")]
    Empty,
    #[error("{0} triangles: more than a u32 index can address")]
    TooLarge(usize),
}

/// A triangle mesh as read from a file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex scalar fields, by name.
    pub fields: Vec<(String, Vec<f32>)>,
}

impl Mesh {
    /// The first problem: an out-of-range index, a non-finite vertex, a
    /// field of the wrong length, or no triangles at all.
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        let n = self.positions.len();
        if let Some(i) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinite(i));
        }
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::Index {
                    triangle: t,
                    vertex: v,
                    vertices: n,
                });
            }
        }
        for (name, f) in &self.fields {
            if f.len() != n {
                return Err(MeshError::FieldLength {
                    name: name.clone(),
                    got: f.len(),
                    vertices: n,
                });
            }
        }
        Ok(())
    }

    /// The per-vertex field `name` (exact match first, then ignoring case).
    pub fn field(&self, name: &str) -> Option<&[f32]> {
        self.fields
            .iter()
            .find(|(n, _)| n == name)
            .or_else(|| {
                self.fields
                    .iter()
                    .find(|(n, _)| n.eq_ignore_ascii_case(name))
            })
            .map(|(_, f)| f.as_slice())
    }

    /// The box around the vertices that triangles use.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for tri in &self.triangles {
            for &v in tri {
                if let Some(p) = self.positions.get(v as usize) {
                    b.grow(Vec3::from_array(*p));
                }
            }
        }
        b
    }
}

/// How a mesh is coloured (linear RGB).
#[derive(Clone, Debug, PartialEq)]
pub enum Paint {
    Solid([f32; 3]),
    /// One colour per vertex (a colour-mapped field), interpolated.
    PerVertex(Vec<[f32; 3]>),
}

/// The nearest surface along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Unit shading normal, facing the ray.
    pub normal: Vec3,
    /// Linear RGB.
    pub color: Vec3,
}

struct Geometry {
    positions: Vec<Vec3>,
    /// Per triangle corner.
    normals: Vec<[Vec3; 3]>,
    colors: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    bvh: Bvh,
}

/// Every mesh of a scene, ready for rays (see the crate docs).
#[derive(Clone)]
pub struct Surfaces(Arc<Geometry>);

impl PartialEq for Surfaces {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.0, &o.0)
    }
}

impl std::fmt::Debug for Surfaces {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Surfaces({} triangles)", self.triangle_count())
    }
}

impl Surfaces {
    /// Merges `meshes` (each validated; a per-vertex paint must have one
    /// colour per vertex), computes vertex normals and builds the BVH.
    pub fn new(meshes: &[(&Mesh, &Paint)]) -> Result<Surfaces, MeshError> {
        let mut g = Geometry {
            positions: Vec::new(),
            normals: Vec::new(),
            colors: Vec::new(),
            triangles: Vec::new(),
            bvh: Bvh::default(),
        };
        for (mesh, paint) in meshes {
            mesh.validate()?;
            let base = g.positions.len();
            if base + mesh.positions.len() > u32::MAX as usize {
                return Err(MeshError::TooLarge(base + mesh.positions.len()));
            }
            g.positions
                .extend(mesh.positions.iter().map(|p| Vec3::from_array(*p)));
            match paint {
                Paint::Solid(c) => g.colors.extend(std::iter::repeat_n(
                    Vec3::from_array(*c),
                    mesh.positions.len(),
                )),
                Paint::PerVertex(cs) => {
                    if cs.len() != mesh.positions.len() {
                        return Err(MeshError::FieldLength {
                            name: "colour".into(),
                            got: cs.len(),
                            vertices: mesh.positions.len(),
                        });
                    }
                    g.colors.extend(cs.iter().map(|c| Vec3::from_array(*c)));
                }
            }
            g.triangles
                .extend(mesh.triangles.iter().map(|t| t.map(|v| v + base as u32)));
        }
        g.normals = corner_normals(&g.positions, &g.triangles);
        let boxes: Vec<Aabb> = g
            .triangles
            .iter()
            .map(|t| {
                let mut b = Aabb::EMPTY;
                for &v in t {
                    b.grow(g.positions[v as usize]);
                }
                b
            })
            .collect();
        g.bvh = Bvh::build(&boxes);
        Ok(Surfaces(Arc::new(g)))
    }

    pub fn triangle_count(&self) -> usize {
        self.0.triangles.len()
    }

    /// The box around every triangle.
    pub fn bounds(&self) -> Aabb {
        self.0.bvh.bounds()
    }

    /// Bytes held (geometry and BVH).
    pub fn memory_bytes(&self) -> usize {
        let g = &self.0;
        (g.positions.len() + g.colors.len()) * 12
            + g.normals.len() * 36
            + g.triangles.len() * 12
            + g.bvh.memory_bytes()
    }

    /// The nearest hit strictly inside `t`.
    pub fn nearest(&self, ray: &Ray, t: Range1) -> Option<Hit> {
        let g = &self.0;
        let frame = RayFrame::new(ray);
        let mut best: Option<(u32, triangle::TriangleHit)> = None;
        g.bvh.ray_closest(ray, t, |i, t_max| {
            let [a, b, c] = g.triangles[i as usize].map(|v| g.positions[v as usize]);
            let h = intersect(&frame, a, b, c, Range1::new(t.lo, t_max))?;
            best = Some((i, h));
            Some(h.t)
        });
        let (i, h) = best?;
        let tri = g.triangles[i as usize];
        let [a, b, c] = tri.map(|v| g.positions[v as usize]);
        let geometric = (b - a).cross(c - a).normalized();
        let facing = if geometric.dot(ray.dir) > 0.0 {
            -1.0
        } else {
            1.0
        };
        let ng = geometric * facing;
        let w = h.weights;
        let mix = |v: &[Vec3]| {
            v[tri[0] as usize] * w[0] + v[tri[1] as usize] * w[1] + v[tri[2] as usize] * w[2]
        };
        let nc = g.normals[i as usize];
        let mut n = nc[0] * w[0] + nc[1] * w[1] + nc[2] * w[2];
        // Smooth normals where the vertices have one; the face normal on a
        // crease the interpolation cancels out.
        n = if n.length_squared() > 1e-12 {
            n.normalized()
        } else {
            ng
        };
        if n.dot(ng) < 0.0 {
            n = n * -1.0;
        }
        Some(Hit {
            t: h.t,
            normal: n,
            color: mix(&g.colors),
        })
    }

    /// Whether anything is hit strictly inside `t` (shadow and occlusion
    /// rays): stops at the first triangle found.
    pub fn occluded(&self, ray: &Ray, t: Range1) -> bool {
        let g = &self.0;
        let frame = RayFrame::new(ray);
        let mut hit = false;
        g.bvh.ray_closest(ray, t, |i, t_max| {
            let [a, b, c] = g.triangles[i as usize].map(|v| g.positions[v as usize]);
            intersect(&frame, a, b, c, Range1::new(t.lo, t_max))?;
            hit = true;
            // Nothing can be nearer than −∞: the traversal ends here.
            Some(f32::NEG_INFINITY)
        });
        hit
    }

    /// Every hit along `ray` inside `t`, nearest first: what tests count
    /// crossings with.
    pub fn all_hits(&self, ray: &Ray, t: Range1) -> Vec<f32> {
        let g = &self.0;
        let frame = RayFrame::new(ray);
        let mut out = Vec::new();
        // The closest-hit traversal that never shrinks its range visits
        // every leaf the ray touches (faces included).
        g.bvh.ray_closest(ray, t, |i, _| {
            let [a, b, c] = g.triangles[i as usize].map(|v| g.positions[v as usize]);
            if let Some(h) = intersect(&frame, a, b, c, t) {
                out.push(h.t);
            }
            None
        });
        out.sort_by(f32::total_cmp);
        out
    }
}

/// Cosine of the crease angle: faces meeting at a sharper angle than this
/// (40°) keep their own normal at the shared vertex, so a box stays a box
/// while a marching-cubes surface shades smoothly.
const CREASE_COS: f32 = 0.766;

/// Smooth normals per triangle corner: at each corner, the area-weighted
/// sum of the face normals around the vertex that lie within the crease
/// angle of this face's normal (zero for a degenerate face).
fn corner_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<[Vec3; 3]> {
    // The cross product's length is twice the area: the weight.
    let face: Vec<Vec3> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            (b - a).cross(c - a)
        })
        .collect();
    // Faces around each vertex (CSR).
    let mut start = vec![0u32; positions.len() + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..positions.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut around = vec![0u32; start[positions.len()] as usize];
    for (f, t) in triangles.iter().enumerate() {
        for &v in t {
            around[fill[v as usize] as usize] = f as u32;
            fill[v as usize] += 1;
        }
    }
    let unit = |v: Vec3| {
        if v.length_squared() > 0.0 {
            v.normalized()
        } else {
            Vec3::ZERO
        }
    };
    triangles
        .par_iter()
        .enumerate()
        .map(|(f, t)| {
            let nf = unit(face[f]);
            t.map(|v| {
                let faces = &around[start[v as usize] as usize..start[v as usize + 1] as usize];
                let mut n = Vec3::ZERO;
                for &g in faces {
                    if unit(face[g as usize]).dot(nf) >= CREASE_COS {
                        n += face[g as usize];
                    }
                }
                unit(n)
            })
        })
        .collect()
}

/// A cosine-weighted direction in the hemisphere around unit `n`, from two
/// uniform numbers in `[0, 1)` (ambient occlusion rays).
pub fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    // Orthonormal basis around n (Duff et al. 2017), no branch on a pole.
    let s = 1.0f32.copysign(n.z);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t1 = Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let t2 = Vec3::new(b, s + n.y * n.y * a, -n.y);
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    (t1 * (r * phi.cos()) + t2 * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalized()
}

#[cfg(test)]
mod tests;
