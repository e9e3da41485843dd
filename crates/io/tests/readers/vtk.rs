//! VTK XML readers on the files VTK itself wrote (`tests/data/vtk/`, made by
//! `tools/gen_vtk_testdata.py`) and on corrupted or hand-made variants.

use std::path::{Path, PathBuf};

use voxless_io::{VtkMesh, read_vtk_points, read_vtu_mesh};

use super::{TempDir, close, column, error_message};

fn vtk_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk")
}

fn expected_json() -> serde_json::Value {
    let text = std::fs::read_to_string(vtk_dir().join("expected.json")).expect("expected.json");
    serde_json::from_str(&text).expect("valid expected.json")
}

fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .flat_map(|x| match x.as_array() {
            Some(inner) => inner.iter().map(|y| y.as_f64().unwrap()).collect(),
            None => vec![x.as_f64().unwrap()],
        })
        .collect()
}

fn assert_column(label: &str, got: &[f32], expected: &[f64]) {
    assert_eq!(got.len(), expected.len(), "{label}: length");
    for (i, (&g, &e)) in got.iter().zip(expected).enumerate() {
        assert!(close(f64::from(g), e, 1e-6), "{label}[{i}]: {g} vs {e}");
    }
}

/// Column `name` split into rows of `width` (for vectors stored as x/y/z).
fn components(columns: &[(String, Vec<f32>)], name: &str) -> Vec<f32> {
    let get = |axis: &str| {
        columns
            .iter()
            .find(|(n, _)| n == &format!("{name}_{axis}"))
            .map(|(_, v)| v.clone())
            .unwrap_or_else(|| panic!("no column {name}_{axis}"))
    };
    let (x, y, z) = (get("x"), get("y"), get("z"));
    (0..x.len()).flat_map(|i| [x[i], y[i], z[i]]).collect()
}

#[test]
fn vtk_points_every_encoding() {
    let expected = expected_json();
    let e = &expected["points"];
    let files = e["files"].as_array().unwrap();
    assert!(files.len() >= 7);
    let velocity = numbers(&e["velocity"]);
    for file in files {
        let path = vtk_dir().join(file.as_str().unwrap());
        let label = path.display().to_string();
        let t = read_vtk_points(&path).unwrap_or_else(|err| panic!("{err}"));
        let flat: Vec<f32> = t.positions.iter().flatten().map(|&c| c as f32).collect();
        assert_column(
            &format!("{label} positions"),
            &flat,
            &numbers(&e["positions"]),
        );
        for name in ["temperature", "pressure", "id"] {
            assert_column(
                &format!("{label} {name}"),
                column(&t, name),
                &numbers(&e[name]),
            );
        }
        assert_column(
            &format!("{label} velocity"),
            &components(&t.columns, "velocity"),
            &velocity,
        );
        let speed: Vec<f64> = velocity
            .chunks(3)
            .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
            .collect();
        assert_column(
            &format!("{label} velocity_mag"),
            column(&t, "velocity_mag"),
            &speed,
        );
        assert_column(&format!("{label} speed"), column(&t, "speed"), &speed);
        assert_eq!(t.time, e["time"].as_f64(), "{label}");
        assert_eq!(t.domain, None);
    }
}

