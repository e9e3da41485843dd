//! VTK XML datasets: PolyData (`.vtp`) and UnstructuredGrid (`.vtu`).
//!
//! A file is a `<VTKFile type="PolyData|UnstructuredGrid" byte_order=...
//! header_type=... compressor=...>` element holding one or more `<Piece>`s.
//! Each piece has `NumberOfPoints` (and, for a grid, `NumberOfCells`), a
//! `<Points>` array of 3-component coordinates, `<PointData>` and
//! `<CellData>` arrays, and for a grid `<Cells>` with `connectivity`,
//! `offsets` (the end of each cell in `connectivity`) and `types` arrays.
//!
//! Every `DataArray` encoding VTK's writers produce is read:
//!
//! - `format="ascii"`: whitespace-separated numbers;
//! - `format="binary"`: inline base64 of a header and the data;
//! - `format="appended"` with `offset`: the data lies in `<AppendedData
//!   encoding="raw">` (binary bytes after a `_` marker) or
//!   `encoding="base64"`, the offset counting from after the marker;
//! - `compressor="vtkZLibDataCompressor"`: binary data split into zlib blocks
//!   with a block header (nblocks, block size, last block size, compressed
//!   sizes), each block compressed on its own;
//! - `header_type="UInt32"` (the default) or `"UInt64"`;
//! - `byte_order="LittleEndian"` or `"BigEndian"`;
//! - element types `Float32`, `Float64`, `Int8`..`Int64`, `UInt8`..`UInt64`.
//!
//! Point and cell data become named `f32` columns: a 1-component array keeps
//! its name; a 3-component array `v` becomes `v_x`, `v_y`, `v_z` and its
//! magnitude `v_mag`, and a velocity (named `velocity`, `velocities`, `vel`
//! or `v`, any case) also gives `speed`; arrays of other component counts
//! become `v_0` .. `v_k`. An unnamed array is called `array<i>`. Arrays of
//! non-numeric types (`String`, `Bit`) are skipped. A dataset-level
//! `FieldData` array `TimeValue` gives the time. Pieces are concatenated; each
//! must have the same point (and cell) data arrays as the first.
//!
//! Sizes in headers and attributes are checked against the data present
//! before any buffer is allocated for them; a corrupt file gives an error,
//! never a panic or a huge allocation.
//!
//! The parser works on the whole file as bytes (appended data is addressed
//! by offset), so the memory variants [`read_vtk_points_bytes`] and
//! [`read_vtu_mesh_bytes`] take a byte slice; the path functions read the
//! file and call them.

mod data;
mod polys;
mod xml;

pub use polys::read_vtp_surface_bytes;

use std::path::Path;

use crate::{IoError, ParticleTable};
use data::Source;
use xml::{ArraySpec, Document};

/// VTK's cell type number for a linear tetrahedron.
const VTK_TETRA: f64 = 10.0;

/// A tetrahedral mesh read from a `.vtu` file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VtkMesh {
    /// Vertex positions.
    pub points: Vec<[f32; 3]>,
    /// Tetrahedra as four indices into `points`, in file order.
    pub tets: Vec<[u32; 4]>,
    /// Per-point columns, each `points.len()` long (named as in the module
    /// docs).
    pub point_data: Vec<(String, Vec<f32>)>,
    /// Per-tet columns, each `tets.len()` long: the cell data of the kept
    /// tetrahedra, with the values of skipped cells removed.
    pub cell_data: Vec<(String, Vec<f32>)>,
    /// Number of cells that are not linear tetrahedra (VTK type 10) and were
    /// left out, e.g. triangles, hexahedra or quadratic tets.
    pub skipped_cells: usize,
}

/// Reads the points of a `.vtp` or `.vtu` file (or any VTK XML dataset with
/// `<Points>`) as particles, with the point data as columns (see the module
/// docs for the naming). Cells are ignored.
///
/// Fails with [`IoError::Format`] if the file is not VTK XML, has no piece
/// or no points array, or an array is malformed, truncated, of an
/// unsupported encoding, or does not hold one tuple per point.
pub fn read_vtk_points(path: &Path) -> Result<ParticleTable, IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    read_vtk_points_bytes(&bytes, path)
}

