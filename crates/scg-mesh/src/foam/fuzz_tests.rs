//! Bad bytes never panic: every truncation and many byte substitutions of the OpenFOAM
//! fixtures (ASCII and binary) go through the mesh and field parsers, in memory.

use std::path::{Path, PathBuf};

use super::field::parse_vector_field;
use super::mesh::parse_mesh;
use crate::{MeshError, PolyMesh};

const FILES: [&str; 5] = ["points", "faces", "owner", "neighbour", "boundary"];

struct Case {
    dir: PathBuf,
    files: Vec<(PathBuf, Vec<u8>)>,
    u: (PathBuf, Vec<u8>),
    mesh: PolyMesh,
}

fn case(name: &str) -> Case {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/foam")
        .join(name);
    let pm = dir.join("constant/polyMesh");
    let files: Vec<(PathBuf, Vec<u8>)> = FILES
        .iter()
        .map(|f| (pm.join(f), std::fs::read(pm.join(f)).unwrap()))
        .collect();
    let u = dir.join("0/U");
    let u = (u.clone(), std::fs::read(&u).unwrap());
    let mesh = super::read_mesh(&dir).unwrap();
    Case {
        dir,
        files,
        u,
        mesh,
    }
}

/// Parse the mesh with file `k` replaced by `bytes` (k = 5: the field U).
fn parse(c: &Case, k: usize, bytes: &[u8]) -> Result<(), MeshError> {
    if k == 5 {
        return parse_vector_field(&c.u.0, bytes, &c.mesh).map(|_| ());
    }
    let mut views: Vec<(&Path, &[u8])> = c
        .files
        .iter()
        .map(|(p, b)| (p.as_path(), b.as_slice()))
        .collect();
    views[k].1 = bytes;
    let arr: [(&Path, &[u8]); 5] = views.try_into().unwrap();
    parse_mesh(&c.dir.join("constant/polyMesh"), arr).map(|_| ())
}

fn original(c: &Case, k: usize) -> &(PathBuf, Vec<u8>) {
    if k == 5 { &c.u } else { &c.files[k] }
}

/// Every error names a file of the case and is an `Invalid` (never I/O: all is in memory).
fn assert_names_file(c: &Case, e: &MeshError) {
    match e {
        MeshError::Invalid { file, entry, .. } => {
            assert!(file.starts_with(&c.dir), "{e}");
            assert!(!entry.is_empty(), "{e}");
        }
        MeshError::Io { .. } => panic!("unexpected I/O error {e}"),
    }
}

#[test]
fn every_truncation_is_an_error_and_never_panics() {
    for name in ["ascii", "binary"] {
        let c = case(name);
        let mut n = 0;
        for k in 0..6 {
            let (_, bytes) = original(&c, k);
            assert!(parse(&c, k, bytes).is_ok());
            // The data ends at the last ')' (mesh files) or '}' (U); after it only a comment.
            let end = bytes
                .iter()
                .rposition(|&b| b == if k == 5 { b'}' } else { b')' })
                .unwrap();
            for len in 0..bytes.len() {
                let r = parse(&c, k, &bytes[..len]);
                if len <= end {
                    let e = r.expect_err(&format!("{name} file {k} cut at {len} parsed"));
                    assert_names_file(&c, &e);
                }
                n += 1;
            }
        }
        println!("{name}: {n} truncations");
        assert!(n > 10_000, "{n} truncations");
    }
}

#[test]
fn byte_substitutions_never_panic() {
    let subs = [b'9', b'(', b')', b';', b'{', 0xff, b'n'];
    for name in ["ascii", "binary"] {
        let c = case(name);
        let (mut errors, mut total) = (0, 0);
        for k in 0..6 {
            let mut bytes = original(&c, k).1.clone();
            for i in 0..bytes.len() {
                let keep = bytes[i];
                for &s in &subs {
                    if s == keep {
                        continue;
                    }
                    bytes[i] = s;
                    if let Err(e) = parse(&c, k, &bytes) {
                        assert_names_file(&c, &e);
                        errors += 1;
                    }
                    total += 1;
                }
                bytes[i] = keep;
            }
        }
        // Most substitutions break something; some (a digit in a coordinate, a space in a
        // comment, a binary payload byte) are still valid files.
        println!("{name}: {errors} errors of {total} substitutions");
        assert!(errors > total / 4, "{name}: {errors} errors of {total}");
    }
}
