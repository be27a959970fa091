//! `[forces]`: the opt-in forces besides drag and gravity, each evaluated for the original
//! particle so that SCG keeps the original's acceleration.
//!
//! Cunningham slip: a 1 µm particle relaxes with τ·C_c (Davies, C_c = 1.166 in air) and
//! settles at τ·C_c·g; SCG α = 2 and 4 follow the original to 1e-12 with the correction
//! taken at the original diameter (`forces_at = "original"`, the default), and depart by
//! the ratio of C_c at the two sizes with `forces_at = "coarse"`.

use scg::core::physics::drag::cunningham_davies;

const SCENE: &str = r#"
name = "slip"
duration = 2.0e-4
dt = 1.0e-6
seed = 1

[fluid]
density = 1.2
viscosity = 1.8e-5

[flow]
kind = "uniform"
velocity = [1.0, 0.0, 0.0]

[drag]
law = "stokes"

[gravity]
acceleration = [0.0, 0.0, -9.81]

[forces]
cunningham = { mean_free_path = 6.6e-8 }

[[groups]]
name = "a"
diameter = 1.0e-6
density = 1000.0
positions = [[0.0, 0.0, 0.0]]
"#;

/// The scene `text` with the overrides `set`, or the error loading it gives.
fn load(text: &str, set: &[&str]) -> Result<scg::scene::Scene, scg::scene::SceneError> {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    scg::scene::parse(text, "forces.toml", "forces", &set)
}

/// [`load`] that must succeed.
fn scene(text: &str, set: &[&str]) -> scg::scene::Scene {
    load(text, set).unwrap_or_else(|e| panic!("{e}"))
}

fn run(set: &[&str]) -> (scg::scene::Scene, Vec<scg::core::sim::ParticleState>) {
    let scene = scene(SCENE, set);
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    let p = sim.particles();
    (scene, p)
}

#[test]
fn a_small_particle_relaxes_and_settles_with_the_slip_corrected_tau() {
    let (scene, p) = run(&[]);
    let (d, rho, mu, g) = (1e-6, 1000.0, 1.8e-5, 9.81);
    let cc = cunningham_davies(d, 6.6e-8);
    assert!((cc - 1.166).abs() < 5e-4);
    let tau = rho * d * d / (18.0 * mu) * cc;
    let t = scene.steps() as f64 * scene.dt;
    // from rest in u = (1, 0, 0) with gravity: v = w·(1 − e^(−t/τ)), w = u + τ·g
    let e = 1.0 - (-t / tau).exp();
    let vx = 1.0 * e;
    let vz = -tau * g * e;
    let v = p[0].velocity;
    assert!((v.x - vx).abs() < 1e-12 * vx, "{} vs {vx}", v.x);
    assert!((v.z - vz).abs() < 1e-9 * vz.abs(), "{} vs {vz}", v.z);
    // without the correction it is 14 % faster to respond: the test sees the difference
    let (_, plain) = run(&["forces.cunningham.mean_free_path=1e-30"]);
    assert!((plain[0].velocity.z / v.z - 1.0 / cc).abs() < 1e-3);
}

#[test]
fn scg_follows_the_original_with_the_slip_taken_at_its_size() {
    let (_, original) = run(&[]);
    let x0 = original[0].position;
    for alpha in ["2", "4"] {
        let (_, at) = run(&[&format!("groups.0.alpha={alpha}")]);
        let x = at[0].position;
        assert!(
            (x - x0).length() <= 1e-12 * x0.length(),
            "α {alpha}: {x} vs {x0}"
        );
        // "coarse": C_c at α·d, a different τ, a different path
        let (_, coarse) = run(&[
            &format!("groups.0.alpha={alpha}"),
            "coarse_grain.forces_at=\"coarse\"",
        ]);
        let dz = (coarse[0].position.z - x0.z).abs() / x0.z.abs();
        assert!(
            dz > 0.03,
            "α {alpha}: forces_at coarse moves z by only {dz}"
        );
    }
}

#[test]
fn the_plan_names_the_slip_and_bad_input_is_refused() {
    let plan = scene(SCENE, &[]).build(false).plan().render();
    assert!(plan.contains("cunningham_davies"), "{plan}");
    let none = scene(SCENE, &["forces.cunningham.mean_free_path=1e-30"]);
    assert!(none.build(false).plan().render().contains("cunningham"));
    let plain = SCENE.replace("[forces]\ncunningham = { mean_free_path = 6.6e-8 }\n", "");
    let off = scene(&plain, &[]);
    assert!(!off.build(false).plan().render().contains("cunningham"));
    for (set, key) in [
        (
            "forces.cunningham.mean_free_path=-1",
            "forces.cunningham.mean_free_path",
        ),
        ("forces.lift=true", "lift"),
    ] {
        let e = load(SCENE, &[set]).expect_err(set);
        assert!(e.to_string().contains(key), "{set}: {e}");
    }
    let nodrag = SCENE.replace("[drag]\nlaw = \"stokes\"\n", "");
    let e = load(&nodrag, &[]).expect_err("no drag");
    assert!(e.to_string().contains("forces.cunningham"), "{e}");
}

