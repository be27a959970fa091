//! Bad OpenFOAM input: each case edits one file of the ASCII (or binary) fixture and checks
//! that the error names that file and the entry at fault.

use std::path::Path;

use scg_mesh::MeshError;
use scg_mesh::foam::{self, TimeSel};

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        let q = to.join(p.file_name().unwrap());
        if p.is_dir() {
            copy_dir(&p, &q);
        } else {
            std::fs::copy(&p, &q).unwrap();
        }
    }
}

/// A copy of fixture `name` with `file` edited by `edit`.
fn edited(name: &str, file: &str, edit: impl FnOnce(Vec<u8>) -> Vec<u8>) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/foam")
        .join(name);
    copy_dir(&src, dir.path());
    let p = dir.path().join(file);
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, edit(bytes)).unwrap();
    dir
}

fn replace(from: &str, to: &str) -> impl FnOnce(Vec<u8>) -> Vec<u8> {
    let (from, to) = (from.to_string(), to.to_string());
    move |b| {
        let s = String::from_utf8(b).unwrap();
        assert!(s.contains(&from), "fixture lacks {from:?}");
        s.replacen(&from, &to, 1).into_bytes()
    }
}

/// Read mesh and U; return the error.
fn error(dir: &Path) -> MeshError {
    let mesh = match foam::read_mesh(dir) {
        Ok(m) => m,
        Err(e) => return e,
    };
    foam::read_vector_field(dir, &mesh, TimeSel::Latest, "U").expect_err("read succeeded")
}

/// The error is `Invalid`, names `file` (relative to the case) and an entry containing
/// `entry`, and its message contains `message`.
fn assert_error(dir: &Path, e: &MeshError, file: &str, entry: &str, message: &str) {
    let MeshError::Invalid {
        file: f,
        entry: en,
        message: m,
    } = e
    else {
        panic!("not an Invalid error: {e}");
    };
    assert_eq!(f, &dir.join(file), "{e}");
    assert!(en.contains(entry), "entry {en:?} lacks {entry:?}: {e}");
    assert!(m.contains(message), "message {m:?} lacks {message:?}: {e}");
    // The Display form carries all three.
    let s = e.to_string();
    assert!(s.contains(&dir.join(file).display().to_string()) && s.contains(en.as_str()));
}

#[test]
fn wrong_field_class() {
    let d = edited("ascii", "0/U", replace("volVectorField", "volScalarField"));
    let e = error(d.path());
    assert_error(d.path(), &e, "0/U", "FoamFile/class", "volScalarField");
}

#[test]
fn field_length_differs_from_the_cells() {
    // Drop the last internal value: 26 values for 27 cells.
    let d = edited("ascii", "0/U", replace("27\n(", "26\n("));
    let e = error(d.path());
    // The list now has one value more than it says: the parser expects ')'.
    assert_error(d.path(), &e, "0/U", "internalField", "expected ')'");
    let d = edited("ascii", "0/U", |b| {
        let s = String::from_utf8(b).unwrap();
        let start = s.find("27\n(").unwrap();
        let line = s[start..].find("\n(0.1 ").unwrap() + start;
        let end = s[line + 1..].find('\n').unwrap() + line + 1;
        let s = format!("{}{}", &s[..line], &s[end..]).replacen("27\n(", "26\n(", 1);
        s.into_bytes()
    });
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "0/U",
        "internalField",
        "26 values where 27 are needed",
    );
}

#[test]
fn patch_value_count_differs_from_the_patch_faces() {
    let d = edited(
        "ascii",
        "0/U",
        replace("(0.0 0.0 1.5)\n)", "(0.0 0.0 1.5)\n(0 0 9)\n)"),
    );
    let d2 = d.path().join("0/U");
    let s = std::fs::read_to_string(&d2)
        .unwrap()
        .replacen("List<vector> 9", "List<vector> 10", 1);
    std::fs::write(&d2, s).unwrap();
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "0/U",
        "boundaryField/inlet/value",
        "10 values where 9 are needed",
    );
}

#[test]
fn non_finite_values() {
    let d = edited("ascii", "0/U", replace("(0.30000000000000004 ", "(nan "));
    let e = error(d.path());
    assert_error(d.path(), &e, "0/U", "internalField[3]", "not finite");
    let d = edited(
        "ascii",
        "constant/polyMesh/points",
        replace("(0.10000000000000001 0 0)", "(inf 0 0)"),
    );
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "constant/polyMesh/points",
        "points[1]",
        "not finite",
    );
}

