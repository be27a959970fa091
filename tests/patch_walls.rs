//! Wall patches of a CFD mesh as contact walls (`flow.patches.wall_model = "contact"`, the
//! default with `[material]`): a sphere thrown at or rolling over a flat wall patch of a
//! box mesh (hexahedra, tetrahedra, polyhedra with hanging nodes, written as an OpenFOAM
//! case) moves exactly as against the analytic `kind = "plane"` wall at the same place; a
//! box of wall patches with particle contacts keeps every particle, bit-identical on one
//! and two threads; `scg check` and `scg run --plan` say what the patches became.
//!
//! Run: `cargo test --release --test patch_walls -- --nocapture` (prints the deviations).

mod common;

use std::path::Path;
use std::process::Command;

use glam::DVec3;
use scg::core::components::{AngularVelocity, ParticleId, Position, Velocity, WallHistory};
use scg::core::stages::outlet::OutletLog;
use scg::core::state::ContactResolution;
use scg::core::step::StepSystem;
use scg::scene::Scene;
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
use scg_mesh::foam::{Format, write_case};
use scg_mesh::{CellField, PolyMesh};

/// Edge of the box, m.
const L: f64 = 0.01;
/// Particle diameter, m.
const D: f64 = 1.0e-3;

const SIDES: &str = r#"walls = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]"#;

const SHAPES: [CellShape; 3] = [
    CellShape::Hex,
    CellShape::Tet,
    CellShape::Poly { refine: 0.3 },
];

/// The box [0, L]³ of 8³ hexahedra shaped `shape`, one patch per side, still fluid,
/// written as an OpenFOAM case `case` in `dir`.
fn write_box(dir: &Path, shape: CellShape) -> PolyMesh {
    let mesh = BoxMesh::new(DVec3::ZERO, DVec3::splat(L), [8, 8, 8])
        .shape(shape)
        .naming(PatchNaming::Sides)
        .perturbed(0.0, 1)
        .build()
        .unwrap();
    let field = CellField {
        cells: vec![DVec3::ZERO; mesh.n_cells],
        patches: vec![None; mesh.patches.len()],
    };
    write_case(dir.join("case"), &mesh, Some(("U", &field)), Format::Binary).unwrap();
    mesh
}

fn v3(v: DVec3) -> String {
    format!("[{:e}, {:e}, {:e}]", v.x, v.y, v.z)
}

/// A scene of one 1 mm glass sphere at `x0` with `v0` under gravity and Stokes drag in
/// still air; `flow` is the `[flow]` body (and what follows it: planes). `friction` is
/// μ_s; `rolling` adds `[contacts]` with that rolling friction.
fn one_sphere(
    flow: &str,
    x0: DVec3,
    v0: DVec3,
    friction: f64,
    rolling: f64,
    dt: f64,
    t: f64,
) -> String {
    let contacts = if rolling > 0.0 {
        format!("[contacts]\nrolling_friction = {rolling:e}\n")
    } else {
        String::new()
    };
    format!(
        "duration = {t:e}\ndt = {dt:e}\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n[drag]\nlaw = \"stokes\"\n[gravity]\nacceleration = [0.0, 0.0, -9.81]\n[material]\nyoungs_modulus = 1e8\npoisson_ratio = 0.3\nrestitution = 0.8\nfriction = {friction:e}\n{contacts}[[groups]]\nname = \"p\"\ndiameter = {D:e}\ndensity = 2500.0\npositions = [{}]\nvelocities = [{}]\n[flow]\n{flow}\n",
        v3(x0),
        v3(v0)
    )
}

fn mesh_flow() -> String {
    format!("kind = \"openfoam\"\ncase = \"case\"\n[flow.patches]\n{SIDES}")
}

/// Still air and the analytic plane through `point` with inward `normal`.
fn plane_flow(point: DVec3, normal: DVec3) -> String {
    format!(
        "kind = \"still\"\n[[walls]]\nkind = \"plane\"\npoint = {}\nnormal = {}",
        v3(point),
        v3(normal)
    )
}

