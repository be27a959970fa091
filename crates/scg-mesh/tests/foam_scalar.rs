//! OpenFOAM volScalarFields (turbulence k, epsilon, omega, nut): writer → reader round trips
//! (ASCII, binary, gzip), `uniform` and `nonuniform` values, every class of scalar
//! boundary type, bad input (negative k, NaN, wrong class, wrong counts), and files written
//! by OpenFOAM v1912 (`tests/fixtures/foam/kepsilon`, `komega_binary`; the simpleFoam
//! pitzDaily tutorial when the `openfoam-examples` package is installed).

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::DVec3;
use scg_mesh::build::{BoxMesh, PatchNaming};
use scg_mesh::foam::boundary::{FaceValue, SCALAR_TABLE};
use scg_mesh::foam::{self, Format, TimeSel};
use scg_mesh::{MeshError, Patch, PolyMesh, ScalarField};

/// A 3 × 2 × 4 box with patches inlet (z low), outlet (z high) and walls.
fn mesh() -> PolyMesh {
    BoxMesh::new(DVec3::ZERO, DVec3::new(0.3, 0.2, 0.4), [3, 2, 4])
        .naming(PatchNaming::InletOutletWalls { axis: 2 })
        .build()
        .unwrap()
}

fn patch<'a>(m: &'a PolyMesh, name: &str) -> (usize, &'a Patch) {
    m.patches
        .iter()
        .enumerate()
        .find(|(_, p)| p.name == name)
        .unwrap()
}

/// A case with `mesh` written (ASCII) and no fields.
fn case(mesh: &PolyMesh) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    foam::write_case(dir.path(), mesh, None, Format::Ascii).unwrap();
    dir
}

/// A volScalarField file: `internal` after `internalField`, each `(patch, body)` as the
/// patch's dictionary body.
fn field_text(class: &str, internal: &str, patches: &[(&str, &str)]) -> String {
    let mut s = format!(
        "FoamFile\n{{\n    version 2.0;\n    format ascii;\n    class {class};\n    object k;\n}}\n\
         dimensions [0 2 -2 0 0 0 0];\ninternalField {internal};\nboundaryField\n{{\n"
    );
    for (p, body) in patches {
        s.push_str(&format!("    {p} {{ {body} }}\n"));
    }
    s.push_str("}\n");
    s
}

/// Write `text` as `0/k` of `dir` and read it.
fn read_k(dir: &Path, mesh: &PolyMesh, text: &str) -> Result<ScalarField, MeshError> {
    std::fs::create_dir_all(dir.join("0")).unwrap();
    std::fs::write(dir.join("0/k"), text).unwrap();
    foam::read_scalar_field(dir, mesh, TimeSel::Latest, "k")
}

/// The error is `Invalid`, names `file`, an entry containing `entry`, and a message
/// containing every one of `message`.
fn assert_invalid(e: &MeshError, file: &Path, entry: &str, message: &[&str]) {
    let MeshError::Invalid {
        file: f,
        entry: en,
        message: m,
    } = e
    else {
        panic!("not Invalid: {e}");
    };
    assert_eq!(f, file, "{e}");
    assert!(en.contains(entry), "entry {en:?} lacks {entry:?}: {e}");
    for part in message {
        assert!(m.contains(part), "message lacks {part:?}: {e}");
    }
}

/// A nonuniform field with negative, tiny and large values; inlet values, the others none.
fn sample(m: &PolyMesh) -> ScalarField {
    let cells = (0..m.n_cells)
        .map(|i| (i as f64 * 0.37).sin() * 10f64.powi(i as i32 % 7 - 3))
        .collect();
    let patches = m
        .patches
        .iter()
        .map(|p| (p.name == "inlet").then(|| (0..p.size).map(|k| 0.1 + k as f64 / 3.0).collect()))
        .collect();
    ScalarField { cells, patches }
}

