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
        if let TableWalk::Inside { cell, value, .. } = flow.walk_table(hint, x) {
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
            PatchRole::Wall => PatchInteraction::frictionless(e),
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
    // a step from x0 (in cell h0, its mid-step point too) to x1 at v1
    let step = |x1: DVec3, v1: DVec3, models: &[PatchInteraction]| {
        land(&f, x0, h0, Place::cell(h0), x1, v1, models)
    };
    // through the outlet (x max)
    let l = step(DVec3::new(1.2, 0.5, 0.5), DVec3::X, &m1);
    assert_eq!(
        hint::departure(l.hint),
        Some(hint::Departure::Escaped(patch(&f, "outlet")))
    );
    // through the inlet (escapes there)
    let l = step(DVec3::new(-0.2, 0.5, 0.5), -DVec3::X, &m1);
    assert_eq!(
        hint::departure(l.hint),
        Some(hint::Departure::Escaped(patch(&f, "inlet")))
    );
    // a stick wall keeps it
    let mut ms = m1.clone();
    ms[patch(&f, "walls") as usize] = PatchInteraction::Stick;
    let l = step(DVec3::new(0.5, 1.25, 0.5), DVec3::Y, &ms);
    assert_eq!(
        hint::departure(l.hint),
        Some(hint::Departure::Stuck(patch(&f, "walls")))
    );
    // into the y max wall: v_y reversed × e, and the rest of the step after the impact
    // (0.25 / 2 = 0.125 s) moved on it: e·0.25 = 0.125 inside the wall's plane
    let l = step(
        DVec3::new(0.5, 1.25, 0.5),
        DVec3::new(0.0, 2.0, 1.0),
        &models(&f, 0.5),
    );
    assert!(
        (l.x - DVec3::new(0.5, 0.875, 0.5)).length() < 1e-12,
        "{}",
        l.x
    );
    assert!((l.v - DVec3::new(0.0, -1.0, 1.0)).length() < 1e-12);
    // the hint is a cell holding the point (on a shared face either side will do)
    assert!(matches!(f.track(l.hint, l.x), Location::Inside(h) if h.cell == l.hint));
    // a corner: two reflections
    let l = step(DVec3::new(0.5, 1.2, -0.1), DVec3::new(0.0, 1.0, -1.0), &m1);
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

/// A wall face moving at V (a frozen rotor's blade): the particle leaves it with the
/// normal velocity relative to the surface −e·(v − V)·n exactly and, without friction, its
/// tangential velocity kept; the impact is recorded relative to the surface; faces that do
/// not move rebound as before.
#[test]
fn a_moving_wall_face_rebounds_relative_to_its_surface() {
    let u = DVec3::ZERO;
    let mut f = box_flow(u, &[("walls", PatchRole::Wall)]);
    let m = f.mesh();
    let wp = &m.patches[patch(&f, "walls") as usize];
    // the faces of the y max side of `walls`, turning about the x axis through the box's
    // centre at 3 rad/s: their surface moves along ±z
    let spin = Spin {
        omega: DVec3::new(3.0, 0.0, 0.0),
        origin: DVec3::splat(0.5),
    };
    let g = f.geometry();
    let top: Vec<(u32, usize)> = (wp.start..wp.start + wp.size)
        .filter(|&k| (g.face_centres[k].y - 1.0).abs() < 1e-12)
        .map(|k| (k as u32, 0))
        .collect();
    assert!(!top.is_empty());
    let ni = m.n_internal_faces();
    let nb = m.n_faces() - ni;
    f.set_moving_faces(MovingFaces::new(ni, nb, vec![spin], &top).unwrap());
    let x0 = DVec3::splat(0.5);
    let h0 = f.find_cell(x0).unwrap();
    let (e, v) = (0.5, DVec3::new(0.3, 2.0, 1.0));
    let l = land(
        &f,
        x0,
        h0,
        Place::cell(h0),
        DVec3::new(0.5, 1.25, 0.5),
        v,
        &models(&f, e),
    );
    let hit = DVec3::new(0.5, 1.0, 0.5);
    let w = spin.velocity(hit);
    assert!((w - DVec3::new(0.0, 0.0, 1.5)).length() < 1e-12, "{w}");
    let rel = l.v - w;
    assert!((rel.y - (-e * (v - w).y)).abs() < 1e-12, "{l:?}");
    assert!((rel.x - (v - w).x).abs() < 1e-12 && (rel.z - (v - w).z).abs() < 1e-12);
    let imp = l.impact.unwrap();
    assert!((imp.velocity - (v - w)).length() < 1e-12);
    // a face at rest (the y min side): the plain rebound
    let l = land(
        &f,
        x0,
        h0,
        Place::cell(h0),
        DVec3::new(0.5, -0.25, 0.5),
        -v,
        &models(&f, e),
    );
    assert!(
        (l.v - DVec3::new(-0.3, 1.0, -1.0)).length() < 1e-12,
        "{l:?}"
    );
    assert_eq!(f.surface_velocity(0, hit), None);
}

/// A channel whose first cell layer (y_c = 15 mm, y⁺_c = 500 at u_τ = 0.5 m/s, ν =
/// 1.5e-5 m²/s) and the layers above carry the log law at their centres: with the wall
/// function, the velocity at y⁺ = 30 and 100 inside the first cell is the log law's within
/// 2 % anywhere in the cell (u_τ from the cell's velocity, or from k = u_τ²/√C_μ);
/// without it, the
/// interpolation to the no-slip wall gives a slow layer (far below the log law).
#[test]
fn wall_function_follows_the_log_law_in_the_first_cell() {
    use crate::physics::wall_function::{FrictionVelocity, LogLaw};
    let (nu, u_tau) = (1.5e-5, 0.5);
    let law = LogLaw::default();
    let lam = law.y_plus_lam();
    let m = BoxMesh::new(DVec3::ZERO, DVec3::new(0.12, 0.3, 0.12), [4, 10, 4])
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let log = |y: f64| u_tau * law.u_plus(y * u_tau / nu, lam);
    let cells: Vec<DVec3> = g
        .cell_centres
        .iter()
        .map(|c| DVec3::new(log(c.y), 0.0, 0.0))
        .collect();
    // no-slip on `ymin` (zero face values), the other patches carry the owner's value
    let patches = m
        .patches
        .iter()
        .map(|p| {
            Some(
                (p.start..p.start + p.size)
                    .map(|f| {
                        if p.name == "ymin" {
                            DVec3::ZERO
                        } else {
                            cells[m.owner[f] as usize]
                        }
                    })
                    .collect(),
            )
        })
        .collect();
    let field = CellField { cells, patches };
    let roles: Vec<PatchRole> = m
        .patches
        .iter()
        .map(|p| {
            if p.name == "ymin" {
                PatchRole::Wall
            } else {
                PatchRole::Lost
            }
        })
        .collect();
    let k = vec![u_tau * u_tau / law.c_mu.sqrt(); m.n_cells];
    let with = |friction| {
        let spec = WallFunctionSpec { law, nu, friction };
        MeshFlow::with_wall_function(
            m.clone(),
            &field,
            Interpolation::CellPoint,
            roles.clone(),
            Some(&spec),
        )
        .unwrap()
    };
    let plain = MeshFlow::new(m.clone(), &field, Interpolation::CellPoint, roles.clone()).unwrap();
    for flow in [
        with(FrictionVelocity::FromVelocity),
        with(FrictionVelocity::FromK(k)),
    ] {
        let (n_cells, n_faces) = flow.wall_cells().unwrap().counts();
        assert_eq!((n_cells, n_faces), (16, 16));
        for y_plus in [30.0, 100.0] {
            let y = y_plus * nu / u_tau;
            let want = log(y);
            // on the centre line of a first-layer cell, and off it
            for (x, z) in [(0.045, 0.045), (0.035, 0.05), (0.031, 0.059)] {
                let p = DVec3::new(x, y, z);
                let c = flow.find_cell(p).unwrap();
                let (u, _) = flow.velocity(c, p);
                let err = (u.x - want).abs() / want;
                println!(
                    "y+ = {y_plus}, (x, z) = ({x}, {z}): {:.4} m/s, log law {want:.4}, {:+.2} %",
                    u.x,
                    100.0 * (u.x - want) / want
                );
                assert!(err < 0.02, "y+ = {y_plus} at ({x}, {z}): {} vs {want}", u.x);
                assert!(u.y.abs() < 1e-9 && u.z.abs() < 1e-9, "{u}");
                // the walk and the landing see the same value
                assert_eq!(
                    flow.velocity_walk(c, p).0.x.to_bits() >> 8,
                    u.x.to_bits() >> 8
                );
            }
            let p = DVec3::new(0.045, y, 0.045);
            let (u0, _) = plain.velocity(plain.find_cell(p).unwrap(), p);
            assert!(u0.x < 0.5 * want, "no wall function: {} vs {want}", u0.x);
        }
        // at the wall zero, beyond the first centre unchanged
        let p = DVec3::new(0.045, 1e-12, 0.045);
        assert!(flow.velocity(flow.find_cell(p).unwrap(), p).0.x < 1e-6);
    }
}

/// The cell gradient (Gauss, face-centre values) is exact for an affine field in the
/// cells away from the boundary (whose zero-gradient patch values are not the field's),
/// on a perturbed hex box; with `cell_value` the distance-weighted face values are exact
/// only on the regular box, and the gradient is still the field's there.
#[test]
fn cell_gradient_of_an_affine_field() {
    let a = glam::DMat3::from_cols(
        DVec3::new(1.0, -2.0, 0.5),
        DVec3::new(3.0, 0.25, -1.0),
        DVec3::new(-0.5, 2.0, 1.5),
    );
    let b = DVec3::new(0.3, -0.2, 0.1);
    for (perturb, scheme) in [
        (0.15, Interpolation::CellPointLinearExact),
        (0.0, Interpolation::CellValue),
    ] {
        let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [6, 6, 6])
            .shape(CellShape::Hex)
            .perturbed(perturb, 5)
            .build()
            .unwrap();
        let g = MeshGeometry::new(&m).unwrap();
        let field = CellField::at_cell_centres(&m, &g, |x| a * x + b);
        // cells none of whose points is on the boundary
        let inner: Vec<usize> = (0..m.n_cells)
            .filter(|&c| {
                let [lo, hi] = g.cell_bounds[c];
                lo.min_element() > 0.05 && hi.max_element() < 0.95
            })
            .collect();
        assert!(!inner.is_empty());
        let roles = vec![PatchRole::Lost; field.patches.len()];
        let flow = MeshFlow::new(m, &field, scheme, roles).unwrap();
        for c in inner {
            let j = flow.cell_gradient(c as u32);
            let err = (j - a)
                .to_cols_array()
                .iter()
                .map(|v| v.abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-10, "{scheme:?} cell {c}: {j} vs {a}");
        }
    }
}