fn load(dir: &Path, text: &str) -> Scene {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// One particle's state after a step: x, v, ω, wall contacts.
#[derive(Clone, Copy, Debug)]
struct State {
    x: DVec3,
    v: DVec3,
    w: DVec3,
    touches: usize,
}

/// The single particle's state after every step.
fn states(scene: &Scene) -> Vec<State> {
    let mut sim = scene.build(false);
    let mut q = sim.world.query::<(
        &ParticleId,
        &Position,
        &Velocity,
        &AngularVelocity,
        &WallHistory,
    )>();
    (0..scene.steps())
        .map(|_| {
            sim.step().unwrap();
            let (_, x, v, w, h) = q.single(&sim.world).unwrap();
            State {
                x: x.0,
                v: v.0,
                w: w.0,
                touches: h.0.len(),
            }
        })
        .collect()
}

/// Largest deviations of `a` from `b`, relative to the largest |x|, |v|, |ω| of `b`.
fn deviation(a: &[State], b: &[State]) -> (f64, f64, f64) {
    assert_eq!(a.len(), b.len());
    let scale = |f: &dyn Fn(&State) -> DVec3| b.iter().map(|s| f(s).length()).fold(0.0, f64::max);
    let dev = |f: &dyn Fn(&State) -> DVec3| {
        let s = scale(f);
        a.iter()
            .zip(b)
            .map(|(p, q)| (f(p) - f(q)).length())
            .fold(0.0, f64::max)
            / if s > 0.0 { s } else { 1.0 }
    };
    (dev(&|s| s.x), dev(&|s| s.v), dev(&|s| s.w))
}

const TOL: f64 = 1e-9;

#[test]
fn thrown_sphere_bounces_off_a_wall_patch_as_off_the_plane() {
    // (v0, centre at the hit, plane point, inward normal); the hit comes 2 ms after the
    // start. On the floor at (5, 5) mm: a corner shared by four faces of the zmin patch,
    // so the contact (t_c ≈ 50 µs = 50 steps) moves across faces and their triangles.
    let floor = (
        DVec3::new(0.3, 0.1, -0.5),
        DVec3::new(5.0e-3, 5.0e-3, 0.5 * D),
        DVec3::ZERO,
        DVec3::Z,
    );
    // A side wall (x = L), thrown sideways under gravity.
    let side = (
        DVec3::new(0.5, 0.2, 0.1),
        DVec3::new(L - 0.5 * D, 5.0e-3, 5.0e-3),
        DVec3::new(L, 0.0, 0.0),
        -DVec3::X,
    );
    for shape in SHAPES {
        let dir = tempfile::tempdir().unwrap();
        write_box(dir.path(), shape);
        for (name, (v0, hit, point, normal)) in [("floor", floor), ("side", side)] {
            // Start so that the throw reaches `hit` after 2 ms (the free flight is close
            // to ballistic: τ ≈ 7.7 s).
            let t = 2.0e-3;
            let x0 = hit - v0 * t + 0.5 * DVec3::new(0.0, 0.0, 9.81) * t * t;
            for (friction, rolling) in [(0.0, 0.0), (0.3, 0.0), (0.3, 0.02)] {
                let mesh = load(
                    dir.path(),
                    &one_sphere(&mesh_flow(), x0, v0, friction, rolling, 1e-6, 3.0e-3),
                );
                assert!(mesh.patch_walls.is_some(), "contact walls by default");
                let plane = load(
                    dir.path(),
                    &one_sphere(
                        &plane_flow(point, normal),
                        x0,
                        v0,
                        friction,
                        rolling,
                        1e-6,
                        3.0e-3,
                    ),
                );
                let (a, b) = (states(&mesh), states(&plane));
                let touched = b
                    .iter()
                    .filter(|s| (s.x - point).dot(normal) < 0.5 * D)
                    .count();
                assert!(
                    touched > 20,
                    "{name}: the sphere should touch the wall: {touched} steps"
                );
                // One contact whenever the plane has one.
                assert!(
                    a.iter().zip(&b).all(|(p, q)| p.touches == q.touches),
                    "{shape:?} {name}: contacts differ"
                );
                let (dx, dv, dw) = deviation(&a, &b);
                let end = b.last().unwrap();
                println!(
                    "{shape:?} {name} μ = {friction} μ_r = {rolling}: {touched} steps in contact, end v = {:?}, ω = {:?}; deviation x {dx:.2e}, v {dv:.2e}, ω {dw:.2e}",
                    end.v.to_array(),
                    end.w.to_array()
                );
                assert!(end.v.dot(-normal) < 0.0, "{name}: it bounced");
                assert!(
                    dx < TOL && dv < TOL && dw < TOL,
                    "{shape:?} {name} μ = {friction}: {dx:e} {dv:e} {dw:e}"
                );
            }
        }
    }
}

#[test]
fn sphere_rolling_over_faces_and_split_quads_feels_one_contact() {
    // Resting on the floor with a sideways speed: friction turns sliding into rolling,
    // the contact crosses the face edge at x = 5 mm (two faces of one flat patch) and the
    // triangles' edges inside the faces (quads split about their centres, the tet mesh's
    // diagonals, the polygons of hanging nodes): one contact, one tangential history,
    // the plane's trajectory.
    for shape in SHAPES {
        let dir = tempfile::tempdir().unwrap();
        write_box(dir.path(), shape);
        // At its resting overlap under gravity (δ = (m·g/K)^(2/3) ≈ 39 nm).
        let x0 = DVec3::new(4.3e-3, 4.3e-3, 0.5 * D - 3.9e-8);
        let v0 = DVec3::new(0.06, 0.03, 0.0);
        let mesh = load(
            dir.path(),
            &one_sphere(&mesh_flow(), x0, v0, 0.3, 0.02, 2e-6, 0.02),
        );
        let plane = load(
            dir.path(),
            &one_sphere(
                &plane_flow(DVec3::ZERO, DVec3::Z),
                x0,
                v0,
                0.3,
                0.02,
                2e-6,
                0.02,
            ),
        );
        let (a, b) = (states(&mesh), states(&plane));
        // It settles within a few hundred steps (a hop off the start), then rolls.
        let settled = b.iter().position(|s| s.touches == 1).unwrap();
        let rolling = b.len() - settled;
        assert!(b[settled..].iter().all(|s| s.touches == 1), "{shape:?}");
        assert!(
            rolling > b.len() * 9 / 10,
            "{shape:?}: in contact {rolling} steps"
        );
        assert!(
            a.iter().zip(&b).all(|(p, q)| p.touches == q.touches),
            "{shape:?}: one contact whenever the plane has one"
        );
        let end = b.last().unwrap();
        assert!(end.x.x > 5.05e-3, "it crossed the face edge: {:?}", end.x);
        // Rolling: the contact point is (nearly) at rest.
        let slip = (end.v + end.w.cross(-0.5 * D * DVec3::Z)).length();
        let (dx, dv, dw) = deviation(&a, &b);
        println!(
            "{shape:?} rolling: x {:?} → {:?}, slip {slip:.2e} m/s; deviation x {dx:.2e}, v {dv:.2e}, ω {dw:.2e}",
            x0.to_array(),
            end.x.to_array()
        );
        assert!(
            slip < 1e-2 * end.v.length(),
            "rolling at the end: slip {slip}"
        );
        assert!(
            dx < TOL && dv < TOL && dw < TOL,
            "{shape:?}: {dx:e} {dv:e} {dw:e}"
        );
    }
}

/// Particles at random positions in [lo, hi] with random velocities of up to `speed`.
fn random_particles(n: usize, lo: DVec3, hi: DVec3, speed: f64, seed: u64) -> (String, String) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let (mut p, mut v) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let x = DVec3::new(
            rng.random_range(lo.x..hi.x),
            rng.random_range(lo.y..hi.y),
            rng.random_range(lo.z..hi.z),
        );
        let u = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ) * speed;
        p.push(v3(x));
        v.push(v3(u));
    }
    (format!("[{}]", p.join(", ")), format!("[{}]", v.join(", ")))
}