#[test]
fn ascii_binary_and_gzip_round_trips_are_exact() {
    let m = mesh();
    let field = sample(&m);
    for format in [Format::Ascii, Format::Binary] {
        let dir = case(&m);
        foam::write_scalar_field(dir.path(), "0", "k", &m, &field, format).unwrap();
        let back = foam::read_scalar_field(dir.path(), &m, TimeSel::Latest, "k").unwrap();
        assert_eq!(back, field, "{format:?}");
        let text = std::fs::read(dir.path().join("0/k")).unwrap();
        assert!(text.windows(14).any(|w| w == b"volScalarField"));
        // gzipped: 0/k.gz is read when 0/k is absent
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(&text).unwrap();
        std::fs::write(dir.path().join("0/k.gz"), gz.finish().unwrap()).unwrap();
        std::fs::remove_file(dir.path().join("0/k")).unwrap();
        let back = foam::read_scalar_field(dir.path(), &m, TimeSel::Time(0.0), "k").unwrap();
        assert_eq!(back, field, "{format:?} gzipped");
    }
    // The writer checks the counts.
    let mut short = field.clone();
    short.cells.pop();
    let dir = case(&m);
    let e = foam::write_scalar_field(dir.path(), "0", "k", &m, &short, Format::Ascii);
    assert!(e.unwrap_err().to_string().contains("internalField"));
}

#[test]
fn uniform_and_nonuniform_values() {
    let m = mesh();
    let dir = case(&m);
    let (_, inlet) = patch(&m, "inlet");
    let n = inlet.size;
    let list: Vec<String> = (0..n).map(|k| format!("{}", -0.5 * k as f64)).collect();
    let text = field_text(
        "volScalarField",
        &format!("nonuniform List<scalar> {}{{0.25}}", m.n_cells),
        &[
            ("walls", "type fixedValue; value uniform 1e-3;"),
            (
                "inlet",
                &format!(
                    "type fixedValue; value nonuniform List<scalar> {n}({});",
                    list.join(" ")
                ),
            ),
            ("outlet", "type zeroGradient;"),
        ],
    );
    let f = read_k(dir.path(), &m, &text).unwrap();
    assert_eq!(f.cells, vec![0.25; m.n_cells]);
    let (w, walls) = patch(&m, "walls");
    assert_eq!(f.patches[w], Some(vec![1e-3; walls.size]));
    let (i, _) = patch(&m, "inlet");
    let want: Vec<f64> = (0..n).map(|k| -0.5 * k as f64).collect();
    assert_eq!(f.patches[i], Some(want));
    assert_eq!(f.patches[patch(&m, "outlet").0], None);
    // A uniform internal field, and a regular-expression entry for every patch.
    let text = field_text(
        "volScalarField",
        "uniform -2",
        &[("\".*\"", "type zeroGradient;")],
    );
    let f = read_k(dir.path(), &m, &text).unwrap();
    assert_eq!(f.cells, vec![-2.0; m.n_cells]);
    assert!(f.patches.iter().all(Option::is_none));
}

#[test]
fn every_scalar_boundary_type_class() {
    let m = mesh();
    let dir = case(&m);
    let file = dir.path().join("0/k");
    let (w, walls) = patch(&m, "walls");
    let others = [
        ("inlet", "type zeroGradient;"),
        ("outlet", "type zeroGradient;"),
    ];
    let with = |body: &str| {
        let mut p = vec![("walls", body)];
        p.extend(others);
        field_text("volScalarField", "uniform 3", &p)
    };
    for &(kind, meaning) in SCALAR_TABLE {
        // Every type with a value that differs from the owner's (3).
        let r = read_k(
            dir.path(),
            &m,
            &with(&format!("type {kind}; value uniform 7;")),
        );
        match meaning {
            FaceValue::Written => {
                assert_eq!(r.unwrap().patches[w], Some(vec![7.0; walls.size]), "{kind}");
                // ... and without one: an error asking for the value.
                let e = read_k(dir.path(), &m, &with(&format!("type {kind};"))).unwrap_err();
                assert_invalid(&e, &file, "boundaryField/walls/type", &[kind, "`value`"]);
            }
            FaceValue::Owner | FaceValue::Empty => {
                assert_eq!(r.unwrap().patches[w], None, "{kind}");
                let r = read_k(dir.path(), &m, &with(&format!("type {kind};")));
                assert_eq!(r.unwrap().patches[w], None, "{kind}");
            }
            FaceValue::Unsupported(why) => {
                let e = r.unwrap_err();
                assert_invalid(
                    &e,
                    &file,
                    "boundaryField/walls/type",
                    &[kind, "not supported", why],
                );
            }
            FaceValue::Zero | FaceValue::Tangential => panic!("{kind}: a vector kind"),
        }
    }
    // kqRWallFunction is a zeroGradient type: its written value is not used.
    let f = read_k(
        dir.path(),
        &m,
        &with("type kqRWallFunction; value uniform 0.5;"),
    );
    assert_eq!(f.unwrap().patches[w], None);
    // noSlip is a vector type; a made-up one is unknown. Both name patch, type and the list.
    for kind in ["noSlip", "fooBarWallFunction"] {
        let e = read_k(
            dir.path(),
            &m,
            &with(&format!("type {kind}; value uniform 1;")),
        )
        .unwrap_err();
        assert_invalid(
            &e,
            &file,
            "boundaryField/walls/type",
            &[kind, "unknown", "kqRWallFunction", "epsilonWallFunction"],
        );
    }
    // A patch without an entry.
    let text = field_text("volScalarField", "uniform 3", &others);
    let e = read_k(dir.path(), &m, &text).unwrap_err();
    assert_invalid(&e, &file, "boundaryField/walls", &["missing"]);
}

