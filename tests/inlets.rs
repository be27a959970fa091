//! Inlets on mesh flows (`[flow.patches] inlets`, `[[feeders]] patch`): where fed particles
//! start, how many, how uniformly, with which velocity; conservation of particles through
//! a box with an inlet and an outlet; restart and thread bit-identity; bad input.
//!
//! Run: `cargo test --release --test inlets -- --nocapture` (prints the measured numbers).

mod common;

use std::collections::HashSet;
use std::path::Path;
use std::process::Command;

use glam::DVec3;
use scg::core::stages::feeder::fed_by;
use scg::core::stages::outlet::OutletLog;
use scg::core::state::Tally;
use scg::scene::Scene;
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
use scg_mesh::foam::{Format, write_case};
use scg_mesh::{CellField, MeshGeometry, PolyMesh};

/// Box edge, m.
const L: f64 = 0.01;
/// The inlet (x = 0) is split at y = Y_SPLIT into two quads of areas 0.3 L² and 0.7 L².
const Y_SPLIT: f64 = 0.3 * L;

/// [0, L]³ of 6 × 2 × 1 hexahedra, the middle y layer moved to y = 0.3 L; patches
/// `inlet` (x = 0), `outlet` (x = L), `walls`. The walls move with the affine field the
/// tests sample on them, so the mesh gives them type `patch` (the scene still makes them
/// walls): at a no-slip `wall` meeting the inlet, cell-point bounds the point values
/// (crates/scg-mesh/src/interp.rs), and the affine field would not be reproduced there.
fn split_box() -> PolyMesh {
    let mut m = BoxMesh::new(DVec3::ZERO, DVec3::splat(L), [6, 2, 1])
        .shape(CellShape::Hex)
        .naming(PatchNaming::InletOutletWalls { axis: 0 })
        .build()
        .unwrap();
    for p in &mut m.patches {
        p.kind = "patch".into();
    }
    for p in &mut m.points {
        if (p.y - 0.5 * L).abs() < 1e-12 * L {
            p.y = Y_SPLIT;
        }
    }
    m
}

/// `u` at the cell centres and at the boundary face centres (so that
/// `cell_point_linear_exact` reproduces an affine `u` everywhere).
fn sample(mesh: &PolyMesh, u: impl Fn(DVec3) -> DVec3) -> CellField {
    let g = MeshGeometry::new(mesh).unwrap();
    CellField {
        cells: g.cell_centres.iter().map(|&c| u(c)).collect(),
        patches: mesh
            .patches
            .iter()
            .map(|p| {
                Some(
                    (p.start..p.start + p.size)
                        .map(|f| u(g.face_centres[f]))
                        .collect(),
                )
            })
            .collect(),
    }
}

/// Feeder `a`: rate 1e5 /s, velocity from the field, α = 4 (scg). Feeder `b`: 3.3e4 /s
/// between 2 and 25 ms, released every 0.1 ms, velocity given. Group `c`: 50 heavy
/// particles next to the inlet shot back through it (lost through the inlet role).
const FEEDERS: &str = r#"
[[groups]]
name = "a"
diameter = 10e-6
density = 1000.0
alpha = 4.0
[[groups]]
name = "b"
diameter = 20e-6
density = 2500.0
law = "none"
[[groups]]
name = "c"
diameter = 1e-3
density = 1000.0
count = 50
region = { kind = "box", min = [0.0006, 0.001, 0.001], max = [0.0008, 0.009, 0.009] }
velocity = [-5.0, 0.0, 0.0]
[[feeders]]
group = "a"
rate = 1.0e5
patch = "inlet"
velocity = "field"
[[feeders]]
group = "b"
rate = 3.3e4
patch = "inlet"
velocity = [0.5, 0.0, 0.0]
start = 0.002
stop = 0.025
interval = 1.0e-4
"#;

fn scene_text(duration: f64) -> String {
    format!(
        r#"duration = {duration:e}
dt = 1.0e-5
seed = 11
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "openfoam"
case = "case"
interpolation = "cell_point_linear_exact"
[flow.patches]
walls = ["walls"]
outlets = ["outlet"]
inlets = ["inlet"]
[drag]
law = "stokes"
{FEEDERS}"#
    )
}

