//! Write a box mesh of scg's generators (`scg_mesh::build`) as an OpenFOAM case, for
//! `bench/vs-openfoam.sh --mesh tet|poly` (blockMesh makes only hexahedra).
//!
//! ```sh
//! cargo run --release -p scg-mesh --example write_box_mesh -- DIR SHAPE NX NY NZ W H [PERTURB]
//!     [--series N SPACING]
//! ```
//!
//! SHAPE is `hex`, `tet` (6 per hexahedron) or `poly` (a quarter of the hexahedra refined,
//! hanging nodes); NX × NY × NZ hexahedra over x, y in [−W, W] and z in [0, H] (m); the
//! interior points moved by up to PERTURB (default 0) of the spacing. Patches `inlet`
//! (z = 0, type patch), `outlet` (z = H, type patch) and `walls` (the sides, type wall).
//! Writes DIR/constant/polyMesh (ASCII) and a minimal DIR/system; no field, unless
//! `--series N SPACING`: then also N time folders 0, SPACING, 2·SPACING, … each holding a
//! binary `U` at the cell centres, a vortex about z whose rate swings in time,
//! u = ω(t)·(−y, x, 0) + (0, 0, 0.01·(1 − r²/W²)), ω(t) = 31.4·(1 + 0.5·sin(2π·t/(N·SPACING)))
//! rad/s (an unsteady series for `[flow] series`, e.g. its memory at 10^6 cells).

use glam::DVec3;
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let (a, series) = match a.iter().position(|s| s == "--series") {
        Some(i) if a.len() == i + 3 => {
            let n: usize = a[i + 1].parse().unwrap_or(0);
            let dt: f64 = a[i + 2].parse().unwrap_or(f64::NAN);
            if n < 2 || dt.is_nan() || dt <= 0.0 {
                eprintln!("--series N SPACING: N ≥ 2 snapshots, SPACING > 0 s");
                std::process::exit(2);
            }
            (a[..i].to_vec(), Some((n, dt)))
        }
        Some(_) => {
            eprintln!("usage: --series N SPACING (last)");
            std::process::exit(2);
        }
        None => (a, None),
    };
    let num = |i: usize| -> f64 {
        a[i].parse().unwrap_or_else(|_| {
            eprintln!("not a number: {}", a[i]);
            std::process::exit(2)
        })
    };
    if a.len() < 8 {
        eprintln!(
            "usage: write_box_mesh DIR hex|tet|poly NX NY NZ W H [PERTURB] [--series N SPACING]"
        );
        std::process::exit(2);
    }
    let shape = match a[2].as_str() {
        "hex" => CellShape::Hex,
        "tet" => CellShape::Tet,
        "poly" => CellShape::Poly { refine: 0.25 },
        s => {
            eprintln!("unknown shape {s}");
            std::process::exit(2)
        }
    };
    let n = [num(3) as usize, num(4) as usize, num(5) as usize];
    let (w, h) = (num(6), num(7));
    let perturb = if a.len() > 8 { num(8) } else { 0.0 };
    let mesh = BoxMesh::new(DVec3::new(-w, -w, 0.0), DVec3::new(w, w, h), n)
        .shape(shape)
        .naming(PatchNaming::InletOutletWalls { axis: 2 })
        .perturbed(perturb, 11)
        .build()
        .unwrap_or_else(|e| {
            eprintln!("error: {e}");
            std::process::exit(1)
        });
    scg_mesh::foam::write_case(&a[1], &mesh, None, scg_mesh::foam::Format::Ascii).unwrap_or_else(
        |e| {
            eprintln!("error: {e}");
            std::process::exit(1)
        },
    );
    if let Some((n, dt)) = series {
        write_series(&a[1], &mesh, w, n, dt);
    }
    println!(
        "{}: {} cells, {} faces, {} points",
        a[1],
        mesh.n_cells,
        mesh.n_faces(),
        mesh.points.len()
    );
}

/// The `--series` snapshots (see the module documentation).
fn write_series(dir: &str, mesh: &scg_mesh::PolyMesh, w: f64, n: usize, dt: f64) {
    let fail = |e: scg_mesh::MeshError| -> ! {
        eprintln!("error: {e}");
        std::process::exit(1)
    };
    let geom = scg_mesh::MeshGeometry::new(mesh).unwrap_or_else(|e| fail(e));
    let period = n as f64 * dt;
    for k in 0..n {
        let t = k as f64 * dt;
        let omega = 31.4 * (1.0 + 0.5 * (std::f64::consts::TAU * t / period).sin());
        let u = |c: DVec3| {
            let r2 = (c.x * c.x + c.y * c.y) / (w * w);
            DVec3::new(-omega * c.y, omega * c.x, 0.01 * (1.0 - r2))
        };
        let field = scg_mesh::CellField {
            cells: geom.cell_centres.iter().map(|&c| u(c)).collect(),
            patches: vec![None; mesh.patches.len()],
        };
        let time = format!("{t}");
        scg_mesh::foam::write_vector_field(
            dir,
            &time,
            "U",
            mesh,
            &field,
            scg_mesh::foam::Format::Binary,
        )
        .unwrap_or_else(|e| fail(e));
    }
}