#[test]
fn vtk_meshes_every_encoding() {
    let expected = expected_json();
    let e = &expected["mesh"];
    let tets: Vec<[u32; 4]> = e["tets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            let v: Vec<u32> = t
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_u64().unwrap() as u32)
                .collect();
            [v[0], v[1], v[2], v[3]]
        })
        .collect();
    for file in e["files"].as_array().unwrap() {
        let path = vtk_dir().join(file.as_str().unwrap());
        let label = path.display().to_string();
        let mesh: VtkMesh = read_vtu_mesh(&path).unwrap_or_else(|err| panic!("{err}"));
        let flat: Vec<f32> = mesh.points.iter().flatten().copied().collect();
        assert_column(&format!("{label} points"), &flat, &numbers(&e["points"]));
        assert_eq!(mesh.tets, tets, "{label}");
        assert_eq!(
            mesh.skipped_cells as u64,
            e["skipped_cells"].as_u64().unwrap()
        );
        let point = |n: &str| &mesh.point_data.iter().find(|(c, _)| c == n).unwrap().1;
        let cell = |n: &str| &mesh.cell_data.iter().find(|(c, _)| c == n).unwrap().1;
        assert_column(&format!("{label} phi"), point("phi"), &numbers(&e["phi"]));
        assert_column(
            &format!("{label} velocity"),
            &components(&mesh.point_data, "velocity"),
            &numbers(&e["velocity"]),
        );
        assert_column(
            &format!("{label} density"),
            cell("density"),
            &numbers(&e["density"]),
        );
        assert_column(
            &format!("{label} region"),
            cell("region"),
            &numbers(&e["region"]),
        );
        assert!(
            mesh.cell_data
                .iter()
                .all(|(_, v)| v.len() == mesh.tets.len())
        );

        // The points of a .vtu read as particles.
        let t = read_vtk_points(&path).unwrap();
        let points: Vec<[f32; 3]> = t.positions.iter().map(|p| p.map(|c| c as f32)).collect();
        assert_eq!(points, mesh.points);
        assert_column(
            &format!("{label} phi as column"),
            column(&t, "phi"),
            &numbers(&e["phi"]),
        );
    }
    // A .vtp is not a mesh.
    let path = vtk_dir().join("points_ascii.vtp");
    let msg = error_message(read_vtu_mesh(&path), &path);
    assert!(msg.contains("PolyData"), "{msg}");
}

#[test]
fn vtk_truncated_files_fail_cleanly() {
    let dir = TempDir::new("vtk-trunc");
    let mut names: Vec<String> = std::fs::read_dir(vtk_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".vtp") || n.ends_with(".vtu"))
        .collect();
    names.sort();
    for name in names {
        let bytes = std::fs::read(vtk_dir().join(&name)).unwrap();
        for tenth in 1..10 {
            let cut = bytes.len() * tenth / 10;
            let path = dir.write(&format!("cut{tenth}-{name}"), &bytes[..cut]);
            error_message(read_vtk_points(&path), &path);
            if name.ends_with(".vtu") {
                error_message(read_vtu_mesh(&path), &path);
            }
        }
    }
}

/// A minimal little-endian .vtu with one tet whose arrays are all appended
/// raw; `points_header` replaces the header of the Points array.
fn raw_vtu(compressed: bool, points_header: &[u8], points_data: &[u8], conn: [i32; 4]) -> Vec<u8> {
    let mut appended = Vec::new();
    let mut offsets = Vec::new();
    let mut push = |header: &[u8], data: &[u8]| {
        offsets.push(appended.len());
        appended.extend_from_slice(header);
        appended.extend_from_slice(data);
    };
    push(points_header, points_data);
    let conn_bytes: Vec<u8> = conn.iter().flat_map(|v| v.to_le_bytes()).collect();
    push(&16u32.to_le_bytes(), &conn_bytes);
    push(&4u32.to_le_bytes(), &4i32.to_le_bytes());
    push(&1u32.to_le_bytes(), &[10u8]);
    let compressor = if compressed {
        " compressor=\"vtkZLibDataCompressor\""
    } else {
        ""
    };
    let mut out = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt32\"{compressor}>\n<UnstructuredGrid>\n\
         <Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n<Points>\n\
         <DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" offset=\"{}\"/>\n\
         </Points>\n<Cells>\n\
         <DataArray type=\"Int32\" Name=\"connectivity\" format=\"appended\" offset=\"{}\"/>\n\
         <DataArray type=\"Int32\" Name=\"offsets\" format=\"appended\" offset=\"{}\"/>\n\
         <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{}\"/>\n\
         </Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_",
        offsets[0], offsets[1], offsets[2], offsets[3]
    )
    .into_bytes();
    out.extend_from_slice(&appended);
    out.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
    out
}

fn tet_points() -> Vec<u8> {
    [
        0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0,
    ]
    .iter()
    .flat_map(|v| v.to_le_bytes())
    .collect()
}

#[test]
fn vtk_hand_written_raw_file() {
    let dir = TempDir::new("vtk-raw");
    let good = raw_vtu(false, &48u32.to_le_bytes(), &tet_points(), [0, 1, 2, 3]);
    let path = dir.write("good.vtu", &good);
    let mesh = read_vtu_mesh(&path).unwrap();
    assert_eq!(mesh.tets, [[0, 1, 2, 3]]);
    assert_eq!(mesh.points[3], [0.0, 0.0, 1.0]);
    assert_eq!(mesh.skipped_cells, 0);
}