/// A neutrally buoyant 1 mm sphere in water turning with a solid-body rotation of
/// 1 rad/s, started with the fluid's velocity.
const NEUTRAL: &str = r#"
name = "neutral"
duration = 6.283185307179586
dt = 5.0e-5
seed = 1

[fluid]
density = 1000.0
viscosity = 1.0e-3

[flow]
kind = "vortex"
center = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
rpm = 9.549296585513721
inflow_ratio = 0.0

[drag]
law = "stokes"

[forces]
pressure_gradient = true
added_mass = 0.5

[[groups]]
name = "a"
diameter = 1.0e-3
density = 1000.0
positions = [[0.1, 0.0, 0.0]]
velocities = [[0.0, 0.1, 0.0]]
"#;

/// The largest relative departure of the particle's distance from the axis from 0.1 m
/// over one revolution (checked every 100 steps).
fn radius_drift(set: &[&str]) -> f64 {
    let scene = scene(NEUTRAL, set);
    let mut sim = scene.build(false);
    let mut worst = 0.0f64;
    let mut done = 0;
    while done < scene.steps() {
        let n = 100.min(scene.steps() - done);
        sim.run(n, |_| true).unwrap();
        done += n;
        let x = sim.particles()[0].position;
        worst = worst.max(((x.x * x.x + x.y * x.y).sqrt() / 0.1 - 1.0).abs());
    }
    worst
}

#[test]
fn a_neutral_particle_follows_a_solid_body_rotation() {
    // with the pressure gradient and added mass on, dv/dt = (u − v)/(k·τ) + Du/Dt: v = u
    // along the path is the solution, and the particle stays on its circle
    let on = radius_drift(&[]);
    eprintln!("pressure gradient + added mass: radius within {on:.2e} over a revolution");
    assert!(on < 1e-9, "{on}");
    // without the pressure gradient nothing holds it on the circle: it drifts outward
    let off = radius_drift(&["forces.pressure_gradient=false"]);
    eprintln!("added mass alone: {off:.2e}");
    assert!(off > 1e-4, "{off}");
}

/// A 20 µm, 2000 kg/m³ particle in a forced vortex with inflow (the paper's classifier
/// flow without its nozzle), every step force on: SCG α = 2 and 4 give the original's
/// trajectory (each force evaluated for the original particle), and the lift moves it.
const SWIRL: &str = r#"
name = "swirl"
duration = 0.05
dt = 1.0e-5
seed = 1

[fluid]
density = 1.2
viscosity = 1.8e-5

[flow]
kind = "vortex"
center = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
rpm = 3000.0
inflow_ratio = 0.5

[drag]
law = "stokes"

[gravity]
acceleration = [0.0, 0.0, -9.81]
buoyancy = true

[forces]
pressure_gradient = true
added_mass = 0.5
saffman_mei = true
rubinow_keller = true
cunningham = { mean_free_path = 6.6e-8 }

[[groups]]
name = "a"
diameter = 20.0e-6
density = 2000.0
positions = [[0.02, 0.0, 0.0]]
"#;

fn swirl(set: &[&str]) -> glam::DVec3 {
    let scene = scene(SWIRL, set);
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    sim.particles()[0].position
}

#[test]
fn scg_keeps_the_originals_path_with_every_force_on() {
    let x0 = swirl(&[]);
    for alpha in ["2", "4"] {
        let x = swirl(&[&format!("groups.0.alpha={alpha}")]);
        assert!(
            (x - x0).length() <= 1e-12 * x0.length(),
            "α {alpha}: {x} vs {x0}"
        );
        let coarse = swirl(&[
            &format!("groups.0.alpha={alpha}"),
            "coarse_grain.forces_at=\"coarse\"",
        ]);
        assert!(
            (coarse - x0).length() > 1e-6 * x0.length(),
            "α {alpha}: coarse {coarse}"
        );
    }
    // each step force changes the path (the test would see one switched off)
    for off in [
        "forces.saffman_mei=false",
        "forces.pressure_gradient=false",
        "forces.rubinow_keller=false",
    ] {
        let x = swirl(&[off]);
        assert!(
            (x - x0).length() > 1e-9 * x0.length(),
            "{off} changes nothing"
        );
    }
}

#[test]
fn the_plan_lists_the_step_forces() {
    let plan = scene(SWIRL, &[]).build(false).plan().render();
    for want in [
        "forces:pressure_gradient+added_mass+saffman_mei",
        "added_mass inertia",
        "cunningham_davies",
        "drag:stokes+forces",
        "rotational_lift",
    ] {
        assert!(plan.contains(want), "{want}: {plan}");
    }
    let off = scene(
        SWIRL,
        &["forces.saffman_mei=false", "forces.pressure_gradient=false"],
    );
    let plan = off.build(false).plan().render();
    assert!(
        plan.contains("forces:added_mass") && !plan.contains("saffman"),
        "{plan}"
    );
}

