//! VTK reader: hexahedral and tetrahedral boxes in legacy ASCII and binary files (written
//! with vtkio's model) and in XML `.vtu` files written here by hand in the three XML
//! encodings (ascii, inline base64 binary, appended raw); mixed wedge/polyhedron/pyramid
//! cells; point data averaged onto cells; the legacy writer's round trip; bad input.

mod common;

use std::collections::BTreeMap;
use std::path::Path;

use common::{BoxGrid, box_grid, canonical, check_orientation, point_mean_centres};
use glam::DVec3;
use scg_mesh::vtk;
use scg_mesh::{CellField, MeshError, PolyMesh};
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType,
    UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

/// Cells as (VTK type, connectivity).
type CellList = Vec<(u8, Vec<u32>)>;

fn grid() -> BoxGrid {
    box_grid(
        [3, 2, 2],
        DVec3::new(0.0, -0.5, 1.0),
        DVec3::new(0.3, 0.5, 1.2),
    )
}

fn hex_cells(g: &BoxGrid) -> CellList {
    g.hexes.iter().map(|h| (12, h.to_vec())).collect()
}

fn tet_cells(g: &BoxGrid) -> CellList {
    g.tets().iter().map(|t| (10, t.to_vec())).collect()
}

/// Where the velocity is stored.
#[derive(Clone, Copy, Debug)]
enum Data {
    Cell,
    Point,
}

fn values(points: &[DVec3], cells: &CellList, data: Data) -> Vec<DVec3> {
    match data {
        Data::Point => points.iter().map(|&p| common::affine_u(p)).collect(),
        Data::Cell => cells
            .iter()
            .map(|(_, c)| {
                let mut c = c.clone();
                c.sort_unstable();
                c.dedup();
                // (An out-of-range index, in the bad-input test, counts as the origin.)
                let centre = c
                    .iter()
                    .map(|&i| points.get(i as usize).copied().unwrap_or_default())
                    .sum::<DVec3>()
                    / c.len() as f64;
                common::affine_u(centre)
            })
            .collect(),
    }
}

fn cell_type(t: u8) -> CellType {
    match t {
        10 => CellType::Tetra,
        12 => CellType::Hexahedron,
        13 => CellType::Wedge,
        14 => CellType::Pyramid,
        24 => CellType::QuadraticTetra,
        42 => CellType::Polyhedron,
        _ => unreachable!(),
    }
}

/// A legacy file through vtkio's writer (`binary`: big-endian binary, else ASCII).
fn write_legacy(path: &Path, points: &[DVec3], cells: &CellList, data: Data, binary: bool) {
    let mut vertices = Vec::new();
    for (_, c) in cells {
        vertices.push(c.len() as u32);
        vertices.extend(c);
    }
    let u: Vec<f64> = values(points, cells, data)
        .iter()
        .flat_map(|v| v.to_array())
        .collect();
    let attr = Attribute::DataArray(DataArray {
        name: "U".into(),
        elem: ElementType::Vectors,
        data: u.into(),
    });
    let data = match data {
        Data::Cell => Attributes {
            point: vec![],
            cell: vec![attr],
        },
        Data::Point => Attributes {
            point: vec![attr],
            cell: vec![],
        },
    };
    let vtk = Vtk {
        version: Version::new_legacy(4, 2),
        title: "test".into(),
        byte_order: ByteOrder::BigEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: points
                .iter()
                .flat_map(|p| p.to_array())
                .collect::<Vec<f64>>()
                .into(),
            cells: Cells {
                cell_verts: VertexNumbers::Legacy {
                    num_cells: cells.len() as u32,
                    vertices,
                },
                types: cells.iter().map(|c| cell_type(c.0)).collect(),
            },
            data,
        }),
    };
    if binary {
        vtk.export_be(path).unwrap();
    } else {
        vtk.export_ascii(path).unwrap();
    }
}

/// XML encodings written by [`write_vtu`].
#[derive(Clone, Copy, Debug)]
enum Xml {
    Ascii,
    Base64,
    AppendedRaw,
}

