//! OpenFOAM boundary conditions as OpenFOAM means them, and interpolation that cannot
//! overshoot: every interpolated value lies within the range of the cell and boundary-face
//! values it is built from, at edges and corners of walls too.

use std::path::Path;

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
use scg_mesh::foam::{self, Format, TimeSel};
use scg_mesh::geometry::MeshGeometry;
use scg_mesh::interp::{Interpolation, Interpolator};
use scg_mesh::locate::Locator;
use scg_mesh::{CellField, MeshError, PolyMesh};

/// A volVectorField file for `mesh` with cell values `cells` and one boundaryField entry
/// per patch, `entries[i]` being the body of patch i's dictionary.
fn u_file(cells: &[DVec3], mesh: &PolyMesh, entries: &[String]) -> String {
    let mut s = String::from(
        "FoamFile\n{\n    version 2.0;\n    format ascii;\n    class volVectorField;\n    \
         object U;\n}\ndimensions [0 1 -1 0 0 0 0];\n",
    );
    s += &format!("internalField nonuniform List<vector> {}\n(\n", cells.len());
    for c in cells {
        s += &format!("({:e} {:e} {:e})\n", c.x, c.y, c.z);
    }
    s += ");\nboundaryField\n{\n";
    for (p, e) in mesh.patches.iter().zip(entries) {
        s += &format!("    {}\n    {{\n        {e}\n    }}\n", p.name);
    }
    s + "}\n"
}

/// A case in a temporary folder: `mesh` and the U file `text`.
fn case(mesh: &PolyMesh, text: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    foam::write_case(dir.path(), mesh, None, Format::Ascii).unwrap();
    std::fs::create_dir_all(dir.path().join("0")).unwrap();
    std::fs::write(dir.path().join("0/U"), text).unwrap();
    dir
}

fn read(dir: &Path, mesh: &PolyMesh) -> Result<CellField, MeshError> {
    foam::read_vector_field(dir, mesh, TimeSel::Latest, "U")
}

fn sides_box() -> (PolyMesh, Vec<DVec3>) {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.25), [4, 3, 2])
        .naming(PatchNaming::Sides)
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let cells = g
        .cell_centres
        .iter()
        .map(|c| DVec3::new(1.0 + c.x, -2.0 + c.y * c.z, 0.5 - c.x * c.y))
        .collect();
    (m, cells)
}

/// Each boundary-condition type gives the face values OpenFOAM defines, exactly.
#[test]
fn each_type_gives_the_wall_value_openfoam_defines() {
    let (m, cells) = sides_box();
    let patch = |name: &str| m.patches.iter().position(|p| p.name == name).unwrap();
    // the outward normal of each side (axis-aligned: normals exact)
    let normal = [
        ("xmin", -DVec3::X),
        ("xmax", DVec3::X),
        ("ymin", -DVec3::Y),
        ("ymax", DVec3::Y),
        ("zmin", -DVec3::Z),
        ("zmax", DVec3::Z),
    ];
    let owner_values = |p: usize| -> Vec<DVec3> {
        let pt = &m.patches[p];
        (pt.start..pt.start + pt.size)
            .map(|f| cells[m.owner[f] as usize])
            .collect()
    };
    let w = DVec3::new(0.25, -1.5, 3.0);
    let written = format!("value uniform ({} {} {});", w.x, w.y, w.z);
    // (type, extra entries, expected values per patch: None = owner's)
    type Expect<'a> = Box<dyn Fn(usize) -> Option<Vec<DVec3>> + 'a>;
    let sizes: Vec<usize> = m.patches.iter().map(|p| p.size).collect();
    let size = |p: usize| sizes[p];
    let cases: Vec<(&str, String, Expect)> = vec![
        (
            "noSlip",
            String::new(),
            Box::new(move |p| Some(vec![DVec3::ZERO; size(p)])),
        ),
        (
            "fixedValue",
            written.clone(),
            Box::new(move |p| Some(vec![w; size(p)])),
        ),
        (
            "movingWallVelocity",
            written.clone(),
            Box::new(move |p| Some(vec![w; size(p)])),
        ),
        (
            "inletOutlet",
            format!("inletValue uniform (0 0 0); {written}"),
            Box::new(move |p| Some(vec![w; size(p)])),
        ),
        (
            "pressureInletOutletVelocity",
            written.clone(),
            Box::new(move |p| Some(vec![w; size(p)])),
        ),
        ("zeroGradient", String::new(), Box::new(|_| None)),
        ("empty", String::new(), Box::new(|_| None)),
    ];
    for (kind, extra, expect) in &cases {
        let entries: Vec<String> = m
            .patches
            .iter()
            .map(|_| format!("type {kind}; {extra}"))
            .collect();
        let d = case(&m, &u_file(&cells, &m, &entries));
        let f = read(d.path(), &m).unwrap_or_else(|e| panic!("{kind}: {e}"));
        assert_eq!(f.cells, cells);
        for (p, _) in m.patches.iter().enumerate() {
            assert_eq!(f.patches[p], expect(p), "{kind} on {}", m.patches[p].name);
        }
    }
    // the owner's value without its normal component
    for kind in ["slip", "symmetry", "symmetryPlane", "wedge"] {
        let entries: Vec<String> = m.patches.iter().map(|_| format!("type {kind};")).collect();
        let d = case(&m, &u_file(&cells, &m, &entries));
        let f = read(d.path(), &m).unwrap();
        for (name, n) in normal {
            let p = patch(name);
            let want: Vec<DVec3> = owner_values(p)
                .into_iter()
                .map(|u| u - u.dot(n) * n)
                .collect();
            let got = f.patches[p].as_ref().unwrap();
            assert_eq!(got, &want, "{kind} on {name}");
            assert!(got.iter().all(|u| u.dot(n) == 0.0));
        }
    }
}