/// Write the case with field `u` and load the scene.
fn setup(dir: &Path, u: impl Fn(DVec3) -> DVec3, duration: f64) -> Scene {
    let mesh = split_box();
    let field = sample(&mesh, u);
    write_case(dir.join("case"), &mesh, Some(("U", &field)), Format::Binary).unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene_text(duration)).unwrap();
    scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// A sheared field along +x: u = (1 + 50·y, 0, 0) m/s (affine, so interpolated exactly).
fn shear(x: DVec3) -> DVec3 {
    DVec3::new(1.0 + 50.0 * x.y, 0.0, 0.0)
}

#[test]
fn fed_particles_start_on_the_patch_radius_inward_with_exact_counts_and_field_velocity() {
    let dir = tempfile::tempdir().unwrap();
    let scene = setup(dir.path(), shear, 0.03);
    let flow = scene.mesh_flow.as_ref().unwrap().flow.clone();
    let mut sim = scene.build(false);
    let mut seen: HashSet<u32> = sim.particles().iter().map(|p| p.id).collect();
    assert_eq!(seen.len(), 50);
    let every = 10; // interval 1e-4 s / dt
    let (mut n_fed, mut low, mut worst_r, mut worst_u) = ([0usize; 2], [0usize; 2], 0.0, 0.0);
    for k in 1..=scene.steps() {
        sim.step().unwrap();
        let t = sim.time();
        let tally = sim.world.resource::<Tally>().clone();
        // (2) exact counts: feeder a every step, feeder b at each release
        assert_eq!(tally.fed[0], fed_by(1.0e5, 0.0, f64::MAX, t), "step {k}");
        if k % every == 0 {
            assert_eq!(tally.fed[1], fed_by(3.3e4, 0.002, 0.025, t), "step {k}");
        }
        for p in sim.particles() {
            if !seen.insert(p.id) {
                continue;
            }
            let g = p.group as usize;
            assert!(g < 2, "{p:?}");
            n_fed[g] += 1;
            // (1) on the inlet (x = 0), one simulated radius inward, inside the mesh
            let r = 0.5 * p.diameter;
            let dr = (p.position.x - r).abs() / r;
            worst_r = f64::max(worst_r, dr);
            assert!(dr <= 1e-12, "{p:?}");
            assert!(
                (0.0..=L).contains(&p.position.y) && (0.0..=L).contains(&p.position.z),
                "{p:?}"
            );
            let cell = flow.find_cell(p.position).expect("inside the mesh");
            low[g] += usize::from(p.position.y < Y_SPLIT);
            if g == 0 {
                assert_eq!(r, 20e-6); // α = 4 under scg: 40 µm
                // (4) the interpolated field at the spawn point (and the affine field)
                let (u, _) = flow.velocity(cell, p.position);
                let du = (p.velocity - u).length() / u.length();
                worst_u = f64::max(worst_u, du);
                assert!(du <= 1e-12, "{p:?} vs {u}");
                // every cell of this 6 × 2 × 1 box touches the box's edges, where the point
                // values are a convex combination rather than the affine fit (no overshoot):
                // the value lies within the field's range, not on the affine field
                let (lo, hi) = (shear(DVec3::ZERO), shear(DVec3::splat(L)));
                assert!(
                    p.velocity.cmpge(lo - 1e-12).all() && p.velocity.cmple(hi + 1e-12).all(),
                    "{p:?}"
                );
            } else {
                assert_eq!(p.velocity, DVec3::new(0.5, 0.0, 0.0));
                assert_eq!(r, 10e-6);
            }
        }
    }
    let tally = sim.world.resource::<Tally>().clone();
    println!(
        "fed {n_fed:?} (tally {:?}), below y = 0.3 L: {low:?}, worst |x − r|/r = {worst_r:.2e}, worst |v − u|/|u| = {worst_u:.2e}",
        tally.fed
    );
    let t = sim.time();
    let due = [
        fed_by(1.0e5, 0.0, f64::MAX, t),
        fed_by(3.3e4, 0.002, 0.025, t),
    ];
    assert_eq!(due, [3000, 759]); // ⌊1e5 · 0.03⌋, ⌊3.3e4 · 0.023⌋
    assert_eq!([n_fed[0] as u64, n_fed[1] as u64], due);
    assert_eq!(tally.fed[..2], due);
    // (3) the 0.3 L² face gets 30 % of the particles within 4 binomial σ
    for g in 0..2 {
        let n = n_fed[g] as f64;
        let sigma = (n * 0.3 * 0.7).sqrt();
        let dev = (low[g] as f64 - 0.3 * n).abs();
        println!(
            "group {g}: {} of {n} on the small face, |dev| = {:.2} σ",
            low[g],
            dev / sigma
        );
        assert!(dev < 4.0 * sigma, "group {g}: {} of {n}", low[g]);
    }
}

