//! Corrupt VTK files: byte substitutions in the files VTK 9.1 wrote
//! (`tests/fixtures/vtk`) give a valid mesh or an error naming the file, never a panic or
//! an abort (counts are bounded before vtkio allocates; vtkio's own panics are caught).

use std::path::{Path, PathBuf};

use scg_mesh::vtk;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/vtk")
        .join(name)
}

const FILES: [&str; 8] = [
    "mixed_ascii42.vtk",
    "mixed_binary.vtk",
    "mixed_ascii.vtu",
    "mixed_base64.vtu",
    "mixed_appended_zlib.vtu",
    "mixed_appended_raw.vtu",
    "mixed_appended_base64.vtu",
    "poly.vtk",
];

/// Byte substitutions in the VTK-written files (every 13th byte, two values) give a mesh
/// or an error naming the file, never a panic.
#[test]
fn corrupted_vtk_files_never_panic() {
    // vtkio panics on some corrupt inputs; `vtk::read` catches those. Keep their messages
    // out of the test output (this test is alone in its binary, so the hook is its own).
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if !info.location().is_some_and(|l| l.file().contains("vtkio")) {
            default(info);
        }
    }));
    let dir = tempfile::tempdir().unwrap();
    let (mut errors, mut total) = (0, 0);
    for name in FILES {
        let t = std::time::Instant::now();
        let bytes = std::fs::read(fixture(name)).unwrap();
        let ext = Path::new(name).extension().unwrap().to_str().unwrap();
        let path = dir.path().join(format!("bad.{ext}"));
        for i in (0..bytes.len()).step_by(13) {
            for s in [b'9', 0xff] {
                let mut b = bytes.clone();
                b[i] = s;
                std::fs::write(&path, &b).unwrap();
                match vtk::read(&path, "U") {
                    Err(e) => {
                        assert!(e.to_string().contains(&path.display().to_string()), "{e}");
                        errors += 1;
                    }
                    Ok((m, _)) => m.check(&path).unwrap(),
                }
                total += 1;
            }
        }
        println!("{name}: {:.2} s", t.elapsed().as_secs_f64());
    }
    println!("{errors} errors of {total} substitutions");
    assert!(errors > total / 10, "{errors} of {total}");
    let _ = std::panic::take_hook();
}