/// 400 spheres of 0.8 mm in the box of wall patches (perturbed tetrahedra), thrown at up
/// to 1 m/s under gravity, with particle contacts: the scene and its case in `dir`.
fn crowded_box(dir: &Path, steps: u64) -> Scene {
    let mesh = BoxMesh::new(DVec3::ZERO, DVec3::splat(L), [6, 6, 6])
        .shape(CellShape::Tet)
        .naming(PatchNaming::Sides)
        .perturbed(0.2, 5)
        .build()
        .unwrap();
    // A swirl, so that the drag pushes particles at the walls too.
    let g = scg_mesh::MeshGeometry::new(&mesh).unwrap();
    let field = CellField {
        cells: g
            .cell_centres
            .iter()
            .map(|c| DVec3::new(c.y - 0.5 * L, 0.5 * L - c.x, 0.0) * 200.0)
            .collect(),
        patches: vec![None; mesh.patches.len()],
    };
    write_case(dir.join("case"), &mesh, Some(("U", &field)), Format::Binary).unwrap();
    let (p, v) = random_particles(400, DVec3::splat(1e-3), DVec3::splat(9e-3), 1.0, 3);
    let text = format!(
        "duration = {:e}\ndt = 2e-6\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n[drag]\nlaw = \"stokes\"\n[gravity]\nacceleration = [0.0, 0.0, -9.81]\n[material]\nyoungs_modulus = 1e8\npoisson_ratio = 0.3\nrestitution = 0.7\nfriction = 0.3\n[contacts]\nrolling_friction = 0.01\n[flow]\nkind = \"openfoam\"\ncase = \"case\"\n[flow.patches]\n{SIDES}\n[[groups]]\nname = \"p\"\ndiameter = 0.8e-3\ndensity = 2500.0\npositions = {p}\nvelocities = {v}\n",
        steps as f64 * 2e-6
    );
    load(dir, &text)
}

