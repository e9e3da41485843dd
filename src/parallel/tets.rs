//! Phase-space tessellations over the ranks.
//!
//! Each rank reads a slab of Lagrangian planes through the one-process
//! reader (`crate::load::tets::read_grid`) — the block rows
//! `nb·r/K .. nb·(r+1)/K` of 8-cell blocks, plus the next plane, which the
//! cells of the last row reach into — and tessellates it exactly as one
//! process would ([`TetMesh::from_slab`]): the whole mesh is the slabs'
//! meshes in rank order. So the default density range (a percentile of
//! every k-th tet in mesh order) is found exactly: the ranks count their
//! tets, each knows its tets' mesh indices, and the chosen densities are
//! gathered. Tets then go to the boxes their bounds overlap (renders and
//! samples), or to the one box holding their centroid (projections, whose
//! columns add up), degenerate tets' point masses with them.

use std::path::{Path, PathBuf};

use voxless_core::{Aabb, Vec3};
use voxless_parallel::{Comm, CommExt, Reader, Writer};
use voxless_scene::TetsDesc;
use voxless_tets::{
    LagrangianSlab, Tet, TetMesh, TetMeshBuilder, TetSettings, TetVolume, density_range,
    density_stride,
};

use super::share::{exchange, outboxes, root_box};
use super::{ParallelError, Part, PartCounts};
use crate::load::tets::{box_frame, particle_mass, read_grid, slab_planes};
use crate::load::whole_set::agree;
use crate::load::{Purpose, Share};
use crate::projection::pixel_integral;
use crate::{AnyVolume, Fields, SceneError, VolumeKind, VolumeSummary, WorldFrame};

/// This rank's slab of the run `t` names, placed in the frame its box
/// picks (as one process places the whole grid), with that frame and the
/// particle mass in it.
fn read_slab(
    t: &TetsDesc,
    base: &Path,
    share: Share,
    notes: &mut Vec<String>,
) -> Result<(LagrangianSlab, WorldFrame, f64, PathBuf), SceneError> {
    let (grid, path) = read_grid(t, base, Some(share), notes)?;
    let frame = box_frame(grid.box_size);
    let local_box = (grid.box_size / frame.scale) as f32;
    let mass = particle_mass(t, grid.n, local_box, grid.box_size, frame.scale)?;
    let (rows, first, _, planes) = slab_planes(grid.n, share);
    let slab = LagrangianSlab {
        n: grid.n,
        box_size: local_box,
        rows,
        first_plane: first,
        planes,
        positions: grid.positions.iter().map(|&p| frame.to_local(p)).collect(),
    };
    Ok((slab, frame, mass, path))
}