#[test]
fn negative_k_is_rejected_by_check_non_negative() {
    let m = mesh();
    let dir = case(&m);
    let file = dir.path().join("0/k");
    let mut values = vec!["0.01".to_string(); m.n_cells];
    values[3] = "-0.0025".into();
    let (i, inlet) = patch(&m, "inlet");
    let text = |internal: &str, inlet_value: &str| {
        field_text(
            "volScalarField",
            internal,
            &[
                ("walls", "type kqRWallFunction; value uniform 0.01;"),
                ("inlet", &format!("type fixedValue; value {inlet_value};")),
                (
                    "outlet",
                    "type inletOutlet; inletValue uniform 0; value uniform 0;",
                ),
            ],
        )
    };
    // Negative values are valid scalars ...
    let internal = format!(
        "nonuniform List<scalar> {}({})",
        m.n_cells,
        values.join(" ")
    );
    let f = read_k(dir.path(), &m, &text(&internal, "uniform 0.01")).unwrap();
    assert_eq!(f.cells[3], -0.0025);
    // ... but not for k.
    let e = f.check_non_negative(&file, "k", &m).unwrap_err();
    assert_invalid(&e, &file, "internalField[3]", &["k", "negative", "-0.0025"]);
    assert!(e.to_string().contains(&file.display().to_string()));
    // A negative face value names the patch's value entry.
    let mut face = vec!["0.01".to_string(); inlet.size];
    face[1] = "-7".into();
    let value = format!("nonuniform List<scalar> {}({})", inlet.size, face.join(" "));
    let f = read_k(dir.path(), &m, &text("uniform 0.01", &value)).unwrap();
    assert_eq!(f.patches[i].as_ref().unwrap()[1], -7.0);
    let e = f.check_non_negative(&file, "k", &m).unwrap_err();
    assert_invalid(
        &e,
        &file,
        "boundaryField/inlet/value[1]",
        &["negative", "-7"],
    );
    // Zero is fine.
    let f = read_k(dir.path(), &m, &text("uniform 0", "uniform 0")).unwrap();
    f.check_non_negative(&file, "k", &m).unwrap();
}