#[test]
fn vtk_malformed_inputs() {
    let dir = TempDir::new("vtk-bad");
    let points = tet_points();
    let tet = [0, 1, 2, 3];
    let u32s =
        |values: &[u32]| -> Vec<u8> { values.iter().flat_map(|v| v.to_le_bytes()).collect() };
    // (name, file, expected text in the message); read with read_vtu_mesh.
    let mesh_cases: Vec<(&str, Vec<u8>, &str)> = vec![
        // Header declares far more bytes than the appended data holds.
        (
            "huge-raw-header",
            raw_vtu(false, &u32s(&[u32::MAX]), &points, tet),
            "declares 4294967295 data bytes",
        ),
        (
            "short-raw-header",
            raw_vtu(false, &u32s(&[40]), &points, tet),
            "expected 12 values (48 bytes)",
        ),
        (
            "bad-index",
            raw_vtu(false, &u32s(&[48]), &points, [0, 1, 2, 4]),
            "refers to point 4",
        ),
        (
            "negative-index",
            raw_vtu(false, &u32s(&[48]), &points, [0, -1, 2, 3]),
            "refers to point -1",
        ),
        // zlib headers: a huge block count, huge compressed sizes, a block
        // size zlib could not produce from the bytes given, bytes that are
        // not zlib.
        (
            "huge-block-count",
            raw_vtu(true, &u32s(&[u32::MAX, 65536, 0]), &points, tet),
            "4294967295 blocks",
        ),
        (
            "huge-compressed-size",
            raw_vtu(true, &u32s(&[1, 48, 48, u32::MAX]), &points, tet),
            "4294967295 compressed bytes",
        ),
        (
            "zip-bomb-claim",
            raw_vtu(true, &u32s(&[1, 50_000, 0, 48]), &points, tet),
            "declares 50000 bytes once inflated, but the array holds 48",
        ),
        (
            "zip-bomb-ratio",
            raw_vtu(true, &u32s(&[1, 1 << 30, 0, 48]), &points, tet),
            "claims 1073741824 bytes from 48 compressed bytes, more than zlib can expand",
        ),
        (
            "not-zlib",
            raw_vtu(true, &u32s(&[1, 48, 0, 48]), &points, tet),
            "not valid zlib",
        ),
    ];
    for (name, bytes, expected) in mesh_cases {
        let path = dir.write(&format!("{name}.vtu"), &bytes);
        let msg = error_message(read_vtu_mesh(&path), &path);
        assert!(msg.contains(expected), "{name}: {msg}");
    }

    // Edits of a VTK-written ascii file; read with read_vtk_points.
    let ascii = std::fs::read_to_string(vtk_dir().join("points_ascii.vtp")).unwrap();
    let edit = |pairs: &[(&str, &str)]| -> Vec<u8> {
        let mut text = ascii.clone();
        for (from, to) in pairs {
            assert!(text.contains(from), "test edit '{from}' not found");
            text = text.replacen(from, to, 1);
        }
        text.into_bytes()
    };
    let points_tag = "<DataArray type=\"Float32\" Name=\"Points\"";
    let points_start = ascii.find(points_tag).unwrap();
    let points_text = points_start + ascii[points_start..].find('>').unwrap() + 1;
    let bad_number =
        format!("{} abc {}", &ascii[..points_text], &ascii[points_text..]).into_bytes();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "huge-count",
            edit(&[(
                "NumberOfPoints=\"64\"",
                "NumberOfPoints=\"99999999999999999\"",
            )]),
            "99999999999999999",
        ),
        (
            "too-many-values",
            edit(&[("NumberOfPoints=\"64\"", "NumberOfPoints=\"63\"")]),
            "expected 189 values",
        ),
        ("bad-number", bad_number, "cannot parse 'abc'"),
        (
            "no-points",
            edit(&[("<Points>", "<Other>"), ("</Points>", "</Other>")]),
            "no <Points> array",
        ),
        (
            "bad-type",
            edit(&[(points_tag, "<DataArray type=\"Float128\" Name=\"Points\"")]),
            "\"Float128\" is not supported",
        ),
        (
            "bad-components",
            edit(&[("NumberOfComponents=\"3\"", "NumberOfComponents=\"zero\"")]),
            "NumberOfComponents",
        ),
        (
            "bad-format",
            edit(&[("format=\"ascii\"", "format=\"hex\"")]),
            "format=\"hex\"",
        ),
        (
            "mismatched-tags",
            edit(&[("</PointData>", "</CellData>")]),
            "XML error",
        ),
        (
            "appended-missing",
            edit(&[("format=\"ascii\"", "format=\"appended\" offset=\"0\"")]),
            "no <AppendedData>",
        ),
        (
            "wrong-root",
            b"<?xml version=\"1.0\"?>\n<Foo type=\"PolyData\"></Foo>\n".to_vec(),
            "root element is <Foo>",
        ),
        (
            "not-xml",
            b"\x00\x01binary \xff junk".to_vec(),
            "no <VTKFile>",
        ),
        ("empty", Vec::new(), "no <VTKFile>"),
        (
            "no-piece",
            b"<VTKFile type=\"PUnstructuredGrid\"><PUnstructuredGrid/></VTKFile>".to_vec(),
            "no <Piece>",
        ),
    ];
    for (name, bytes, expected) in cases {
        let path = dir.write(&format!("{name}.vtp"), &bytes);
        let msg = error_message(read_vtk_points(&path), &path);
        assert!(msg.contains(expected), "{name}: {msg}");
    }
}