/// [`read_vtk_points`] of a VTK XML file held in memory; `name` only labels
/// errors, which read as [`read_vtk_points`]'s for a file of that name.
pub fn read_vtk_points_bytes(bytes: &[u8], name: &Path) -> Result<ParticleTable, IoError> {
    let doc = xml::parse(bytes).map_err(|m| IoError::format(name, m))?;
    let src = Source::new(bytes, &doc);
    let err = |m: String| IoError::format(name, m);
    if doc.pieces.is_empty() {
        return Err(err(no_piece(&doc)));
    }
    let mut positions = Vec::new();
    let mut arrays = Arrays::default();
    for (p, piece) in doc.pieces.iter().enumerate() {
        positions.extend(read_points(&src, p, piece).map_err(err)?);
        arrays
            .add(&src, p, "PointData", &piece.point_data, piece.points)
            .map_err(err)?;
    }
    let time = read_time(&src, &doc).map_err(err)?;
    let mut table = ParticleTable {
        positions,
        columns: Vec::new(),
        time,
        domain: None,
        periodic: false,
        rows: None,
        sph: None,
        ..Default::default()
    };
    arrays.to_columns(&mut table.columns, None);
    if let Some([x, y, z]) = arrays.velocity_names() {
        table.derive_speed(&x, &y, &z);
    }
    Ok(table)
}

/// Reads the linear tetrahedra (VTK cell type 10) of a `.vtu` file with its
/// point and cell data. Other cell types are skipped and counted in
/// [`VtkMesh::skipped_cells`]; the cell data keeps only the tets' values.
///
/// Fails with [`IoError::Format`] if the file is not a VTK XML
/// UnstructuredGrid, an array is malformed or truncated, the `offsets` are
/// not increasing or run past `connectivity`, a tetrahedron does not have
/// four points, or a connectivity index is not a point of its piece.
pub fn read_vtu_mesh(path: &Path) -> Result<VtkMesh, IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    read_vtu_mesh_bytes(&bytes, path)
}

/// [`read_vtu_mesh`] of a VTK XML file held in memory; `name` only labels
/// errors, which read as [`read_vtu_mesh`]'s for a file of that name.
pub fn read_vtu_mesh_bytes(bytes: &[u8], name: &Path) -> Result<VtkMesh, IoError> {
    let doc = xml::parse(bytes).map_err(|m| IoError::format(name, m))?;
    let err = |m: String| IoError::format(name, m);
    if doc.data_type != "UnstructuredGrid" {
        return Err(err(format!(
            "expected a VTK UnstructuredGrid (.vtu) but the file holds type=\"{}\"",
            doc.data_type
        )));
    }
    if doc.pieces.is_empty() {
        return Err(err(no_piece(&doc)));
    }
    let src = Source::new(bytes, &doc);
    let mut mesh = VtkMesh::default();
    let mut point_arrays = Arrays::default();
    let mut cell_arrays = Arrays::default();
    let mut kept = Vec::new();
    let mut cell_base = 0usize;
    for (p, piece) in doc.pieces.iter().enumerate() {
        let base = mesh.points.len();
        mesh.points.extend(
            read_points(&src, p, piece)
                .map_err(err)?
                .into_iter()
                .map(|q| q.map(|c| c as f32)),
        );
        if mesh.points.len() > u32::MAX as usize {
            return Err(err(format!(
                "{} points do not fit 32-bit tet indices",
                mesh.points.len()
            )));
        }
        point_arrays
            .add(&src, p, "PointData", &piece.point_data, piece.points)
            .map_err(err)?;
        cell_arrays
            .add(&src, p, "CellData", &piece.cell_data, piece.cells)
            .map_err(err)?;
        let skipped = read_tets(
            &src,
            p,
            piece,
            base as u32,
            cell_base,
            &mut mesh.tets,
            &mut kept,
        )
        .map_err(err)?;
        mesh.skipped_cells += skipped;
        cell_base += piece.cells;
    }
    point_arrays.to_columns(&mut mesh.point_data, None);
    cell_arrays.to_columns(&mut mesh.cell_data, Some(&kept));
    Ok(mesh)
}