pub(crate) fn open(
    comm: &dyn Comm,
    t: &TetsDesc,
    base: &Path,
    purpose: Purpose,
) -> Result<Part, ParallelError> {
    let mut notes = Vec::new();
    let share = Share {
        rank: comm.rank(),
        ranks: comm.size(),
    };
    let (slab, frame, mass, path) = agree(comm, read_slab(t, base, share, &mut notes))?;
    let settings = TetSettings {
        particle_mass: Some(mass),
        ..Default::default()
    };
    let read = slab.positions.len() as u64;
    let mesh = agree(
        comm,
        TetMesh::from_slab(&slab, &settings).map_err(|e| SceneError::Tets {
            path: path.clone(),
            source: e,
        }),
    )?;
    drop(slab);
    // The mesh index of this rank's first tet, and the sampled tets (a
    // lean mesh derives its tets block by block).
    let counts = comm.all_gather_f64(&[mesh.tet_count() as f64])?;
    let before: usize = counts[..comm.rank()].iter().map(|c| c[0] as usize).sum();
    let total: usize = counts.iter().map(|c| c[0] as usize).sum();
    let stride = density_stride(total);
    let mut w = Writer::new();
    let mut buf = Vec::new();
    for (b, block) in mesh.blocks().iter().enumerate() {
        let tets = mesh.block_tets(b, &mut buf);
        for (i, tet) in (block.tets.start as usize..).zip(tets) {
            if (before + i).is_multiple_of(stride) {
                w.f32(tet.density);
                w.vec3(centroid(tet));
            }
        }
    }
    let (mut densities, mut centroids) = (Vec::new(), Vec::new());
    for msg in comm.all_gather(&w.into_bytes())? {
        let mut r = Reader::new(&msg);
        while !r.is_done() {
            densities.push(r.f32()?);
            centroids.push((r.vec3()?, 1.0));
        }
    }
    let value_range = density_range(&mesh, &mut densities);
    let l = mesh.box_size;
    let bounds = Aabb::new(Vec3::ZERO, Vec3::splat(l));
    let decomposition =
        voxless_parallel::Decomposition::build(root_box(bounds), &centroids, comm.size());
    // Tets to boxes, block by block.
    let mut out = outboxes(comm);
    let mut dst = Vec::new();
    let mut per: Vec<Vec<u32>> = vec![Vec::new(); comm.size()];
    for (b, block) in mesh.blocks().iter().enumerate() {
        for list in &mut per {
            list.clear();
        }
        let tets = mesh.block_tets(b, &mut buf);
        for (i, tet) in tets.iter().enumerate() {
            match purpose {
                Purpose::Render => decomposition.overlapping(&tet.bounds(), &mut dst),
                Purpose::Project => {
                    dst.clear();
                    dst.push(decomposition.owner(centroid(tet)));
                }
            }
            for &r in &dst {
                per[r].push(i as u32);
            }
        }
        for (r, list) in per.iter().enumerate() {
            if list.is_empty() {
                continue;
            }
            let w = &mut out[r];
            w.u8(0);
            w.u32(block.lagrangian);
            w.u64(list.len() as u64);
            for &i in list {
                let tet = &tets[i as usize];
                for v in tet.v {
                    w.vec3(v);
                }
                w.f32(tet.density);
            }
        }
    }
    for &(p, m) in mesh.point_masses() {
        let w = &mut out[decomposition.owner(p)];
        w.u8(1);
        w.vec3(p);
        w.f64(m);
    }
    let (n, tet_mass, mean_volume) = (mesh.n, mesh.tet_mass, mesh.mean_volume);
    drop(mesh);
    let mut local = TetMeshBuilder::new(n, l, tet_mass, mean_volume);
    // Decoded straight into the mesh, message by message (each freed once
    // read), in source order and, within a source, Lagrangian block order.
    for msg in exchange(comm, out)? {
        let mut r = Reader::new(&msg);
        while !r.is_done() {
            if r.u8()? == 1 {
                local.push_point_mass(r.vec3()?, r.f64()?);
                continue;
            }
            let lagrangian = r.u32()?;
            let count = r.u64()? as usize;
            let mut tets = Vec::with_capacity(count);
            for _ in 0..count {
                let v = [r.vec3()?, r.vec3()?, r.vec3()?, r.vec3()?];
                tets.push(Tet {
                    v,
                    density: r.f32()?,
                });
            }
            local.push_block(lagrangian, tets);
        }
    }
    let held = local.tet_count() as u64;
    let local = local.build();
    let volume =
        TetVolume::from_parts(local, value_range).with_pixel_integral(pixel_integral(t.pixels));
    Ok(Part {
        volume: Some(AnyVolume::Tets(Box::new(volume))),
        frame,
        summary: VolumeSummary {
            kind: VolumeKind::Tets,
            bounds,
            value_range,
            attribute_range: None,
        },
        decomposition,
        fields: Fields::Tets { box_size: l, n },
        counts: PartCounts { read, held },
        notes,
        radii: None,
    })
}

fn centroid(t: &Tet) -> Vec3 {
    (t.v[0] + t.v[1] + t.v[2] + t.v[3]) * 0.25
}
