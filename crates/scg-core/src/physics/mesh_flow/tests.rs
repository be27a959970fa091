//! Tests of [`super`] (mesh_flow).
use super::*;
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
use scg_mesh::{Location, MeshGeometry};

fn box_flow(u: DVec3, roles: &[(&str, PatchRole)]) -> MeshFlow {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [4, 4, 4])
        .shape(CellShape::Tet)
        .naming(PatchNaming::InletOutletWalls { axis: 0 })
        .build()
        .unwrap();
    let field = CellField {
        cells: vec![u; m.n_cells],
        patches: vec![None; m.patches.len()],
    };
    let r = m
        .patches
        .iter()
        .map(|p| {
            roles
                .iter()
                .find(|(n, _)| *n == p.name)
                .map_or(PatchRole::Lost, |r| r.1)
        })
        .collect();
    MeshFlow::new(m, &field, Interpolation::CellPoint, r).unwrap()
}

/// A dropped flow frees its mesh, geometry, locator and table (nothing leaked): the
/// mesh's and the geometry's last `Arc`s are the flow's.
#[test]
fn dropping_a_flow_frees_its_mesh() {
    let mut weak = Vec::new();
    for _ in 0..20 {
        let f = box_flow(DVec3::X, &[]);
        let loc = f.locator();
        assert!(f.table().is_some_and(|t| t.bytes() > 0));
        weak.push((
            std::sync::Arc::downgrade(loc.mesh_arc().unwrap()),
            std::sync::Arc::downgrade(loc.geometry_arc().unwrap()),
        ));
        drop(f);
    }
    for (m, g) in &weak {
        assert!(m.upgrade().is_none() && g.upgrade().is_none());
    }
}

/// `MeshFlow::velocity` gives, bit for bit, what walking with the locator from the
/// hint gives (the way it was computed before it asked `find` directly when the table
/// meets a boundary), on a perturbed box with a hole: points inside, beyond the hole's
/// walls inside the mesh (a concave boundary: found elsewhere) and outside.
#[test]
fn velocity_at_a_boundary_equals_the_locators_walk() {
    use rand::{Rng, SeedableRng};
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [6, 6, 6])
        .shape(CellShape::Hex)
        .perturbed(0.15, 3)
        .with_hole(DVec3::splat(0.3), DVec3::splat(0.7))
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let field = CellField::at_cell_centres(&m, &g, |c| {
        DVec3::new(c.y * c.z, (3.0 * c.x).sin(), c.x * c.x)
    });
    let roles = vec![PatchRole::Wall; m.patches.len()];
    let flow = MeshFlow::new(m, &field, Interpolation::CellPoint, roles).unwrap();
    let reference = |hint: u32, x: DVec3| -> (DVec3, u32) {
        if let TableWalk::Inside { cell, value } = flow.walk_table(hint, x) {
            return (value, cell);
        }
        match flow.loc.track(hint, x) {
            Location::Inside(h) | Location::Crossed { hit: h, .. } => {
                let u = flow
                    .velocity_in(h.cell, x)
                    .unwrap_or_else(|| flow.interp.at(&h));
                (u, h.cell)
            }
            Location::Left { .. } | Location::Outside => (flow.interp.velocity(hint, x), hint),
        }
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let n_cells = flow.mesh().n_cells as u32;
    let (mut crossed, mut left) = (0, 0);
    for _ in 0..20_000 {
        let hint = rng.random_range(0..n_cells);
        let c = flow.geometry().cell_centres[hint as usize];
        let x = c + (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 0.6;
        let got = flow.velocity(hint, x);
        let want = reference(hint, x);
        let bits = |(u, c): (DVec3, u32)| (u.to_array().map(f64::to_bits), c);
        assert_eq!(bits(got), bits(want), "hint {hint}, x {x}");
        if let TableWalk::Boundary { .. } = flow.walk_table(hint, x) {
            match flow.loc.find(x) {
                Some(_) => crossed += 1,
                None => left += 1,
            }
        }
    }
    println!("beyond a boundary: {crossed} inside the mesh elsewhere, {left} outside");
    assert!(crossed > 50 && left > 50, "{crossed} / {left}");
}

fn models(f: &MeshFlow, e: f64) -> Vec<PatchInteraction> {
    f.roles()
        .iter()
        .map(|r| match r {
            PatchRole::Wall => PatchInteraction::Rebound { e, mu: 0.0 },
            _ => PatchInteraction::Escape,
        })
        .collect()
}

fn patch(f: &MeshFlow, name: &str) -> u32 {
    f.mesh()
        .patches
        .iter()
        .position(|p| p.name == name)
        .unwrap() as u32
}

#[test]
fn landing_by_role() {
    let u = DVec3::new(0.3, -0.2, 0.1);
    let f = box_flow(
        u,
        &[("walls", PatchRole::Wall), ("outlet", PatchRole::Outlet)],
    );
    let x0 = DVec3::splat(0.5);
    let h0 = f.find_cell(x0).unwrap();
    let (w, h) = f.velocity(h0, DVec3::new(0.6, 0.55, 0.45));
    assert!((w - u).length() < 1e-14);
    assert!((h as usize) < f.mesh().n_cells);
    let m1 = models(&f, 1.0);
    // through the outlet (x max)
    let l = land(&f, x0, h0, h0, DVec3::new(1.2, 0.5, 0.5), DVec3::X, &m1);
    assert_eq!(
        hint::departure(l.hint),
        Some(hint::Departure::Escaped(patch(&f, "outlet")))
    );
    // through the inlet (escapes there)
    let l = land(&f, x0, h0, h0, DVec3::new(-0.2, 0.5, 0.5), -DVec3::X, &m1);
    assert_eq!(
        hint::departure(l.hint),
        Some(hint::Departure::Escaped(patch(&f, "inlet")))
    );
    // a stick wall keeps it
    let mut ms = m1.clone();
    ms[patch(&f, "walls") as usize] = PatchInteraction::Stick;
    let l = land(&f, x0, h0, h0, DVec3::new(0.5, 1.25, 0.5), DVec3::Y, &ms);
    assert_eq!(
        hint::departure(l.hint),
        Some(hint::Departure::Stuck(patch(&f, "walls")))
    );
    // into the y max wall: mirrored back, v_y reversed × e
    let l = land(
        &f,
        x0,
        h0,
        h0,
        DVec3::new(0.5, 1.25, 0.5),
        DVec3::new(0.0, 2.0, 1.0),
        &models(&f, 0.5),
    );
    assert!((l.x - DVec3::new(0.5, 0.75, 0.5)).length() < 1e-12);
    assert!((l.v - DVec3::new(0.0, -1.0, 1.0)).length() < 1e-12);
    // the hint is a cell holding the point (on a shared face either side will do)
    assert!(matches!(f.track(l.hint, l.x), Location::Inside(h) if h.cell == l.hint));
    // a corner: two reflections
    let l = land(
        &f,
        x0,
        h0,
        h0,
        DVec3::new(0.5, 1.2, -0.1),
        DVec3::new(0.0, 1.0, -1.0),
        &m1,
    );
    assert!((l.x - DVec3::new(0.5, 0.8, 0.1)).length() < 1e-12, "{l:?}");
    assert!((l.v - DVec3::new(0.0, -1.0, 1.0)).length() < 1e-12);
    // roles must match the patches
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [1, 1, 1])
        .build()
        .unwrap();
    let field = CellField {
        cells: vec![u; 1],
        patches: vec![None; m.patches.len()],
    };
    assert!(MeshFlow::new(m, &field, Interpolation::CellValue, vec![]).is_err());
}