#[test]
fn nan_and_inf_are_errors() {
    let m = mesh();
    let dir = case(&m);
    let file = dir.path().join("0/k");
    let rest = [
        ("walls", "type zeroGradient;"),
        ("outlet", "type zeroGradient;"),
    ];
    let mut values = vec!["1".to_string(); m.n_cells];
    values[5] = "nan".into();
    let internal = format!(
        "nonuniform List<scalar> {}({})",
        m.n_cells,
        values.join(" ")
    );
    let mut p = vec![("inlet", "type zeroGradient;")];
    p.extend(rest);
    let e = read_k(dir.path(), &m, &field_text("volScalarField", &internal, &p)).unwrap_err();
    assert_invalid(&e, &file, "internalField[5]", &["not finite", "NaN"]);
    let mut p = vec![("inlet", "type fixedValue; value uniform inf;")];
    p.extend(rest);
    let e = read_k(
        dir.path(),
        &m,
        &field_text("volScalarField", "uniform 1", &p),
    )
    .unwrap_err();
    assert_invalid(
        &e,
        &file,
        "boundaryField/inlet/value[0]",
        &["not finite", "inf"],
    );
    // In a binary file too.
    let mut f = ScalarField {
        cells: vec![1.0; m.n_cells],
        patches: vec![None; m.patches.len()],
    };
    f.cells[2] = f64::NAN;
    foam::write_scalar_field(dir.path(), "0", "k", &m, &f, Format::Binary).unwrap();
    let e = foam::read_scalar_field(dir.path(), &m, TimeSel::Latest, "k").unwrap_err();
    assert_invalid(&e, &file, "internalField[2]", &["not finite"]);
}

#[test]
fn wrong_class_and_wrong_counts_are_errors() {
    let m = mesh();
    let dir = case(&m);
    let file = dir.path().join("0/k");
    let zg = [
        ("walls", "type zeroGradient;"),
        ("inlet", "type zeroGradient;"),
        ("outlet", "type zeroGradient;"),
    ];
    // A volVectorField given as a scalar, and the reverse.
    let u = field_text("volVectorField", "uniform (1 0 0)", &zg);
    let e = read_k(dir.path(), &m, &u).unwrap_err();
    assert_invalid(
        &e,
        &file,
        "FoamFile/class",
        &["volVectorField", "volScalarField"],
    );
    let k = field_text("volScalarField", "uniform 1", &zg);
    std::fs::write(&file, &k).unwrap();
    let e = foam::read_vector_field(dir.path(), &m, TimeSel::Latest, "k").unwrap_err();
    assert_invalid(&e, &file, "FoamFile/class", &["volScalarField"]);
    // A vector value or list in a scalar file.
    let e = read_k(
        dir.path(),
        &m,
        &field_text("volScalarField", "uniform (1 0 0)", &zg),
    );
    assert_invalid(&e.unwrap_err(), &file, "internalField", &["vector"]);
    let text = field_text(
        "volScalarField",
        &format!("nonuniform List<vector> {}{{(1 0 0)}}", m.n_cells),
        &zg,
    );
    let e = read_k(dir.path(), &m, &text).unwrap_err();
    assert_invalid(&e, &file, "internalField", &["List<scalar>"]);
    // One value too few in the cells, one too many on a patch.
    let n = m.n_cells - 1;
    let text = field_text(
        "volScalarField",
        &format!("nonuniform List<scalar> {n}{{1}}"),
        &zg,
    );
    let e = read_k(dir.path(), &m, &text).unwrap_err();
    assert_invalid(
        &e,
        &file,
        "internalField",
        &[&format!("{n} values where {} are needed", m.n_cells)],
    );
    let n = patch(&m, "inlet").1.size + 1;
    let inlet = format!("type fixedValue; value nonuniform List<scalar> {n}{{1}};");
    let text = field_text(
        "volScalarField",
        "uniform 1",
        &[zg[0], ("inlet", &inlet), zg[2]],
    );
    let e = read_k(dir.path(), &m, &text).unwrap_err();
    assert_invalid(&e, &file, "boundaryField/inlet/value", &["values where"]);
    // A missing file is an I/O error naming it.
    let e = foam::read_scalar_field(dir.path(), &m, TimeSel::Latest, "omega").unwrap_err();
    assert!(
        matches!(&e, MeshError::Io { file, .. } if file.ends_with("0/omega")),
        "{e}"
    );
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/foam")
        .join(name)
}