/// The scene's first feeder alone at 10^8 /s for 100 steps of 10 µs (10^5 particles),
/// by area or by flux: the particles of group `a`.
fn feed_10e5(mut scene: Scene, by_flux: bool) -> Vec<scg::core::sim::ParticleState> {
    scene.feeders.truncate(1);
    scene.feeders[0].rate = 1.0e8;
    scene.feeders[0].by_flux = by_flux;
    let mut sim = scene.build(false);
    sim.run(100, |_| true).unwrap();
    sim.particles()
        .into_iter()
        .filter(|p| p.group == 0)
        .collect()
}

#[test]
fn spatial_share_matches_area_ratio_over_many_particles() {
    // (3) with 10^5 particles: the share on the 0.3 L² face within 4σ = 4·√(N·0.3·0.7).
    let dir = tempfile::tempdir().unwrap();
    let scene = setup(dir.path(), |_| DVec3::X, 0.0011);
    let ps = feed_10e5(scene, false);
    let n = ps.len() as f64;
    let low = ps.iter().filter(|p| p.position.y < Y_SPLIT).count() as f64;
    let sigma = (n * 0.3 * 0.7).sqrt();
    println!(
        "{n} fed: {low} on the small face, expected {:.1}, |dev| = {:.2} σ",
        0.3 * n,
        (low - 0.3 * n).abs() / sigma
    );
    assert!(n >= 99_000.0);
    assert!((low - 0.3 * n).abs() < 4.0 * sigma);
    // and within each face uniform in z: each half holds half within 4σ
    let zlow = ps.iter().filter(|p| p.position.z < 0.5 * L).count() as f64;
    assert!(
        (zlow - 0.5 * n).abs() < 4.0 * (n * 0.25).sqrt(),
        "{zlow} of {n}"
    );
}

/// `weight = "flux"`: with 1 m/s through the inlet's lower face (y < 0.3 L, area 0.3 L²)
/// and 2 m/s through its upper one (cell values), the positions follow u·n, not the
/// area: the share on the lower face is 0.3·1 / (0.3·1 + 0.7·2) = 0.176 (by area: 0.3),
/// within 4σ of 10^5; within each face they stay uniform by area.
#[test]
fn flux_weighted_feed_follows_the_inflow() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = split_box();
    let step = |x: DVec3| DVec3::new(if x.y < Y_SPLIT { 1.0 } else { 2.0 }, 0.0, 0.0);
    let field = sample(&mesh, step);
    write_case(
        dir.path().join("case"),
        &mesh,
        Some(("U", &field)),
        Format::Binary,
    )
    .unwrap();
    let text = scene_text(0.0011).replace("cell_point_linear_exact", "cell_value");
    std::fs::write(dir.path().join("scene.toml"), &text).unwrap();
    let scene = scg::scene::load(&dir.path().join("scene.toml"), &[]).unwrap();
    let ps = feed_10e5(scene, true);
    let n = ps.len() as f64;
    let share = ps.iter().filter(|p| p.position.y < Y_SPLIT).count() as f64 / n;
    let expected = 0.3 / (0.3 + 0.7 * 2.0);
    let sigma = (expected * (1.0 - expected) / n).sqrt();
    println!("flux-weighted: {share:.4} below the split, expected {expected:.4} (σ {sigma:.1e})");
    assert!(n >= 99_000.0);
    assert!(
        (share - expected).abs() < 4.0 * sigma,
        "{share} vs {expected}"
    );
    let upper: Vec<f64> = ps
        .iter()
        .filter(|p| p.position.y >= Y_SPLIT)
        .map(|p| p.position.y)
        .collect();
    let mid = 0.5 * (Y_SPLIT + L);
    let below = upper.iter().filter(|y| **y < mid).count() as f64;
    let m = upper.len() as f64;
    assert!(
        (below - 0.5 * m).abs() < 4.0 * (0.25 * m).sqrt(),
        "{below} of {m}"
    );
    // the bad word names the key
    let text = scene_text(0.001).replace(
        "velocity = \"field\"",
        "velocity = \"field\"\nweight = \"mass\"",
    );
    std::fs::write(dir.path().join("bad.toml"), &text).unwrap();
    let e = scg::scene::load(&dir.path().join("bad.toml"), &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("feeders[0].weight") && e.contains("\"mass\""),
        "{e}"
    );
    // a region feeder has no flux to weight by
    let e = scg::scene::parse(
        "duration = 0.1\ndt = 1e-3\n[[groups]]\nname = \"a\"\ndiameter = 1e-5\ndensity = 1000.0\n\
         [[feeders]]\ngroup = \"a\"\nrate = 10.0\nweight = \"flux\"\n\
         region = { kind = \"box\", min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }\n",
        "s.toml",
        "s",
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("feeders[0].weight") && e.contains("patch"),
        "{e}"
    );
}