/// A `.vtu` file written by hand after the VTK XML format (header_type UInt64,
/// little-endian).
fn write_vtu(path: &Path, points: &[DVec3], cells: &CellList, data: Data, enc: Xml) {
    let coords: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    let conn: Vec<i64> = cells
        .iter()
        .flat_map(|c| c.1.iter().map(|&i| i as i64))
        .collect();
    let mut offsets = Vec::new();
    let mut end = 0i64;
    for c in cells {
        end += c.1.len() as i64;
        offsets.push(end);
    }
    let types: Vec<u8> = cells.iter().map(|c| c.0).collect();
    let u: Vec<f64> = values(points, cells, data)
        .iter()
        .flat_map(|v| v.to_array())
        .collect();
    // (attributes, text, raw bytes) of each array.
    let arrays: Vec<(String, String, Vec<u8>)> = vec![
        (
            r#"type="Float64" NumberOfComponents="3""#.into(),
            join(&coords),
            coords.iter().flat_map(|x| x.to_le_bytes()).collect(),
        ),
        (
            r#"type="Int64" Name="connectivity""#.into(),
            join(&conn),
            conn.iter().flat_map(|x| x.to_le_bytes()).collect(),
        ),
        (
            r#"type="Int64" Name="offsets""#.into(),
            join(&offsets),
            offsets.iter().flat_map(|x| x.to_le_bytes()).collect(),
        ),
        (
            r#"type="UInt8" Name="types""#.into(),
            join(&types),
            types.clone(),
        ),
        (
            r#"type="Float64" Name="U" NumberOfComponents="3""#.into(),
            join(&u),
            u.iter().flat_map(|x| x.to_le_bytes()).collect(),
        ),
    ];
    let mut appended = Vec::new();
    let tags: Vec<String> = arrays
        .iter()
        .map(|(attrs, text, raw)| match enc {
            Xml::Ascii => format!("<DataArray {attrs} format=\"ascii\">\n{text}\n</DataArray>"),
            Xml::Base64 => {
                let mut block = (raw.len() as u64).to_le_bytes().to_vec();
                block.extend(raw);
                format!(
                    "<DataArray {attrs} format=\"binary\">\n{}\n</DataArray>",
                    base64(&block)
                )
            }
            Xml::AppendedRaw => {
                let offset = appended.len();
                appended.extend((raw.len() as u64).to_le_bytes());
                appended.extend(raw);
                format!("<DataArray {attrs} format=\"appended\" offset=\"{offset}\"/>")
            }
        })
        .collect();
    let (pd, cd) = match data {
        Data::Point => (
            format!("<PointData Vectors=\"U\">\n{}\n</PointData>", tags[4]),
            "<CellData>\n</CellData>".to_string(),
        ),
        Data::Cell => (
            "<PointData>\n</PointData>".to_string(),
            format!("<CellData Vectors=\"U\">\n{}\n</CellData>", tags[4]),
        ),
    };
    let mut out = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n{pd}\n{cd}\n<Points>\n{}\n</Points>\n<Cells>\n{}\n{}\n{}\n</Cells>\n</Piece>\n</UnstructuredGrid>\n",
        points.len(),
        cells.len(),
        tags[0],
        tags[1],
        tags[2],
        tags[3]
    )
    .into_bytes();
    if let Xml::AppendedRaw = enc {
        out.extend(b"<AppendedData encoding=\"raw\">\n_");
        out.extend(&appended);
        out.extend(b"\n</AppendedData>\n");
    }
    out.extend(b"</VTKFile>\n");
    std::fs::write(path, out).unwrap();
}

fn join<T: ToString>(v: &[T]) -> String {
    v.iter().map(T::to_string).collect::<Vec<_>>().join(" ")
}

/// Standard base64 (RFC 4648, with padding).
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// The canonical form with every patch named `boundary`.
fn one_patch(m: &PolyMesh) -> BTreeMap<Vec<[u64; 3]>, (String, String)> {
    let names: Vec<String> = m.patches.iter().map(|p| p.name.clone()).collect();
    canonical(m)
        .into_iter()
        .map(|(k, (o, n))| {
            (
                k,
                (
                    o,
                    if names.contains(&n) {
                        "boundary".into()
                    } else {
                        n
                    },
                ),
            )
        })
        .collect()
}

