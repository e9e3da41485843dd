//! The polygons of a VTK XML PolyData file (`<Polys>`), as triangles.

use std::path::Path;

use super::data::Source;
use super::{Arrays, as_index, no_piece, read_points, xml};
use crate::IoError;
use crate::surface::SurfaceMesh;

/// Reads the polygons of a `.vtp` file as a triangle mesh (each polygon
/// fanned from its first vertex), with the point data as per-vertex fields
/// (named as in the module docs). Vertices, lines and strips are ignored.
///
/// Fails with [`IoError::Format`] if the file is not VTK XML PolyData, has
/// no polygons, or a polygon refers to a point its piece does not have.
pub fn read_vtp_surface_bytes(bytes: &[u8], name: &Path) -> Result<SurfaceMesh, IoError> {
    let doc = xml::parse(bytes).map_err(|m| IoError::format(name, m))?;
    let err = |m: String| IoError::format(name, m);
    if doc.data_type != "PolyData" {
        return Err(err(format!(
            "expected VTK PolyData (.vtp) with <Polys> but the file holds type=\"{}\"",
            doc.data_type
        )));
    }
    if doc.pieces.is_empty() {
        return Err(err(no_piece(&doc)));
    }
    let src = Source::new(bytes, &doc);
    let mut mesh = SurfaceMesh::default();
    let mut point_arrays = Arrays::default();
    for (p, piece) in doc.pieces.iter().enumerate() {
        let base = mesh.positions.len();
        mesh.positions
            .extend(read_points(&src, p, piece).map_err(err)?);
        if mesh.positions.len() > u32::MAX as usize {
            return Err(err(format!(
                "{} points do not fit 32-bit indices",
                mesh.positions.len()
            )));
        }
        point_arrays
            .add(&src, p, "PointData", &piece.point_data, piece.points)
            .map_err(err)?;
        read_polys(&src, p, piece, base as u32, &mut mesh.triangles).map_err(err)?;
    }
    if mesh.triangles.is_empty() {
        return Err(err(
            "the PolyData has no polygons (<Polys> is empty or absent)".into(),
        ));
    }
    point_arrays.to_columns(&mut mesh.fields, None);
    Ok(mesh)
}

fn read_polys(
    src: &Source,
    p: usize,
    piece: &xml::Piece,
    base: u32,
    out: &mut Vec<[u32; 3]>,
) -> Result<(), String> {
    if piece.polys == 0 {
        return Ok(());
    }
    let array = |name: &str, tuples: Option<usize>| -> Result<Vec<f64>, String> {
        let spec = piece
            .poly_arrays
            .iter()
            .find(|a| a.name == name)
            .ok_or_else(|| format!("piece {p}: <Polys> has no '{name}' array"))?;
        src.values(spec, tuples)
            .map_err(|m| format!("piece {p}: <Polys> array '{name}': {m}"))
    };
    let offsets = array("offsets", Some(piece.polys))?;
    let connectivity = array("connectivity", None)?;
    let mut start = 0usize;
    for (i, &end) in offsets.iter().enumerate() {
        let end = as_index(end)
            .filter(|&e| e >= start && e <= connectivity.len())
            .ok_or_else(|| {
                format!(
                    "piece {p}: polygon {i} has offset {end}, outside {start}..={} (offsets must \
                     increase and stay within the connectivity entries)",
                    connectivity.len()
                )
            })?;
        let corner = |k: usize| -> Result<u32, String> {
            let v = connectivity[k];
            as_index(v)
                .filter(|&j| j < piece.points)
                .map(|j| base + j as u32)
                .ok_or_else(|| {
                    format!(
                        "piece {p}: polygon {i} refers to point {v}, but the piece has {} points",
                        piece.points
                    )
                })
        };
        // A fan from the first corner: exact for the convex polygons
        // surface writers produce.
        if end - start >= 3 {
            let first = corner(start)?;
            for k in start + 1..end - 1 {
                out.push([first, corner(k)?, corner(k + 1)?]);
            }
        }
        start = end;
    }
    Ok(())
}
