//! The point and ray index of a mesh: a BVH built by the operations that
//! ask about single points or rays (point samples, shadow rays, per-ray
//! line integrals), never by projections or tile renders.
//!
//! A lean mesh's primitives are its cells at each image shift their corners
//! reach the box at (a cell's hull holds its six tets, and a tet's images
//! are among its cell's): about N³ boxes instead of 6N³, and the tets of a
//! primitive are derived when a query reaches it. An explicit mesh's
//! primitives are its tets.

use rayon::prelude::*;
use voxless_bvh::Bvh;
use voxless_core::{Aabb, Range1, Ray, Vec3};

use crate::lattice::offset;
use crate::mesh::{Tet, TetMesh};

/// A cell at one image shift: the cell's index `(i·N + j)·N + k` and the
/// shift, packed as `cell · 27 + shift code`.
type CellImage = u64;

fn pack(cell: usize, shift: [i8; 3]) -> CellImage {
    let code = (shift[0] + 1) as u64 * 9 + (shift[1] + 1) as u64 * 3 + (shift[2] + 1) as u64;
    cell as u64 * 27 + code
}

fn unpack(p: CellImage) -> (usize, [i8; 3]) {
    let code = (p % 27) as i8;
    (
        (p / 27) as usize,
        [code / 9 - 1, (code / 3) % 3 - 1, code % 3 - 1],
    )
}

pub(crate) struct TetIndex {
    bvh: Bvh,
    /// Lean meshes: the cell image of each primitive (empty for explicit
    /// meshes, whose primitive i is tet i).
    cells: Vec<CellImage>,
}

impl TetIndex {
    pub fn build(mesh: &TetMesh) -> TetIndex {
        if let Some(tets) = mesh.explicit_tets() {
            let boxes: Vec<Aabb> = tets.par_iter().map(|t| t.bounds()).collect();
            return TetIndex {
                bvh: Bvh::build(&boxes),
                cells: Vec::new(),
            };
        }
        let Some(lattice) = mesh.lattice() else {
            unreachable!("a mesh is lean or explicit")
        };
        // The Lagrangian blocks the mesh covers, each block's cells with the
        // images their corners reach.
        let per_block: Vec<Vec<(CellImage, Aabb)>> = mesh
            .lagrangian_blocks()
            .par_iter()
            .map(|&b| {
                let mut out = Vec::new();
                lattice.cell_images(b, |cell, shift, _, _, bounds| {
                    out.push((pack(cell, shift), bounds));
                });
                out
            })
            .collect();
        let count: usize = per_block.iter().map(Vec::len).sum();
        let mut cells = Vec::with_capacity(count);
        let mut boxes = Vec::with_capacity(count);
        for (c, b) in per_block.into_iter().flatten() {
            cells.push(c);
            boxes.push(b);
        }
        let bvh = Bvh::build(&boxes);
        TetIndex { bvh, cells }
    }

    /// Calls `f` with every tet of primitive `prim`.
    #[inline]
    fn tets_of(&self, mesh: &TetMesh, prim: u32, f: &mut impl FnMut(&Tet)) {
        match mesh.lattice() {
            None => {
                if let Some(t) = mesh.explicit_tets().and_then(|t| t.get(prim as usize)) {
                    f(t);
                }
            }
            Some(lattice) => {
                let (cell, shift) = unpack(self.cells[prim as usize]);
                let n = lattice.n;
                let (i, j, k) = (cell / (n * n), (cell / n) % n, cell % n);
                let corners = lattice.cell_corners(i, j, k);
                let off = offset(shift, lattice.l);
                lattice.cell_tets::<true>(&corners, shift, off, &mut |(_, t)| f(&t));
            }
        }
    }

    /// Calls `f` with every tet whose primitive's box contains `p` (a
    /// superset of the tets containing it).
    pub fn at_point(&self, mesh: &TetMesh, p: Vec3, mut f: impl FnMut(&Tet)) {
        self.bvh.point_query(p, |i| self.tets_of(mesh, i, &mut f));
    }

    /// Calls `f` with every tet whose primitive's box `ray` meets within `t`
    /// (a superset of the tets it crosses there).
    pub fn along_ray(&self, mesh: &TetMesh, ray: &Ray, t: Range1, mut f: impl FnMut(&Tet)) {
        self.bvh
            .ray_query(ray, t, |i, _| self.tets_of(mesh, i, &mut f));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_images_pack_and_unpack() {
        for cell in [0usize, 1, 12345, 1 << 40] {
            for x in -1..=1 {
                for y in -1..=1 {
                    for z in -1..=1 {
                        assert_eq!(unpack(pack(cell, [x, y, z])), (cell, [x, y, z]));
                    }
                }
            }
        }
    }
}