#[test]
fn truncated_files() {
    // ASCII points cut inside the list.
    let d = edited("ascii", "constant/polyMesh/points", |b| {
        b[..b.len() / 2].to_vec()
    });
    let e = error(d.path());
    assert_error(d.path(), &e, "constant/polyMesh/points", "points", "");
    // Binary faces cut inside the raw point indices of the faceCompactList.
    let d = edited("binary", "constant/polyMesh/faces", |b| {
        b[..b.len() - 200].to_vec()
    });
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "constant/polyMesh/faces",
        "faces/points",
        "runs past the end of the file",
    );
    // Binary U cut inside the internal field.
    let d = edited("binary", "0/U", |b| {
        let at = b.windows(4).position(|w| w == b"27\n(").unwrap();
        b[..at + 100].to_vec()
    });
    let e = error(d.path());
    assert_error(d.path(), &e, "0/U", "internalField", "truncated");
}

#[test]
fn out_of_range_indices() {
    // A face point beyond the 64 points: PolyMesh::check names it.
    let d = edited(
        "ascii",
        "constant/polyMesh/faces",
        replace("4(1 5 21 17)", "4(1 5 21 64)"),
    );
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "constant/polyMesh",
        "faces",
        "point index 64 out of range (0..64)",
    );
    // A negative owner.
    let d = edited(
        "ascii",
        "constant/polyMesh/owner",
        replace("108\n(\n0\n", "108\n(\n-1\n"),
    );
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "constant/polyMesh/owner",
        "owner[0]",
        "invalid index -1",
    );
}

#[test]
fn boundary_inconsistent_with_the_faces() {
    let d = edited(
        "ascii",
        "constant/polyMesh/boundary",
        replace("startFace       90;", "startFace       91;"),
    );
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "constant/polyMesh",
        "boundary/inlet",
        "startFace 91 where 90 was expected",
    );
    let d = edited(
        "ascii",
        "constant/polyMesh/boundary",
        replace(
            "nFaces          9;\n        startFace       99;",
            "nFaces          8;\n        startFace       99;",
        ),
    );
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "constant/polyMesh",
        "boundary",
        "patches end at face 107, the mesh has 108 faces",
    );
}

#[test]
fn note_disagrees_with_the_owner_list() {
    let d = edited(
        "ascii",
        "constant/polyMesh/owner",
        replace("nCells:27", "nCells:28"),
    );
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "constant/polyMesh/owner",
        "FoamFile/note",
        "nCells:28",
    );
}

#[test]
fn directives_and_macros_are_rejected() {
    let d = edited(
        "ascii",
        "0/U",
        replace("dimensions ", "#include \"initialConditions\"\ndimensions "),
    );
    let e = error(d.path());
    assert_error(d.path(), &e, "0/U", "top level", "#include");
    let d = edited(
        "ascii",
        "0/U",
        replace(
            "value           uniform (0 0 0);",
            "value           $internalField;",
        ),
    );
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "0/U",
        "boundaryField/walls/value",
        "$internalField",
    );
}

#[test]
fn missing_patch_entry_and_missing_file() {
    let d = edited(
        "ascii",
        "0/U",
        replace(
            "    outlet\n    {\n        type            zeroGradient;\n    }\n",
            "",
        ),
    );
    let e = error(d.path());
    assert_error(d.path(), &e, "0/U", "boundaryField/outlet", "missing");
    let d = edited("ascii", "0/U", |b| b);
    std::fs::remove_file(d.path().join("constant/polyMesh/neighbour")).unwrap();
    match foam::read_mesh(d.path()) {
        Err(MeshError::Io { file, source }) => {
            assert_eq!(file, d.path().join("constant/polyMesh/neighbour"));
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn trailing_data_and_wrong_mesh_class() {
    let d = edited("ascii", "constant/polyMesh/neighbour", |mut b| {
        b.extend_from_slice(b"\n12 13\n");
        b
    });
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "constant/polyMesh/neighbour",
        "neighbour",
        "unexpected data after the list",
    );
    let d = edited(
        "ascii",
        "constant/polyMesh/points",
        replace("vectorField", "scalarField"),
    );
    let e = error(d.path());
    assert_error(
        d.path(),
        &e,
        "constant/polyMesh/points",
        "FoamFile/class",
        "scalarField",
    );
}
