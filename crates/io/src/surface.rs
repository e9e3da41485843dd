//! Triangle meshes for surfaces drawn beside volumes: PLY (ASCII and
//! binary, read with `ply-rs-bw`), Wavefront OBJ (`tobj`), STL (ASCII and
//! binary, `stl_io`) and VTK XML PolyData `.vtp` (this crate's VTK reader).
//!
//! Polygons are fanned into triangles. Per-vertex scalar properties become
//! fields a mesh can be coloured by: PLY vertex properties other than the
//! position (e.g. `pressure`, `nx`), VTP point data. OBJ and STL carry none.
//! Indices are checked against the vertex count here, so a corrupt file
//! names the polygon and the index.

use std::io::{BufReader, Cursor};
use std::path::Path;

use crate::IoError;

/// A triangle mesh as read from a file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceMesh {
    /// Vertex positions in float64, so that a mesh far from the origin
    /// keeps its digits until the library moves it into the data's frame.
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex scalar fields, by name.
    pub fields: Vec<(String, Vec<f32>)>,
}

/// The mesh formats, by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceFormat {
    Ply,
    Obj,
    Stl,
    Vtp,
}

impl SurfaceFormat {
    /// The format of `path` by its extension (any case).
    pub fn of(path: &Path) -> Option<SurfaceFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "ply" => SurfaceFormat::Ply,
            "obj" => SurfaceFormat::Obj,
            "stl" => SurfaceFormat::Stl,
            "vtp" => SurfaceFormat::Vtp,
            _ => return None,
        })
    }
}

/// Reads the triangle mesh in `path` (format by extension).
pub fn read_surface(path: &Path) -> Result<SurfaceMesh, IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    read_surface_bytes(&bytes, path)
}

/// [`read_surface`] of a file held in memory; `name` gives the format (by
/// extension) and labels errors.
pub fn read_surface_bytes(bytes: &[u8], name: &Path) -> Result<SurfaceMesh, IoError> {
    let format = SurfaceFormat::of(name).ok_or_else(|| {
        IoError::format(
            name,
            "not a mesh file: expected the extension .ply, .obj, .stl or .vtp",
        )
    })?;
    let mesh = match format {
        SurfaceFormat::Ply => read_ply(bytes).map_err(|m| IoError::format(name, m))?,
        SurfaceFormat::Obj => read_obj(bytes).map_err(|m| IoError::format(name, m))?,
        SurfaceFormat::Stl => read_stl(bytes).map_err(|m| IoError::format(name, m))?,
        SurfaceFormat::Vtp => crate::vtk::read_vtp_surface_bytes(bytes, name)?,
    };
    check(&mesh).map_err(|m| IoError::format(name, m))?;
    Ok(mesh)
}

/// Indices in range, finite positions, at least one triangle.
fn check(mesh: &SurfaceMesh) -> Result<(), String> {
    if mesh.triangles.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    let n = mesh.positions.len();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if let Some(v) = tri.iter().find(|&&v| v as usize >= n) {
            return Err(format!(
                "face {t} refers to vertex {v}, but there are {n} vertices"
            ));
        }
    }
    if let Some(i) = mesh
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(format!("vertex {i} has a non-finite coordinate"));
    }
    Ok(())
}

/// Fans polygon `poly` (vertex indices) into `out`.
fn fan(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    for k in 1..poly.len().saturating_sub(1) {
        out.push([poly[0], poly[k], poly[k + 1]]);
    }
}

mod ply {
    use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};

    /// A vertex: its scalar properties in header order.
    pub struct Vertex(pub Vec<f64>);

    /// A face: its vertex index list.
    pub struct Face(pub Vec<i64>);

    fn scalar(p: &Property) -> Option<f64> {
        Some(match *p {
            Property::Char(v) => v as f64,
            Property::UChar(v) => v as f64,
            Property::Short(v) => v as f64,
            Property::UShort(v) => v as f64,
            Property::Int(v) => v as f64,
            Property::UInt(v) => v as f64,
            Property::Float(v) => v as f64,
            Property::Double(v) => v,
            _ => return None,
        })
    }

    impl PropertyAccess for Vertex {
        fn new() -> Self {
            Vertex(Vec::with_capacity(3))
        }
        fn set_property(&mut self, _name: &str, p: Property) -> PropertyAccessResult {
            // Lists on vertices (rare) are skipped; scalars keep their slot.
            match scalar(&p) {
                Some(v) => {
                    self.0.push(v);
                    PropertyAccessResult::Set
                }
                None => PropertyAccessResult::Ignored,
            }
        }
    }

    impl PropertyAccess for Face {
        fn new() -> Self {
            Face(Vec::new())
        }
        fn set_property(&mut self, name: &str, p: Property) -> PropertyAccessResult {
            if name != "vertex_indices" && name != "vertex_index" {
                return PropertyAccessResult::Ignored;
            }
            self.0 = match p {
                Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
                Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
                Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
                Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
                Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
                Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
                _ => return PropertyAccessResult::Ignored,
            };
            PropertyAccessResult::Set
        }
    }
}