/// Rubinow–Keller: in the forced vortex (vorticity 2Ω everywhere) a particle fed without
/// spin spins up toward Ω as e^(−t/τ_r), τ_r = ρ_p·d²/(60·μ), exactly (1e-12) whatever
/// its path, for the original and SCG α = 2, 4 alike (ρ·d² is SCG's invariant).
#[test]
fn the_spin_relaxes_toward_the_fluids_rotation() {
    use scg::core::components::{AngularVelocity, ParticleId};
    let omega = 3000.0 * std::f64::consts::PI / 30.0;
    let tau = 2000.0 * 20e-6 * 20e-6 / (60.0 * 1.8e-5);
    for alpha in ["1", "2", "4"] {
        let sc = scene(SWIRL, &[&format!("groups.0.alpha={alpha}")]);
        let mut sim = sc.build(false);
        let n = 50; // 0.5 ms ≈ 0.67 τ_r
        sim.run(n, |_| true).unwrap();
        let mut q = sim.world.query::<(&ParticleId, &AngularVelocity)>();
        let (_, w) = q.iter(&sim.world).next().unwrap();
        let want = omega * (1.0 - (-(n as f64) * 1e-5 / tau).exp());
        assert!(
            (w.0.z - want).abs() <= 1e-12 * want,
            "α {alpha}: {} vs {want}",
            w.0.z
        );
        assert!(w.0.x.abs() + w.0.y.abs() == 0.0);
    }
}

/// On a mesh the forces take ∇u from the cell field (Gauss): the paper's vortex sampled
/// on a perturbed hex box and interpolated linear-exactly gives the analytic flow's
/// trajectory with every step force on, far closer than the forces move it.
#[test]
fn on_a_mesh_the_forces_see_the_fields_gradient() {
    use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
    use scg_mesh::foam::{Format, write_case};
    let dir = tempfile::tempdir().unwrap();
    let w = 4.0e-4;
    let mesh = BoxMesh::new(
        glam::DVec3::new(-w, -w, 0.0),
        glam::DVec3::new(w, w, 2.0 * w),
        [20, 20, 20],
    )
    .shape(CellShape::Hex)
    .naming(PatchNaming::Sides)
    .perturbed(0.2, 3)
    .build()
    .unwrap();
    let v = scg::core::physics::flow::Vortex {
        center: glam::DVec3::ZERO,
        axis: glam::DVec3::Z,
        omega: 300.0 * std::f64::consts::TAU / 60.0,
        inflow_ratio: 0.1,
    };
    let g = scg_mesh::MeshGeometry::new(&mesh).unwrap();
    let field = scg_mesh::CellField::at_cell_centres(&mesh, &g, |x| v.velocity(x));
    write_case(
        dir.path().join("case"),
        &mesh,
        Some(("U", &field)),
        Format::Ascii,
    )
    .unwrap();
    let scene = |flow: &str, forces: bool| {
        let text = format!(
            "duration = 0.05\ndt = 2.0e-5\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n[flow]\n{flow}\n[drag]\nlaw = \"stokes\"\n{}[[groups]]\nname = \"a\"\ndiameter = 10.0e-6\ndensity = 1000.0\npositions = [[2.5e-4, 0.0, 4.1e-4]]\n",
            if forces {
                "[forces]\npressure_gradient = true\nadded_mass = 0.5\nsaffman_mei = true\nrubinow_keller = true\n"
            } else {
                ""
            }
        );
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, text).unwrap();
        let s = scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = s.build(false);
        sim.run(s.steps(), |_| true).unwrap();
        sim.particles()[0].position
    };
    let mesh_flow = "kind = \"openfoam\"\ncase = \"case\"\ntime = \"latest\"\nfield = \"U\"\ninterpolation = \"cell_point_linear_exact\"\n[flow.patches]\nwalls = [\"xmin\", \"xmax\", \"ymin\", \"ymax\", \"zmin\", \"zmax\"]";
    let analytic = "kind = \"vortex\"\nrpm = 300.0\ninflow_ratio = 0.1";
    let (on_mesh, on) = (scene(mesh_flow, true), scene(analytic, true));
    let off = scene(analytic, false);
    let (mesh_err, effect) = ((on_mesh - on).length(), (on - off).length());
    eprintln!(
        "mesh vs analytic with the forces: {mesh_err:.2e} m; the forces move it {effect:.2e} m"
    );
    assert!(effect > 1e-9, "{effect}");
    assert!(mesh_err < 1e-3 * effect, "{mesh_err} vs {effect}");
}