/// Check a mesh read from a file against the mesh the generator's cells assemble to, and
/// the field against the affine velocity.
fn check(mesh: &PolyMesh, field: &CellField, expected: &PolyMesh, data: Data, what: &str) {
    assert_eq!(mesh.n_cells, expected.n_cells, "{what}");
    assert_eq!(mesh.n_faces(), expected.n_faces(), "{what}");
    assert_eq!(
        mesh.n_internal_faces(),
        expected.n_internal_faces(),
        "{what}"
    );
    assert_eq!(mesh.points, expected.points, "{what}");
    assert_eq!(one_patch(mesh), one_patch(expected), "{what}");
    assert_eq!(mesh.patches.len(), 1);
    assert_eq!(
        (mesh.patches[0].name.as_str(), mesh.patches[0].kind.as_str()),
        ("boundary", "patch")
    );
    let (closure, min_dot) = check_orientation(mesh);
    assert!(closure < 1e-12, "{what}: closure {closure}");
    assert!(min_dot > 0.0, "{what}: inward face ({min_dot})");
    // Internal faces: owner below neighbour, upper-triangular order.
    for f in 0..mesh.n_internal_faces() {
        assert!(mesh.owner[f] < mesh.neighbour[f], "{what}: face {f}");
    }
    let centres = point_mean_centres(mesh);
    match data {
        Data::Cell => {
            // Cell data are stored values: the affine field at the point-mean centre, exact.
            let want: Vec<DVec3> = centres.iter().map(|&c| common::affine_u(c)).collect();
            for (i, (a, b)) in field.cells.iter().zip(&want).enumerate() {
                assert!(a.abs_diff_eq(*b, 1e-14), "{what}: cell {i}: {a} vs {b}");
            }
            assert_eq!(field.patches, vec![None]);
        }
        Data::Point => {
            // The mean of an affine field over the points is its value at the points' mean.
            for (i, (a, c)) in field.cells.iter().zip(&centres).enumerate() {
                let b = common::affine_u(*c);
                assert!(a.abs_diff_eq(b, 1e-13), "{what}: cell {i}: {a} vs {b}");
            }
            let p = &mesh.patches[0];
            let faces = field.patches[0]
                .as_ref()
                .expect("point data give face values");
            assert_eq!(faces.len(), p.size);
            for (k, v) in faces.iter().enumerate() {
                let f = p.start + k;
                let c = mesh
                    .face(f)
                    .iter()
                    .map(|&i| mesh.points[i as usize])
                    .sum::<DVec3>()
                    / mesh.face(f).len() as f64;
                assert!(
                    v.abs_diff_eq(common::affine_u(c), 1e-13),
                    "{what}: face {f}"
                );
            }
        }
    }
}

fn expected(points: &[DVec3], cells: &CellList) -> PolyMesh {
    vtk::assemble(
        points.to_vec(),
        cells
            .iter()
            .map(|(t, c)| vtk::cell_faces(*t, c).unwrap())
            .collect(),
    )
    .unwrap()
}

#[test]
fn hex_and_tet_boxes_in_every_encoding() {
    let g = grid();
    for (shape, cells) in [("hex", hex_cells(&g)), ("tet", tet_cells(&g))] {
        let exp = expected(&g.points, &cells);
        // Independent counts: 12 hexahedra; 6 tets each, boundary triangles 2 per quad.
        let (nc, nb) = if shape == "hex" {
            (g.n_hex(), g.n_boundary_quads())
        } else {
            (6 * g.n_hex(), 2 * g.n_boundary_quads())
        };
        assert_eq!(exp.n_cells, nc);
        assert_eq!(exp.n_faces() - exp.n_internal_faces(), nb);
        if shape == "hex" {
            assert_eq!(exp.n_internal_faces(), g.n_internal_quads());
        }
        for data in [Data::Cell, Data::Point] {
            let dir = tempfile::tempdir().unwrap();
            for binary in [false, true] {
                let p = dir.path().join(format!("{shape}-{binary}.vtk"));
                write_legacy(&p, &g.points, &cells, data, binary);
                let (m, f) = vtk::read(&p, "U").unwrap_or_else(|e| panic!("{e}"));
                check(
                    &m,
                    &f,
                    &exp,
                    data,
                    &format!("{shape} legacy binary={binary} {data:?}"),
                );
            }
            for enc in [Xml::Ascii, Xml::Base64, Xml::AppendedRaw] {
                let p = dir.path().join(format!("{shape}-{enc:?}.vtu"));
                write_vtu(&p, &g.points, &cells, data, enc);
                let (m, f) = vtk::read(&p, "U").unwrap_or_else(|e| panic!("{enc:?}: {e}"));
                check(&m, &f, &exp, data, &format!("{shape} {enc:?} {data:?}"));
            }
        }
    }
}

