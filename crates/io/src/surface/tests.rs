use super::*;

/// The unit cube: 8 corners, 6 quads wound outward.
const CORNERS: [[f32; 3]; 8] = [
    [0., 0., 0.],
    [1., 0., 0.],
    [1., 1., 0.],
    [0., 1., 0.],
    [0., 0., 1.],
    [1., 0., 1.],
    [1., 1., 1.],
    [0., 1., 1.],
];
const QUADS: [[u32; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [2, 3, 7, 6],
    [1, 2, 6, 5],
    [0, 4, 7, 3],
];

fn area(m: &SurfaceMesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| m.positions[v as usize]);
            let (u, v) = (
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
            );
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
        })
        .sum()
}

fn assert_cube(m: &SurfaceMesh) {
    assert_eq!(m.triangles.len(), 12);
    assert!((area(m) - 6.0).abs() < 1e-9, "area {}", area(m));
}

fn ascii_ply() -> String {
    let mut s = String::from(
        "ply\nformat ascii 1.0\ncomment a cube\nelement vertex 8\nproperty float x\n\
         property float y\nproperty float z\nproperty float pressure\nelement face 6\n\
         property list uchar int vertex_indices\nend_header\n",
    );
    for (i, c) in CORNERS.iter().enumerate() {
        s += &format!("{} {} {} {}\n", c[0], c[1], c[2], i as f32 * 0.5);
    }
    for q in QUADS {
        s += &format!("4 {} {} {} {}\n", q[0], q[1], q[2], q[3]);
    }
    s
}

#[test]
fn ascii_ply_with_a_field() {
    let m = read_surface_bytes(ascii_ply().as_bytes(), Path::new("cube.ply")).unwrap();
    assert_cube(&m);
    assert_eq!(m.fields.len(), 1);
    assert_eq!(m.fields[0].0, "pressure");
    assert_eq!(m.fields[0].1[3], 1.5);
}

#[test]
fn binary_ply() {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty double x\n\
        property double y\nproperty double z\nelement face 6\n\
        property list uchar uint vertex_indices\nend_header\n"
        .to_vec();
    for c in CORNERS {
        for v in c {
            b.extend((v as f64).to_le_bytes());
        }
    }
    for q in QUADS {
        b.push(4);
        for v in q {
            b.extend(v.to_le_bytes());
        }
    }
    assert_cube(&read_surface_bytes(&b, Path::new("cube.PLY")).unwrap());
}

#[test]
fn obj_with_quads() {
    let mut s = String::from("# cube\nmtllib missing.mtl\no cube\n");
    for c in CORNERS {
        s += &format!("v {} {} {}\n", c[0], c[1], c[2]);
    }
    for q in QUADS {
        s += &format!("f {} {} {} {}\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
    }
    assert_cube(&read_surface_bytes(s.as_bytes(), Path::new("cube.obj")).unwrap());
}

#[test]
fn ascii_and_binary_stl() {
    let mut s = String::from("solid cube\n");
    let mut b = vec![0u8; 80];
    b.extend(12u32.to_le_bytes());
    for q in QUADS {
        for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            s += "facet normal 0 0 0\nouter loop\n";
            b.extend([0u8; 12]);
            for v in t {
                let c = CORNERS[v as usize];
                s += &format!("vertex {} {} {}\n", c[0], c[1], c[2]);
                for x in c {
                    b.extend(x.to_le_bytes());
                }
            }
            s += "endloop\nendfacet\n";
            b.extend([0u8; 2]);
        }
    }
    s += "endsolid cube\n";
    let a = read_surface_bytes(s.as_bytes(), Path::new("cube.stl")).unwrap();
    assert_cube(&a);
    // Corners shared by triangles are merged into 8 vertices.
    assert_eq!(a.positions.len(), 8);
    assert_cube(&read_surface_bytes(&b, Path::new("cube.stl")).unwrap());
}

#[test]
fn vtp_polys() {
    let pts: Vec<String> = CORNERS
        .iter()
        .map(|c| format!("{} {} {}", c[0], c[1], c[2]))
        .collect();
    let conn: Vec<String> = QUADS.iter().flatten().map(|v| v.to_string()).collect();
    let s = format!(
        r#"<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
<PolyData><Piece NumberOfPoints="8" NumberOfPolys="6">
<PointData><DataArray type="Float32" Name="T" format="ascii">0 1 2 3 4 5 6 7</DataArray></PointData>
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">{}</DataArray></Points>
<Polys><DataArray type="Int32" Name="connectivity" format="ascii">{}</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">4 8 12 16 20 24</DataArray></Polys>
</Piece></PolyData></VTKFile>"#,
        pts.join(" "),
        conn.join(" ")
    );
    let m = read_surface_bytes(s.as_bytes(), Path::new("cube.vtp")).unwrap();
    assert_cube(&m);
    assert_eq!(m.fields[0].0, "T");
}

#[test]
fn bad_files_name_the_problem() {
    let bad = ascii_ply().replace("4 4 5 6 7\n", "4 4 5 6 70\n");
    let e = read_surface_bytes(bad.as_bytes(), Path::new("cube.ply")).unwrap_err();
    assert!(
        e.to_string().contains("cube.ply") && e.to_string().contains("70"),
        "{e}"
    );
    let e = read_surface_bytes(b"ply\nformat ascii 1.0\n", Path::new("x.ply")).unwrap_err();
    assert!(e.to_string().starts_with("x.ply"), "{e}");
    let e = read_surface_bytes(b"v 0 0 0\n", Path::new("x.obj")).unwrap_err();
    assert!(e.to_string().contains("no triangles"), "{e}");
    let e = read_surface_bytes(b"abc", Path::new("x.off")).unwrap_err();
    assert!(e.to_string().contains(".ply"), "{e}");
    let e = read_surface_bytes(b"garbage", Path::new("x.stl")).unwrap_err();
    assert!(e.to_string().starts_with("x.stl"), "{e}");
}