/// The face values the file writes on `patch` although its type reads them as the owner's
/// (the type replaced by fixedValue).
fn written_values(file: &Path, mesh: &PolyMesh, patch: &str, kind: &str) -> Vec<f64> {
    let text = std::fs::read(file).unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("0")).unwrap();
    let from = format!("type            {kind};").into_bytes();
    let at = text.windows(from.len()).position(|w| w == from).unwrap();
    let mut edited = text[..at].to_vec();
    edited.extend(b"type fixedValue;");
    edited.extend(&text[at + from.len()..]);
    std::fs::write(dir.path().join("0/f"), edited).unwrap();
    let f = foam::read_scalar_field(dir.path(), mesh, TimeSel::Latest, "f").unwrap();
    f.patches[patch_index(mesh, patch)].clone().unwrap()
}

/// Equal to 1e-14 relative: what OpenFOAM computes twice in double precision.
fn assert_close(a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!((x - y).abs() <= 1e-14 * y.abs(), "face {i}: {x} vs {y}");
    }
}

fn patch_index(m: &PolyMesh, name: &str) -> usize {
    m.patches.iter().position(|p| p.name == name).unwrap()
}

fn owner_values(m: &PolyMesh, patch: &str, cells: &[f64]) -> Vec<f64> {
    let p = &m.patches[patch_index(m, patch)];
    (p.start..p.start + p.size)
        .map(|f| cells[m.owner[f] as usize])
        .collect()
}

#[test]
fn openfoam_kepsilon_fields_ascii() {
    let case = fixture("kepsilon");
    let m = foam::read_mesh(&case).unwrap();
    let (walls, inlet, outlet) = (
        patch_index(&m, "walls"),
        patch_index(&m, "inlet"),
        patch_index(&m, "outlet"),
    );
    // 0/: the hand-written input. kqRWallFunction's value 0.5 is not the owners'.
    let k0 = foam::read_scalar_field(&case, &m, TimeSel::Time(0.0), "k").unwrap();
    assert_eq!(k0.cells[0], 0.001);
    assert_eq!(k0.patches[walls], None);
    assert_eq!(k0.patches[inlet], Some(vec![0.00375; 9]));
    // 1/: written by simpleFoam (kEpsilon) after one iteration.
    for name in ["k", "epsilon", "nut", "p"] {
        let f = foam::read_scalar_field(&case, &m, TimeSel::Latest, name).unwrap();
        assert_eq!(f.cells.len(), 27, "{name}");
        if name != "p" {
            f.check_non_negative(case.join("1").join(name), name, &m)
                .unwrap();
            assert!(f.cells.iter().all(|&x| x > 0.0), "{name}");
        }
    }
    let file = case.join("1/k");
    let k = foam::read_scalar_field(&case, &m, TimeSel::Latest, "k").unwrap();
    assert_eq!(
        k.patches[walls], None,
        "kqRWallFunction: the owners' values"
    );
    // ... which is what OpenFOAM wrote as its value.
    let w = written_values(&file, &m, "walls", "kqRWallFunction");
    assert_eq!(w, owner_values(&m, "walls", &k.cells));
    // the inlet (turbulentIntensityKineticEnergyInlet) and outlet (inletOutlet) values
    assert_eq!(k.patches[inlet], Some(vec![0.0037500000000000007; 9]));
    assert_eq!(k.patches[outlet].as_ref().unwrap().len(), 9);
    // epsilonWallFunction: OpenFOAM sets the wall faces to the wall cells' values.
    let eps = foam::read_scalar_field(&case, &m, TimeSel::Latest, "epsilon").unwrap();
    // (computed separately by the wall function: equal to within an ulp or two)
    let on_walls = eps.patches[walls].as_ref().unwrap();
    assert_close(on_walls, &owner_values(&m, "walls", &eps.cells));
    assert_eq!(eps.patches[outlet], None);
    assert_eq!(eps.patches[inlet].as_ref().unwrap().len(), 9);
    let nut = foam::read_scalar_field(&case, &m, TimeSel::Latest, "nut").unwrap();
    assert!(nut.patches.iter().all(Option::is_some), "all written");
    // phi is a surfaceScalarField, U a vector.
    for (name, class) in [("phi", "surfaceScalarField"), ("U", "volVectorField")] {
        let e = foam::read_scalar_field(&case, &m, TimeSel::Latest, name).unwrap_err();
        assert_invalid(&e, &case.join("1").join(name), "FoamFile/class", &[class]);
    }
}