#[test]
fn wedges_polyhedron_and_pyramids() {
    // Three unit cubes along x: A as two wedges, B as one polyhedron, C as six pyramids
    // around its centre (point 16).
    let g = box_grid([3, 1, 1], DVec3::ZERO, DVec3::new(3.0, 1.0, 1.0));
    let mut points = g.points.clone();
    points.push(DVec3::new(2.5, 0.5, 0.5));
    let [a, b, c] = [g.hexes[0], g.hexes[1], g.hexes[2]];
    let mut cells: CellList = vec![
        // VTK wedge order: triangle 0 1 2 clockwise seen from 3 4 5 (this one is
        // counter-clockwise, i.e. inverted, and must be flipped) ...
        (13, vec![a[0], a[1], a[2], a[4], a[5], a[6]]),
        // ... and this one in VTK's own orientation.
        (13, vec![a[0], a[3], a[2], a[4], a[7], a[6]]),
    ];
    let hex_faces = vtk::cell_faces(12, &b).unwrap();
    let mut stream = vec![hex_faces.len() as u32];
    for f in &hex_faces {
        stream.push(f.len() as u32);
        stream.extend(f);
    }
    cells.push((42, stream));
    for f in vtk::cell_faces(12, &c).unwrap() {
        // Base outward from the cube = inward from the apex: reverse it for VTK's pyramid
        // (base counter-clockwise seen from the apex).
        cells.push((14, vec![f[3], f[2], f[1], f[0], 16]));
    }
    let dir = tempfile::tempdir().unwrap();
    for binary in [false, true] {
        let p = dir.path().join(format!("mixed-{binary}.vtk"));
        write_legacy(&p, &points, &cells, Data::Cell, binary);
        let (m, f) = vtk::read(&p, "U").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.n_cells, 9);
        // A: 1 diagonal face; A–B and B–C: 1 each; C: 12 triangles between pyramids.
        assert_eq!(m.n_internal_faces(), 15);
        // A: 2 + 2 triangles, 3 quads; B: 4 quads; C: 5 pyramid bases.
        assert_eq!(m.n_faces() - m.n_internal_faces(), 16);
        let (closure, min_dot) = check_orientation(&m);
        assert!(closure < 1e-12 && min_dot > 0.0, "{closure} {min_dot}");
        // Total volume 3 m³ by the divergence theorem over the boundary faces.
        let vol: f64 = (m.n_internal_faces()..m.n_faces())
            .map(|f| {
                let (a, c) = common::face_geometry(&m, f);
                a.dot(c) / 3.0
            })
            .sum();
        assert!((vol - 3.0).abs() < 1e-12, "{vol}");
        assert_eq!(f.cells.len(), 9);
    }
    // Polyhedra in XML are refused with a clear error.
    let p = dir.path().join("mixed.vtu");
    write_vtu(&p, &points, &cells, Data::Cell, Xml::Ascii);
    let e = vtk::read(&p, "U").unwrap_err();
    assert!(
        e.to_string().contains("Cells[2]") && e.to_string().contains("polyhedron"),
        "{e}"
    );
}

#[test]
fn legacy_writer_round_trip() {
    let g = grid();
    for mesh in [g.hex_mesh(), g.tet_mesh()] {
        let field = common::affine_field(&mesh);
        let dir = tempfile::tempdir().unwrap();
        for binary in [false, true] {
            let p = dir.path().join(format!("out-{binary}.vtk"));
            vtk::write_legacy(&p, &mesh, "U", &field, binary).unwrap();
            let (m, f) = vtk::read(&p, "U").unwrap();
            assert_eq!(m.points, mesh.points);
            assert_eq!(one_patch(&m), one_patch(&mesh));
            assert_eq!(f.cells, field.cells, "binary={binary}");
            let (closure, min_dot) = check_orientation(&m);
            assert!(closure < 1e-12 && min_dot > 0.0);
        }
    }
}