/// Run the crowded box: the particles at the end, lost count, wall contacts started.
fn run_crowded_box(steps: u64) -> (Vec<scg::core::sim::ParticleState>, usize, u64) {
    let dir = tempfile::tempdir().unwrap();
    let scene = crowded_box(dir.path(), steps);
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    let lost = sim
        .world
        .resource::<OutletLog>()
        .lost
        .iter()
        .map(Vec::len)
        .sum();
    let walls = sim.world.resource::<ContactResolution>().wall().contacts;
    (sim.particles(), lost, walls)
}

#[test]
fn box_of_wall_patches_with_contacts_keeps_every_particle() {
    let (ps, lost, walls) = run_crowded_box(5000);
    let r = 0.4e-3;
    // Centres inside, and no deeper into a wall than a small fraction of the radius.
    let outside = ps
        .iter()
        .filter(|p| p.position.cmplt(DVec3::ZERO).any() || p.position.cmpgt(DVec3::splat(L)).any())
        .count();
    let deepest = ps
        .iter()
        .map(|p| {
            let lo = p.position.min_element();
            let hi = L - p.position.max_element();
            r - lo.min(hi)
        })
        .fold(f64::NEG_INFINITY, f64::max);
    println!(
        "crowded box: {} particles, lost {lost}, outside {outside}, {walls} wall contacts, deepest overlap {:.3} r",
        ps.len(),
        deepest / r
    );
    assert_eq!((ps.len(), lost, outside), (400, 0, 0));
    assert!(walls > 50, "wall contacts: {walls}");
    assert!(deepest < 0.05 * r, "overlap {deepest} m");
}

/// A digest of the crowded box's final state.
fn patch_walls_digest() -> String {
    let (ps, ..) = run_crowded_box(1000);
    format!("{:016x}", common::state_digest(&ps))
}

/// One thread, two threads with every pass split, and two with the portable kernels: the
/// same bits.
#[test]
fn patch_walls_same_bits_on_one_and_two_threads() {
    let a = common::digest_with(1, 100_000_000, false, patch_walls_digest);
    let b = common::digest_with(2, 1, false, patch_walls_digest);
    let c = common::digest_with(2, 1, true, patch_walls_digest);
    println!("{a} (1 thread), {b} (2 threads, every pass split), {c} (portable)");
    assert_eq!(a, b);
    assert_eq!(a, c);
}