#[test]
fn openfoam_komega_fields_binary() {
    let case = fixture("komega_binary");
    let m = foam::read_mesh(&case).unwrap();
    let walls = patch_index(&m, "walls");
    let text = std::fs::read(case.join("1/omega")).unwrap();
    assert!(text.windows(13).any(|w| w == b"format      b"));
    for name in ["k", "omega", "nut"] {
        let f = foam::read_scalar_field(&case, &m, TimeSel::Latest, name).unwrap();
        assert_eq!(f.cells.len(), 27);
        f.check_non_negative(case.join("1").join(name), name, &m)
            .unwrap();
    }
    // omegaWallFunction, as epsilon's: the wall cells' values on the faces.
    let omega = foam::read_scalar_field(&case, &m, TimeSel::Latest, "omega").unwrap();
    assert_close(
        omega.patches[walls].as_ref().unwrap(),
        &owner_values(&m, "walls", &omega.cells),
    );
    let k = foam::read_scalar_field(&case, &m, TimeSel::Latest, "k").unwrap();
    assert_eq!(k.patches[walls], None);
    // The same case's ASCII k (0/, hand-written) reads as from the ASCII fixture.
    let k0 = foam::read_scalar_field(&case, &m, TimeSel::Time(0.0), "k").unwrap();
    let ka = foam::read_scalar_field(fixture("kepsilon"), &m, TimeSel::Time(0.0), "k").unwrap();
    assert_eq!(k0, ka);
}

/// The simpleFoam pitzDaily tutorial's 0/k, 0/epsilon, 0/nut (uniform values) on a box
/// with its patch names, when the openfoam-examples package is installed.
#[test]
fn pitzdaily_tutorial_fields_if_installed() {
    let tut = Path::new(
        "/usr/share/doc/openfoam-examples/examples/incompressible/simpleFoam/pitzDaily/0",
    );
    if !tut.join("k").exists() {
        eprintln!("skipped: {} not installed", tut.display());
        return;
    }
    // xmin..zmax → inlet, outlet, lowerWall, upperWall, frontAndBack (z sides, merged).
    let mut m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [2, 2, 1])
        .build()
        .unwrap();
    let names = ["inlet", "outlet", "lowerWall", "upperWall", "frontAndBack"];
    let kinds = ["patch", "patch", "wall", "wall", "empty"];
    let zmax = m.patches.pop().unwrap();
    m.patches[4].size += zmax.size;
    for (p, (n, k)) in m.patches.iter_mut().zip(names.iter().zip(kinds)) {
        p.name = n.to_string();
        p.kind = k.to_string();
    }
    m.check(Path::new("pitzDaily box")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("0")).unwrap();
    for name in ["k", "epsilon", "nut", "omega"] {
        std::fs::copy(tut.join(name), dir.path().join("0").join(name)).unwrap();
    }
    let read = |name| foam::read_scalar_field(dir.path(), &m, TimeSel::Latest, name);
    let k = read("k").unwrap();
    assert_eq!(k.cells, vec![0.375; m.n_cells]);
    // inlet fixedValue, outlet zeroGradient, walls kqRWallFunction, frontAndBack empty
    assert_eq!(k.patches[0], Some(vec![0.375; m.patches[0].size]));
    assert!(k.patches[1..].iter().all(Option::is_none));
    let eps = read("epsilon").unwrap();
    assert_eq!(eps.cells[0], 14.855);
    assert!(eps.patches[2].is_some() && eps.patches[3].is_some());
    let nut = read("nut").unwrap();
    for (i, p) in nut.patches.iter().enumerate() {
        assert_eq!(p.is_some(), i < 4, "patch {i}");
    }
    for (f, name) in [(&k, "k"), (&eps, "epsilon"), (&nut, "nut")] {
        f.check_non_negative(dir.path().join("0").join(name), name, &m)
            .unwrap();
    }
    // omega writes `value $internalField;`, a macro scg does not expand.
    let e = read("omega").unwrap_err();
    assert_invalid(
        &e,
        &dir.path().join("0/omega"),
        "boundaryField/inlet/value",
        &["$internalField", "not supported"],
    );
}