/// Found while writing the fuzz targets (fuzz/): with no points or cells,
/// nothing bounds `NumberOfComponents`, and each component becomes a column,
/// so this 300-byte file made the readers build four billion columns.
#[test]
fn vtk_huge_component_count_without_tuples() {
    let dir = TempDir::new("vtk-components");
    let array = "<DataArray type=\"Float32\" Name=\"a\" NumberOfComponents=\"4000000000\" \
                 format=\"ascii\"></DataArray>";
    let points = "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" \
                  format=\"ascii\"></DataArray></Points>";
    let polydata = format!(
        "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"0\">\
         <PointData>{array}</PointData>{points}</Piece></PolyData></VTKFile>\n"
    );
    let path = dir.write("components.vtp", &polydata);
    let msg = error_message(read_vtk_points(&path), &path);
    assert!(msg.contains("4000000000 components"), "{msg}");

    let grid = format!(
        "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid>\
         <Piece NumberOfPoints=\"0\" NumberOfCells=\"0\"><CellData>{array}</CellData>{points}\
         </Piece></UnstructuredGrid></VTKFile>\n"
    );
    let path = dir.write("components.vtu", &grid);
    let msg = error_message(read_vtu_mesh(&path), &path);
    assert!(msg.contains("4000000000 components"), "{msg}");

    // A few components with no tuples are still fine: empty columns.
    let small = polydata.replace("4000000000", "2");
    let path = dir.write("two.vtp", &small);
    let table = read_vtk_points(&path).unwrap();
    assert_eq!(table.len(), 0);
    assert_eq!(table.column("a_1"), Some(&[][..]));
}

/// A 500-byte file whose zlib header declares 1.1 GB from a 17-byte block
/// (found by the `vtu_mesh` fuzzer) is refused by the size check, naming the
/// file and the array, before anything is reserved for it. The same bytes are
/// the fuzz seed `regress_zlib_bomb.vtu`, where libFuzzer's 1 GiB allocation
/// limit fails the run if the reserve comes first.
#[test]
fn vtk_compressed_header_declaring_gigabytes_is_refused() {
    let dir = TempDir::new("vtk-zlib-bomb");
    let seed = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/corpus/vtu_mesh/regress_zlib_bomb.vtu");
    let bytes = std::fs::read(&seed).unwrap_or_else(|e| panic!("{}: {e}", seed.display()));
    let path = dir.write("bomb.vtu", &bytes);
    let msg = error_message(read_vtu_mesh(&path), &path);
    assert!(msg.contains("<Points>"), "{msg}");
    assert!(
        msg.contains("claims 1100000000 bytes from 17 compressed bytes"),
        "{msg}"
    );
}