fn no_piece(doc: &Document) -> String {
    format!(
        "the {} file holds no <Piece> (a parallel P* file only lists other files)",
        if doc.data_type.is_empty() {
            "VTK"
        } else {
            &doc.data_type
        }
    )
}

/// The positions of one piece.
fn read_points(src: &Source, p: usize, piece: &xml::Piece) -> Result<Vec<[f64; 3]>, String> {
    let spec = piece
        .points_array
        .as_ref()
        .ok_or_else(|| format!("piece {p} has no <Points> array"))?;
    if spec.components != 3 {
        return Err(format!(
            "piece {p}: <Points> has {} components, expected 3",
            spec.components
        ));
    }
    let values = src.values(spec, Some(piece.points)).map_err(|m| {
        format!(
            "piece {p}: <Points> array (NumberOfPoints={}): {m}",
            piece.points
        )
    })?;
    Ok(values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// The `TimeValue` field-data array, when present.
fn read_time(src: &Source, doc: &Document) -> Result<Option<f64>, String> {
    let Some(spec) = doc
        .field_data
        .iter()
        .find(|a| a.name == "TimeValue" && a.scalar.is_some())
    else {
        return Ok(None);
    };
    let values = src
        .values(spec, spec.tuples)
        .map_err(|m| format!("FieldData array 'TimeValue': {m}"))?;
    Ok(values.first().copied())
}

/// Reads the cells of one piece, appending its tets (indices offset by
/// `base`) and the global indices of the kept cells. Returns the number of
/// skipped cells.
fn read_tets(
    src: &Source,
    p: usize,
    piece: &xml::Piece,
    base: u32,
    cell_base: usize,
    tets: &mut Vec<[u32; 4]>,
    kept: &mut Vec<usize>,
) -> Result<usize, String> {
    if piece.cells == 0 {
        return Ok(0);
    }
    let array = |name: &str, tuples: Option<usize>| -> Result<Vec<f64>, String> {
        let spec = piece
            .cell_arrays
            .iter()
            .find(|a| a.name == name)
            .ok_or_else(|| format!("piece {p}: <Cells> has no '{name}' array"))?;
        src.values(spec, tuples)
            .map_err(|m| format!("piece {p}: <Cells> array '{name}': {m}"))
    };
    let types = array("types", Some(piece.cells))?;
    let offsets = array("offsets", Some(piece.cells))?;
    let connectivity = array("connectivity", None)?;
    let mut start = 0usize;
    let mut skipped = 0;
    for (i, (&ty, &end)) in types.iter().zip(&offsets).enumerate() {
        let end = as_index(end)
            .filter(|&e| e >= start && e <= connectivity.len())
            .ok_or_else(|| {
                format!(
                    "piece {p}: cell {i} has offset {end}, outside {start}..={} (offsets must \
                     increase and stay within the {} connectivity entries)",
                    connectivity.len(),
                    connectivity.len()
                )
            })?;
        if ty == VTK_TETRA {
            if end - start != 4 {
                return Err(format!(
                    "piece {p}: cell {i} is a tetrahedron with {} points",
                    end - start
                ));
            }
            let mut tet = [0u32; 4];
            for (slot, &v) in tet.iter_mut().zip(&connectivity[start..end]) {
                let index = as_index(v).filter(|&j| j < piece.points).ok_or_else(|| {
                    format!(
                        "piece {p}: cell {i} refers to point {v}, but the piece has {} points",
                        piece.points
                    )
                })?;
                *slot = base + index as u32;
            }
            tets.push(tet);
            kept.push(cell_base + i);
        } else {
            skipped += 1;
        }
        start = end;
    }
    Ok(skipped)
}

/// A non-negative integral value as an index.
fn as_index(v: f64) -> Option<usize> {
    (v >= 0.0 && v.fract() == 0.0 && v < usize::MAX as f64).then_some(v as usize)
}

/// Point or cell data arrays gathered over all pieces.
#[derive(Default)]
struct Arrays {
    /// Name, components, values (all pieces so far).
    arrays: Vec<(String, usize, Vec<f64>)>,
}

impl Arrays {
    /// Adds the arrays of one piece, which must match those of the first.
    fn add(
        &mut self,
        src: &Source,
        p: usize,
        section: &str,
        specs: &[ArraySpec],
        tuples: usize,
    ) -> Result<(), String> {
        let numeric: Vec<&ArraySpec> = specs.iter().filter(|a| a.scalar.is_some()).collect();
        if p == 0 {
            // Every component becomes a column, even when there are no
            // tuples to check the count against. A file with data holds at
            // least one byte per value, so more components than bytes is a
            // corrupt header (that would allocate billions of columns).
            let total = numeric
                .iter()
                .fold(0usize, |sum, a| sum.saturating_add(a.components));
            if total > src.bytes.len() {
                return Err(format!(
                    "the {section} arrays declare {total} components in all, more than the \
                     file's {} bytes can describe",
                    src.bytes.len()
                ));
            }
            for (i, spec) in numeric.iter().enumerate() {
                let name = if spec.name.is_empty() {
                    format!("array{i}")
                } else {
                    spec.name.clone()
                };
                self.arrays.push((name, spec.components, Vec::new()));
            }
        } else if numeric.len() != self.arrays.len() {
            return Err(format!(
                "piece {p} has {} {section} arrays but piece 0 has {}",
                numeric.len(),
                self.arrays.len()
            ));
        }
        for (spec, (name, components, values)) in numeric.iter().zip(&mut self.arrays) {
            if spec.components != *components {
                return Err(format!(
                    "piece {p}: {section} array '{name}' has {} components, piece 0 has \
                     {components}",
                    spec.components
                ));
            }
            let v = src.values(spec, Some(tuples)).map_err(|m| {
                format!("piece {p}: {section} array '{name}' ({tuples} tuples): {m}")
            })?;
            values.extend(v);
        }
        Ok(())
    }

    /// The component column names of the first velocity-like vector.
    fn velocity_names(&self) -> Option<[String; 3]> {
        self.arrays
            .iter()
            .find(|(name, c, _)| *c == 3 && is_velocity(name))
            .map(|(name, _, _)| {
                [
                    format!("{name}_x"),
                    format!("{name}_y"),
                    format!("{name}_z"),
                ]
            })
    }

    /// Appends the columns (see the module docs for the naming). With
    /// `keep`, only those tuples are kept, in that order.
    fn to_columns(&self, out: &mut Vec<(String, Vec<f32>)>, keep: Option<&[usize]>) {
        for (name, components, values) in &self.arrays {
            let c = *components;
            let rows: Vec<usize> = match keep {
                Some(k) => k.to_vec(),
                None => (0..values.len() / c).collect(),
            };
            let component =
                |k: usize| -> Vec<f32> { rows.iter().map(|r| values[r * c + k] as f32).collect() };
            match c {
                1 => out.push((name.clone(), component(0))),
                3 => {
                    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
                        out.push((format!("{name}_{axis}"), component(k)));
                    }
                    let mag = rows
                        .iter()
                        .map(|r| {
                            let v = &values[r * 3..r * 3 + 3];
                            (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt() as f32
                        })
                        .collect();
                    out.push((format!("{name}_mag"), mag));
                }
                _ => {
                    for k in 0..c {
                        out.push((format!("{name}_{k}"), component(k)));
                    }
                }
            }
        }
    }
}

fn is_velocity(name: &str) -> bool {
    ["velocity", "velocities", "vel", "v"]
        .iter()
        .any(|v| name.eq_ignore_ascii_case(v))
}