fn err(path: &Path, field: &str) -> String {
    match vtk::read(path, field) {
        Err(e @ MeshError::Invalid { .. }) => {
            let s = e.to_string();
            assert!(s.contains(&path.display().to_string()), "{s}");
            s
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_vtk_input_names_file_and_entry() {
    let g = grid();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("box.vtk");
    write_legacy(&p, &g.points, &hex_cells(&g), Data::Cell, false);
    assert!(err(&p, "V").contains("V: no 3-component cell or point array of this name"));
    // Unsupported cell type: the first cell made a quadratic tetra.
    let mut cells = hex_cells(&g);
    cells[0] = (24, (0..10).collect());
    let q = dir.path().join("quad.vtk");
    write_legacy(&q, &g.points, &cells, Data::Cell, false);
    let s = err(&q, "U");
    assert!(
        s.contains("Cells[0]") && s.contains("type 24 is not supported"),
        "{s}"
    );
    // Wrong point count for a hexahedron.
    let mut cells = hex_cells(&g);
    cells[3].1.pop();
    let q = dir.path().join("short.vtk");
    write_legacy(&q, &g.points, &cells, Data::Cell, false);
    let s = err(&q, "U");
    assert!(
        s.contains("Cells[3]") && s.contains("needs 8 points"),
        "{s}"
    );
    // Point index out of range.
    let mut cells = hex_cells(&g);
    cells[5].1[2] = 999;
    let q = dir.path().join("range.vtu");
    write_vtu(&q, &g.points, &cells, Data::Cell, Xml::Ascii);
    let s = err(&q, "U");
    assert!(s.contains("Cells[5]") && s.contains("out of range"), "{s}");
    // NaN in the cell data.
    let q = dir.path().join("nan.vtu");
    write_vtu(&q, &g.points, &hex_cells(&g), Data::Cell, Xml::Ascii);
    let text = std::fs::read_to_string(&q).unwrap();
    let u_at = text.find("Name=\"U\"").unwrap();
    let num_at = text[u_at..].find('\n').unwrap() + u_at + 1;
    let end = text[num_at..].find(' ').unwrap() + num_at;
    std::fs::write(&q, format!("{}nan{}", &text[..num_at], &text[end..])).unwrap();
    let s = err(&q, "U");
    assert!(
        s.contains("CELL_DATA/U[0]") && s.contains("not finite"),
        "{s}"
    );
    // Garbage and the wrong extension.
    let q = dir.path().join("garbage.vtu");
    std::fs::write(&q, b"not xml at all").unwrap();
    assert!(err(&q, "U").contains("cannot parse"));
    let q = dir.path().join("box.txt");
    std::fs::write(&q, b"").unwrap();
    assert!(err(&q, "U").contains("expected .vtk"));
    // A missing file is an I/O error naming it.
    let q = dir.path().join("missing.vtk");
    assert!(matches!(vtk::read(&q, "U"), Err(MeshError::Io { file, .. }) if file == q));
}

#[test]
fn truncated_vtk_files_never_panic() {
    let g = box_grid([2, 1, 1], DVec3::ZERO, DVec3::ONE);
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for binary in [false, true] {
        let p = dir.path().join(format!("src-{binary}.vtk"));
        write_legacy(&p, &g.points, &hex_cells(&g), Data::Point, binary);
        files.push(p);
    }
    for enc in [Xml::Ascii, Xml::Base64, Xml::AppendedRaw] {
        let p = dir.path().join(format!("src-{enc:?}.vtu"));
        write_vtu(&p, &g.points, &hex_cells(&g), Data::Cell, enc);
        files.push(p);
    }
    let mut n = 0;
    for src in files {
        let bytes = std::fs::read(&src).unwrap();
        let ext = src.extension().unwrap().to_str().unwrap();
        let cut = dir.path().join(format!("cut.{ext}"));
        for len in (0..bytes.len()).step_by(7) {
            std::fs::write(&cut, &bytes[..len]).unwrap();
            // Ok (a cut in trailing white space) or an error; never a panic.
            let _ = vtk::read(&cut, "U");
            n += 1;
        }
    }
    assert!(n > 200, "{n}");
}