fn read_ply(bytes: &[u8]) -> Result<SurfaceMesh, String> {
    use ply_rs_bw::parser::{Parser, Reader};
    use ply_rs_bw::ply::PropertyType;
    let mut reader = Reader::new(BufReader::new(Cursor::new(bytes)));
    let vp = Parser::<ply::Vertex>::new();
    let fp = Parser::<ply::Face>::new();
    let header = vp
        .read_header(&mut reader)
        .map_err(|e| format!("PLY header: {e}"))?;
    let mut mesh = SurfaceMesh::default();
    let mut names: Vec<String> = Vec::new();
    let mut vertices: Vec<ply::Vertex> = Vec::new();
    let mut faces: Vec<ply::Face> = Vec::new();
    // Elements must be read in header order; others are read and dropped.
    for (key, def) in &header.elements {
        match key.as_str() {
            "vertex" => {
                names = def
                    .properties
                    .iter()
                    .filter(|(_, d)| matches!(d.data_type, PropertyType::Scalar(_)))
                    .map(|(n, _)| n.clone())
                    .collect();
                vertices = vp
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| format!("PLY vertex element: {e}"))?;
            }
            "face" => {
                faces = fp
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| format!("PLY face element: {e}"))?;
            }
            other => {
                vp.read_payload_for_element(&mut reader, def, &header)
                    .map_err(|e| format!("PLY element '{other}': {e}"))?;
            }
        }
    }
    let col = |n: &str| names.iter().position(|m| m == n);
    let (Some(x), Some(y), Some(z)) = (col("x"), col("y"), col("z")) else {
        return Err("PLY vertex element has no x, y and z properties".into());
    };
    mesh.positions = vertices.iter().map(|v| [v.0[x], v.0[y], v.0[z]]).collect();
    for (i, n) in names.iter().enumerate() {
        if i != x && i != y && i != z {
            mesh.fields
                .push((n.clone(), vertices.iter().map(|v| v.0[i] as f32).collect()));
        }
    }
    let nv = vertices.len() as i64;
    let mut poly = Vec::new();
    for (f, face) in faces.iter().enumerate() {
        poly.clear();
        for &v in &face.0 {
            if v < 0 || v >= nv {
                return Err(format!(
                    "face {f} refers to vertex {v}, but there are {nv} vertices"
                ));
            }
            poly.push(v as u32);
        }
        fan(&poly, &mut mesh.triangles);
    }
    Ok(mesh)
}

fn read_obj(bytes: &[u8]) -> Result<SurfaceMesh, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    // Materials are not used: a missing .mtl is no error.
    let (models, _) = tobj::load_obj_buf(&mut BufReader::new(Cursor::new(bytes)), &opts, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| format!("OBJ: {e}"))?;
    let mut mesh = SurfaceMesh::default();
    for m in &models {
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend(m.mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        mesh.triangles.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|c| [c[0] + base, c[1] + base, c[2] + base]),
        );
    }
    Ok(mesh)
}

fn read_stl(bytes: &[u8]) -> Result<SurfaceMesh, String> {
    let m = stl_io::read_stl(&mut Cursor::new(bytes)).map_err(|e| format!("STL: {e}"))?;
    Ok(SurfaceMesh {
        positions: m.vertices.iter().map(|v| v.0.map(f64::from)).collect(),
        triangles: m
            .faces
            .iter()
            .map(|f| f.vertices.map(|v| v as u32))
            .collect(),
        fields: Vec::new(),
    })
}

#[cfg(test)]
mod tests;