#[test]
fn box_with_inlet_and_outlet_conserves_particles_and_loses_none_fed() {
    // (5) uniform u = (1, 0, 0) m/s: fed particles cross the 10 mm box in ≈ 10 ms and
    // drain; nothing fed touches a wall or is lost; group c goes back out through the
    // inlet (role `inlet`) and is lost, all 50.
    let dir = tempfile::tempdir().unwrap();
    let scene = setup(dir.path(), |_| DVec3::X, 0.03);
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    let ps = sim.particles();
    let tally = sim.world.resource::<Tally>().clone();
    let log = sim.world.resource::<OutletLog>().clone();
    let lost: Vec<u64> = log.lost.iter().map(|l| l.len() as u64).collect();
    let resident: Vec<u64> = (0..3)
        .map(|g| ps.iter().filter(|p| p.group == g).count() as u64)
        .collect();
    println!(
        "inlet/outlet box: fed {:?}, resident {resident:?}, drained {:?}, lost {lost:?}",
        tally.fed, tally.drained
    );
    let initial = [0u64, 0, 50];
    for g in 0..3 {
        assert_eq!(
            initial[g] + tally.fed[g],
            resident[g] + tally.drained[g] + lost[g],
            "group {g}"
        );
    }
    assert_eq!((lost[0], lost[1]), (0, 0));
    assert_eq!((lost[2], tally.drained[2], resident[2]), (50, 0, 0));
    assert!(
        tally.drained[0] > 1500 && tally.drained[1] > 300,
        "{tally:?}"
    );
    // every resident particle stayed on its line (y, z) and moves along +x
    assert!(
        ps.iter()
            .all(|p| p.velocity.y == 0.0 && p.velocity.z == 0.0)
    );
}

#[test]
fn inlet_restart_is_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let scene = setup(dir.path(), shear, 0.004);
    let total = scene.steps();
    let mut straight = scene.build(false);
    straight.run(total, |_| true).unwrap();
    let end = straight.checkpoint();
    assert!(end.particles.len() > 300);
    for cut in [total / 2 + 3, 205] {
        let mut first = scene.build(false);
        first.run(cut, |_| true).unwrap();
        let half = first.checkpoint();
        let mut second = scene.build(false);
        second.restore(&half).unwrap();
        second.run(total - half.step, |_| true).unwrap();
        assert!(
            second.checkpoint() == end,
            "inlet restart at step {cut} diverged"
        );
    }
}

/// A digest of the inlet run's final state (ids, positions, velocities) and the count.
fn inlet_digest() -> String {
    let dir = tempfile::tempdir().unwrap();
    let scene = setup(dir.path(), shear, 0.006);
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    let mut h: u64 = 0xcbf29ce484222325;
    for p in sim.particles() {
        h = (h ^ u64::from(p.id)).wrapping_mul(0x100000001b3);
        for b in [p.position, p.velocity].iter().flat_map(|v| v.to_array()) {
            h = (h ^ b.to_bits()).wrapping_mul(0x100000001b3);
        }
    }
    format!("{h:016x} n={}", sim.particles().len())
}

/// One thread, two threads with every pass split, and two with the portable kernels: the
/// same bits.
#[test]
fn inlet_same_bits_on_one_and_two_threads() {
    let a = common::digest_with(1, 100_000_000, false, inlet_digest);
    let b = common::digest_with(2, 1, false, inlet_digest);
    let c = common::digest_with(2, 1, true, inlet_digest);
    println!("{a} (1 thread), {b} (2 threads, every pass split), {c} (portable)");
    assert_eq!(a, b);
    assert_eq!(a, c);
}