/// What cannot be honoured is refused, naming the file, the patch and the type.
#[test]
fn unknown_missing_and_refused_types_are_errors() {
    let (m, cells) = sides_box();
    let with = |kind: &str| -> Vec<String> {
        m.patches
            .iter()
            .enumerate()
            .map(|(i, _)| {
                if i == 2 {
                    kind.to_string()
                } else {
                    "type zeroGradient;".into()
                }
            })
            .collect()
    };
    let name = &m.patches[2].name;
    for (entry, message) in [
        (
            "type noSuchCondition;",
            "unknown boundary condition type 'noSuchCondition'",
        ),
        ("type fixedValue;", "without a `value`"),
        ("type cyclic;", "not supported"),
        ("type processor;", "reconstructPar"),
    ] {
        let d = case(&m, &u_file(&cells, &m, &with(entry)));
        let e = read(d.path(), &m).expect_err(entry);
        let MeshError::Invalid {
            file,
            entry: at,
            message: msg,
        } = &e
        else {
            panic!("{e}");
        };
        assert_eq!(file, &d.path().join("0/U"));
        assert_eq!(at, &format!("boundaryField/{name}/type"), "{e}");
        assert!(msg.contains(message), "{msg}");
        if entry.contains("noSuch") {
            assert!(
                msg.contains("noSlip") && msg.contains("inletOutlet"),
                "{msg}"
            );
        }
    }
}

/// The nodes (cell value, mesh points, face centres) a point value is built from, and the
/// cell and boundary-face values each node is built from.
struct Sources<'a> {
    mesh: &'a PolyMesh,
    geom: &'a MeshGeometry,
    field: &'a CellField,
    face_value: Vec<DVec3>,
    point_faces: Vec<Vec<usize>>,
}

impl<'a> Sources<'a> {
    fn new(mesh: &'a PolyMesh, geom: &'a MeshGeometry, field: &'a CellField) -> Self {
        let ni = mesh.n_internal_faces();
        let mut face_value = vec![DVec3::ZERO; mesh.n_faces()];
        let mut point_faces = vec![Vec::new(); mesh.points.len()];
        for (pi, p) in mesh.patches.iter().enumerate() {
            for (i, f) in (p.start..p.start + p.size).enumerate() {
                face_value[f] = match &field.patches[pi] {
                    Some(v) => v[i],
                    None => field.cells[mesh.owner[f] as usize],
                };
                for &q in mesh.face(f) {
                    point_faces[q as usize].push(f);
                }
            }
        }
        assert!(ni <= mesh.n_faces());
        Sources {
            mesh,
            geom,
            field,
            face_value,
            point_faces,
        }
    }

    fn point(&self, p: usize, lo: &mut DVec3, hi: &mut DVec3) {
        for &c in self.geom.cells_of_point(p) {
            let u = self.field.cells[c as usize];
            *lo = lo.min(u);
            *hi = hi.max(u);
        }
        for &f in &self.point_faces[p] {
            *lo = lo.min(self.face_value[f]);
            *hi = hi.max(self.face_value[f]);
        }
    }

    /// The range of the values node `n` is built from.
    fn node(&self, n: u32, lo: &mut DVec3, hi: &mut DVec3) {
        let np = self.mesh.points.len();
        if (n as usize) < np {
            self.point(n as usize, lo, hi);
        } else {
            for &p in self.mesh.face(n as usize - np) {
                self.point(p as usize, lo, hi);
            }
        }
    }

    fn cell(&self, c: u32, lo: &mut DVec3, hi: &mut DVec3) {
        let u = self.field.cells[c as usize];
        *lo = lo.min(u);
        *hi = hi.max(u);
    }
}