fn scg_cmd(dir: &Path, args: &[&str], text: &str) -> (i32, String, String) {
    let path = dir.join("s.toml");
    std::fs::write(&path, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(args)
        .arg(&path)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!err.contains("panicked"), "panic: {err}");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        err,
    )
}

#[test]
fn check_and_plan_say_what_the_wall_patches_became() {
    let dir = tempfile::tempdir().unwrap();
    write_box(dir.path(), CellShape::Hex);
    let x0 = DVec3::splat(5e-3);
    let contact = one_sphere(&mesh_flow(), x0, DVec3::ZERO, 0.3, 0.0, 1e-6, 1e-4);
    // Contact walls: 64 quads per side, 4 triangles each.
    let (code, out, err) = scg_cmd(dir.path(), &["check"], &contact);
    println!("{out}");
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("patch `zmin` (patch): 64 faces, wall: contact wall with 256 triangles"),
        "{out}"
    );
    assert!(
        out.contains("wall `flow.patches.walls`: mesh of 1536 triangles"),
        "{out}"
    );
    let (_, plan, _) = scg_cmd(dir.path(), &["run", "--plan"], &contact);
    assert!(plan.contains("wall_contact_forces"), "{plan}");
    // Rebound on request: no wall system.
    let rebound = contact.replace(
        "[flow.patches]\n",
        "[flow.patches]\nwall_model = \"rebound\"\n",
    );
    let (code, out, _) = scg_cmd(dir.path(), &["check"], &rebound);
    assert_eq!(code, 0);
    assert!(
        out.contains("64 faces, wall: rebound of the centre as an impulse, restitution e = 0.8"),
        "{out}"
    );
    let (_, plan, _) = scg_cmd(dir.path(), &["run", "--plan"], &rebound);
    assert!(!plan.contains("wall_"), "{plan}");
    let s = load(dir.path(), &rebound);
    assert!(
        !s.build(false)
            .plan()
            .contains(StepSystem::WallContactForces)
    );
    // Without a material: rebound, and "contact" is an error naming the key.
    let bare = contact
        .replace("[material]\nyoungs_modulus = 1e8\npoisson_ratio = 0.3\nrestitution = 0.8\nfriction = 3e-1\n", "");
    assert!(!bare.contains("[material]"), "{bare}");
    let (code, out, err) = scg_cmd(dir.path(), &["check"], &bare);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains(
            "wall: rebound of the centre as an impulse, restitution e = 1, Coulomb friction μ = 0"
        ),
        "{out}"
    );
    let bad = bare.replace(
        "[flow.patches]\n",
        "[flow.patches]\nwall_model = \"contact\"\n",
    );
    let (code, _, err) = scg_cmd(dir.path(), &["check"], &bad);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("s.toml:")
            && err.contains("flow.patches.wall_model")
            && err.contains("[material]"),
        "{err}"
    );
    let bad = contact.replace(
        "[flow.patches]\n",
        "[flow.patches]\nwall_model = \"sticky\"\n",
    );
    let (code, _, err) = scg_cmd(dir.path(), &["check"], &bad);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("wall_model"), "{err}");
}

/// A restart from a checkpoint (cells and wall histories included) ends bit-identical
/// to the uninterrupted run.
#[test]
fn patch_walls_restart_is_bit_identical() {
    let dir = tempfile::tempdir().unwrap();
    let scene = crowded_box(dir.path(), 600);
    let total = scene.steps();
    let mut straight = scene.build(false);
    straight.run(total, |_| true).unwrap();
    let end = straight.checkpoint();
    assert!(end.particles.iter().all(|p| p.cell.is_some()));
    let mut first = scene.build(false);
    first.run(total / 2 + 7, |_| true).unwrap();
    let half = first.checkpoint();
    let mut second = scene.build(false);
    second.restore(&half).unwrap();
    second.run(total - half.step, |_| true).unwrap();
    assert!(
        second.checkpoint() == end,
        "restart with patch walls diverged"
    );
}
