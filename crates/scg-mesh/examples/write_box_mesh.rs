//! Write a box mesh of scg's generators (`scg_mesh::build`) as an OpenFOAM case, for
//! `bench/vs-openfoam.sh --mesh tet|poly` (blockMesh makes only hexahedra).
//!
//! ```sh
//! cargo run --release -p scg-mesh --example write_box_mesh -- DIR SHAPE NX NY NZ W H [PERTURB]
//! ```
//!
//! SHAPE is `hex`, `tet` (6 per hexahedron) or `poly` (a quarter of the hexahedra refined,
//! hanging nodes); NX × NY × NZ hexahedra over x, y in [−W, W] and z in [0, H] (m); the
//! interior points moved by up to PERTURB (default 0) of the spacing. Patches `inlet`
//! (z = 0, type patch), `outlet` (z = H, type patch) and `walls` (the sides, type wall).
//! Writes DIR/constant/polyMesh (ASCII) and a minimal DIR/system; no field.

use glam::DVec3;
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 8 {
        eprintln!("usage: write_box_mesh DIR hex|tet|poly NX NY NZ W H [PERTURB]");
        std::process::exit(2);
    }
    let num = |i: usize| -> f64 {
        a[i].parse().unwrap_or_else(|_| {
            eprintln!("not a number: {}", a[i]);
            std::process::exit(2)
        })
    };
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
    println!(
        "{}: {} cells, {} faces, {} points",
        a[1],
        mesh.n_cells,
        mesh.n_faces(),
        mesh.points.len()
    );
}