fn check(dir: &Path, text: &str) -> (i32, String, String) {
    let path = dir.join("bad.toml");
    std::fs::write(&path, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .arg("check")
        .arg(&path)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(!err.contains("panicked"), "panic: {err}");
    (out.status.code().unwrap_or(-1), stdout, err)
}

#[test]
fn scg_check_reports_inlets_and_rejects_bad_patch_feeders() {
    let dir = tempfile::tempdir().unwrap();
    let _ = setup(dir.path(), |_| DVec3::X, 0.01);
    let good = scene_text(0.01);
    let (code, out, err) = check(dir.path(), &good);
    println!("{out}");
    assert_eq!(code, 0, "{err}");
    // the inlet role; area L² = 1e-4 m², Q = 1 m/s · 1e-4 m² into the mesh
    assert!(
        out.contains("patch `inlet` (patch): 2 faces, inlet"),
        "{out}"
    );
    assert!(
        out.contains("feeders[0] on patch `inlet`: area 1.000000e-4 m², mean field velocity [1.000000e0, 0.000000e0, 0.000000e0] m/s, inflow Q = ∫u·n_in dA = 1.000000e-4 m³/s"),
        "{out}"
    );
    assert!(out.contains("velocity from the field"), "{out}");
    assert!(out.contains("feeders[1] on patch `inlet`"), "{out}");
    assert!(!out.contains("outside the flow mesh"), "{out}");
    let line_of =
        |text: &str, needle: &str| text.lines().position(|l| l.contains(needle)).unwrap() + 1;
    let analytic = good
        .replace(
            "kind = \"openfoam\"",
            "kind = \"uniform\"\nvelocity = [1.0, 0.0, 0.0]",
        )
        .replace("case = \"case\"\n", "")
        .replace("interpolation = \"cell_point_linear_exact\"\n", "")
        .replace(
            "[flow.patches]\nwalls = [\"walls\"]\noutlets = [\"outlet\"]\ninlets = [\"inlet\"]\n",
            "",
        );
    for (bad, key, needle, words) in [
        (
            good.replacen("patch = \"inlet\"", "patch = \"intel\"", 1),
            "feeders[0].patch",
            "patch = \"intel\"",
            "unknown patch `intel`",
        ),
        (
            analytic.clone(),
            "feeders[0].patch",
            "patch = \"inlet\"",
            "needs a flow on a mesh",
        ),
        (
            good.replacen(
                "patch = \"inlet\"",
                "patch = \"inlet\"\nregion = { kind = \"box\", min = [0.0, 0.0, 0.0], max = [0.001, 0.001, 0.001] }",
                1,
            ),
            "feeders[0].patch",
            "patch = \"inlet\"",
            "not both",
        ),
        (
            good.replacen("velocity = \"field\"", "velocity = \"fluid\"", 1),
            "feeders[0].velocity",
            "velocity = \"fluid\"",
            "\"field\"",
        ),
        (
            good.replace("inlets = [\"inlet\"]", "inlets = [\"inlet\", \"outlet\"]"),
            "flow.patches.inlets",
            "inlets = [",
            "two roles",
        ),
        (
            good.replace("inlets = [\"inlet\"]", "inlets = [\"in\"]"),
            "flow.patches.inlets",
            "inlets = [",
            "unknown patch `in`",
        ),
    ] {
        let (code, _, err) = check(dir.path(), &bad);
        println!("{err}");
        assert_eq!(code, 2, "{key}: {err}");
        let line = line_of(&bad, needle);
        assert!(
            err.contains(&format!("bad.toml:{line}: key `{key}`")) && err.contains(words),
            "{key} (line {line}): {err}"
        );
    }
    // `velocity = "field"` on a region feeder
    let region_field = analytic.replacen(
        "patch = \"inlet\"",
        "region = { kind = \"box\", min = [0.0, 0.0, 0.0], max = [0.001, 0.001, 0.001] }",
        2,
    );
    let (code, _, err) = check(dir.path(), &region_field);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("key `feeders[0].velocity`") && err.contains("goes with `patch`"),
        "{err}"
    );
}