/// A square duct of no-slip walls along x (0.1 × 0.02 × 0.02 m), inlet at x = 0 with a
/// plug inflow, outlet zeroGradient; the cells hold a developing duct profile with swirl.
fn duct(shape: CellShape, perturb: f64) -> (PolyMesh, CellField) {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::new(0.1, 0.02, 0.02), [20, 5, 5])
        .shape(shape)
        .perturbed(perturb, 4)
        .naming(PatchNaming::InletOutletWalls { axis: 0 })
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let cells = g
        .cell_centres
        .iter()
        .map(|c| {
            let (y, z) = (c.y / 0.02, c.z / 0.02);
            let shape = 16.0 * y * (1.0 - y) * z * (1.0 - z);
            DVec3::new(
                10.0 * shape.powf(0.3) * (1.0 + 5.0 * c.x),
                3.0 * (z - 0.5) * shape,
                -3.0 * (y - 0.5) * shape,
            )
        })
        .collect();
    let patches = m
        .patches
        .iter()
        .map(|p| match p.name.as_str() {
            "walls" => Some(vec![DVec3::ZERO; p.size]),
            "inlet" => Some(vec![DVec3::new(10.0, 0.0, 0.0); p.size]),
            _ => None,
        })
        .collect();
    (m, CellField { cells, patches })
}

/// Every component of every interpolated value lies within the range of the values it is
/// built from, for every scheme, at 10^5 random points of which half lie within 0.5 mm of
/// an edge or a corner of the duct; and points up to 0.5 mm beyond a wall (a mid-step
/// point) take values within their cell's range, never an extrapolation.
#[test]
fn interpolation_never_overshoots_at_edges_and_corners() {
    let schemes = [
        Interpolation::CellValue,
        Interpolation::CellPoint,
        Interpolation::CellPointIdw,
    ];
    for (shape, perturb) in [
        (CellShape::Hex, 0.0),
        (CellShape::Hex, 0.2),
        (CellShape::Tet, 0.15),
    ] {
        let (m, field) = duct(shape, perturb);
        let g = MeshGeometry::new(&m).unwrap();
        let loc = Locator::new(&m, &g).unwrap();
        let src = Sources::new(&m, &g, &field);
        let spread = field
            .cells
            .iter()
            .fold(0.0_f64, |a, u| a.max(u.abs().max_element()));
        let tol = 1e-9 * spread;
        let its: Vec<Interpolator> = schemes
            .iter()
            .map(|&s| Interpolator::new(&loc, &field, s).unwrap())
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(33);
        let n = if cfg!(debug_assertions) {
            4_000
        } else {
            100_000
        };
        let mut near_edges = 0;
        let mut checked = 0;
        for i in 0..n {
            let mut x = DVec3::new(
                rng.random_range(0.0..0.1),
                rng.random_range(0.0..0.02),
                rng.random_range(0.0..0.02),
            );
            if i % 2 == 0 {
                // within 0.5 mm of an edge along x (two walls) or a corner (inlet, walls)
                let d = 5e-4;
                x.y = if rng.random::<bool>() {
                    rng.random_range(0.0..d)
                } else {
                    0.02 - rng.random_range(0.0..d)
                };
                x.z = if rng.random::<bool>() {
                    rng.random_range(0.0..d)
                } else {
                    0.02 - rng.random_range(0.0..d)
                };
                if i % 6 == 0 {
                    x.x = if rng.random::<bool>() {
                        rng.random_range(0.0..d)
                    } else {
                        0.1 - rng.random_range(0.0..d)
                    };
                }
                near_edges += 1;
            }
            let Some(hit) = loc.find(x) else { continue };
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            src.cell(hit.cell, &mut lo, &mut hi);
            for &nd in &hit.nodes {
                src.node(nd, &mut lo, &mut hi);
            }
            for it in &its {
                let scheme = it.scheme();
                let u = it.at(&hit);
                assert!(
                    u.cmpge(lo - tol).all() && u.cmple(hi + tol).all(),
                    "{shape:?} {perturb} {scheme:?} at {x}: {u} outside [{lo}, {hi}]"
                );
            }
            checked += 1;
            // beyond the nearest wall by up to 0.5 mm, from the cell holding x
            let beyond = x + DVec3::new(0.0, if x.y < 0.01 { -1.0 } else { 1.0 }, 0.0)
                * (x.y.min(0.02 - x.y) + rng.random_range(0.0..5e-4));
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            src.cell(hit.cell, &mut lo, &mut hi);
            for &f in g.faces_of(hit.cell as usize) {
                src.node(m.points.len() as u32 + f, &mut lo, &mut hi);
            }
            for it in &its {
                let scheme = it.scheme();
                let u = it.velocity(hit.cell, beyond);
                assert!(
                    u.cmpge(lo - tol).all() && u.cmple(hi + tol).all(),
                    "{shape:?} {scheme:?} beyond the wall at {beyond}: {u} outside [{lo}, {hi}]"
                );
            }
        }
        assert!(
            checked > n * 9 / 10 && near_edges >= n / 2,
            "{checked} / {near_edges}"
        );
    }
}
