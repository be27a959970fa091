//! Walls with a velocity: the wall's surface velocity at the contact point enters the one
//! contact model, so a wall translating at constant velocity gives the contact a resting
//! wall gives in the wall's frame (Galilean invariance, to round-off), with and without
//! friction; a turntable drags a resting sphere along its surface velocity.
//!
//! Run: `cargo test --release --test moving_walls`.

mod common;

use glam::DVec3;
use scg::core::components::AngularVelocity;
use scg::core::physics::contact::{Material, NormalLaw};
use scg::core::physics::flow::FlowField;
use scg::core::physics::integrate::Integrator;
use scg::core::physics::scaling::CoarseGrainLaw;
use scg::core::physics::wall_motion::WallMotion;
use scg::core::physics::wall_shape::WallShape;
use scg::core::stages::walls::{Wall, WallSet};
use scg::core::{ParticleSpec, SimConfig, Simulation};

const D: f64 = 1e-3;
const RHO: f64 = 2500.0;
const DT: f64 = 2e-7;

fn sim(
    motion: WallMotion,
    friction: f64,
    gravity: Option<DVec3>,
    x0: DVec3,
    v0: DVec3,
) -> Simulation {
    let mut s = Simulation::new(SimConfig {
        dt: DT,
        integrator: Integrator::Exponential,
        drag: None,
        fluid: None,
        flow: FlowField::Still,
        mesh_flow: None,
        gravity,
        buoyancy: false,
        scg_at_original: false,
        extra_forces: Default::default(),
        contacts: None,
        walls: Some(WallSet {
            walls: vec![Wall {
                name: "floor".into(),
                shape: WallShape::Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Z,
                },
                motion,
            }],
            law: NormalLaw::hertz(0.7),
            material: Material {
                youngs_modulus: 1e8,
                poisson_ratio: 0.3,
                restitution: 0.7,
                friction,
            },
        }),
        record_every: None,
        groups: vec!["p".into()],
        carrier: None,
    });
    s.spawn(&ParticleSpec {
        group: 0,
        diameter: D,
        density: RHO,
        alpha: 1.0,
        law: CoarseGrainLaw::Scg,
        position: x0,
        velocity: v0,
    });
    s
}

/// (x, v, ω) of the one particle.
fn state(s: &mut Simulation) -> (DVec3, DVec3, DVec3) {
    let p = s.particles()[0];
    let w = s
        .world
        .query::<&AngularVelocity>()
        .iter(&s.world)
        .next()
        .map_or(DVec3::ZERO, |w| w.0);
    (p.position, p.velocity, w)
}

/// A floor moving at V (toward the sphere and along it) against a floor at rest met by a
/// sphere moving at v0 − V: at every step x − V·t, v − V and ω agree to round-off
/// (positions to 1e-13 m, velocities and spins to 1e-11 of their scale), through the
/// approach, an oblique frictional contact (sliding, then rolling) and the rebound; the
/// wall's velocity really acts (a floor at rest gives another rebound).
#[test]
fn a_translating_wall_is_a_resting_wall_in_its_frame() {
    let v_wall = DVec3::new(0.3, -0.2, 0.25);
    let x0 = DVec3::new(1e-3, 2e-3, 0.52e-3);
    let v0 = DVec3::new(0.4, 0.1, -0.5);
    for friction in [0.0, 0.4] {
        let moving = WallMotion {
            velocity: v_wall,
            ..WallMotion::FIXED
        };
        let mut a = sim(moving, friction, None, x0, v0);
        let mut b = sim(WallMotion::FIXED, friction, None, x0, v0 - v_wall);
        let mut c = sim(WallMotion::FIXED, friction, None, x0, v0);
        let (mut touched, mut worst) = (0, [0.0_f64; 3]);
        for k in 1..=20_000u32 {
            a.step().unwrap();
            b.step().unwrap();
            c.step().unwrap();
            let t = k as f64 * DT;
            let ((xa, va, wa), (xb, vb, wb)) = (state(&mut a), state(&mut b));
            let dx = (xa - v_wall * t - xb).length();
            let dv = (va - v_wall - vb).length() / v0.length();
            let dw = (wa - wb).length() / (v0.length() / D);
            worst = [worst[0].max(dx), worst[1].max(dv), worst[2].max(dw)];
            if xb.z < 0.5 * D {
                touched += 1;
            }
        }
        println!(
            "friction {friction}: {touched} steps in contact, worst |Δx| {:.2e} m, |Δv|/v {:.2e}, |Δω|/(v/d) {:.2e}",
            worst[0], worst[1], worst[2]
        );
        assert!(touched > 50, "the sphere met the floor ({touched} steps)");
        assert!(
            worst[0] < 1e-13 && worst[1] < 1e-11 && worst[2] < 1e-11,
            "{worst:?}"
        );
        let ((_, vb, _), (_, vc, _)) = (state(&mut b), state(&mut c));
        assert!(
            (vb + v_wall - vc).length() > 0.05,
            "the wall's velocity acted"
        );
    }
}

/// A sphere resting on a turntable (a floor spinning about z through the origin) under
/// gravity, with friction: the surface under it drags it along ω × r, and it moves in that
/// direction, not radially; without friction it stays put.
#[test]
fn a_turntable_drags_a_resting_sphere_along_its_surface() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let turntable = WallMotion {
        angular_velocity: DVec3::new(0.0, 0.0, 20.0),
        ..WallMotion::FIXED
    };
    let x0 = DVec3::new(0.01, 0.0, 0.5 * D - 1e-7);
    for friction in [0.0, 0.5] {
        let mut s = sim(turntable, friction, Some(g), x0, DVec3::ZERO);
        for _ in 0..5_000 {
            s.step().unwrap();
        }
        let (x, v, _) = state(&mut s);
        let surface = DVec3::new(0.0, 20.0 * 0.01, 0.0); // ω × r at x0: +y
        let along = v.dot(surface.normalize());
        println!("friction {friction}: v = {v}, x = {x}");
        if friction > 0.0 {
            assert!(along > 1e-3, "dragged along the surface: {v}");
            assert!(v.x.abs() < 0.2 * along, "not radially: {v}");
        } else {
            assert!(
                along.abs() < 1e-9 && v.x.abs() < 1e-9,
                "no friction, no drag: {v}"
            );
        }
    }
}

/// A scene's `[[walls]] motion` (rpm about an axis): a 1 mm sphere resting on a horizontal
/// disc turning about z, 50 mm from the axis and carried at the disc's speed, stays on its
/// circle while Ω²·r < μ·g (static friction holds it) and slides outward once Ω²·r > μ·g
/// (μ = 0.3: Ω_c = √(μ·g/r) = 7.67 rad/s; 0.95 and 1.05 Ω_c over 0.4 s). A free sphere
/// would roll instead (the turntable's rolling orbits); rolling resistance μ_r = 0.5 > μ
/// (`[contacts] rolling_friction`) holds its spin, so friction alone decides.
#[test]
fn a_disc_throws_a_resting_sphere_off_when_its_centripetal_need_beats_friction() {
    let omega_c = (0.3f64 * 9.81 / 0.05).sqrt();
    let radius_after = |omega: f64| {
        let rpm = omega * 60.0 / std::f64::consts::TAU;
        let text = format!(
            "duration = 0.4\ndt = 2.0e-6\nrecord_every = 1000\n[gravity]\nacceleration = [0.0, 0.0, -9.81]\n[material]\nyoungs_modulus = 1.0e7\npoisson_ratio = 0.3\nrestitution = 0.3\nfriction = 0.3\n[contacts]\nrolling_friction = 0.5\n[[walls]]\nname = \"disc\"\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmotion = {{ rpm = {rpm}, axis = [0.0, 0.0, 1.0] }}\n[[groups]]\nname = \"a\"\ndiameter = 1.0e-3\ndensity = 2500.0\npositions = [[0.05, 0.0, 0.4999e-3]]\nvelocities = [[0.0, {}, 0.0]]\n",
            omega * 0.05
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("disc.toml");
        std::fs::write(&path, text).unwrap();
        let sc = scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
        assert!(!sc.walls[0].motion.is_fixed());
        let mut sim = sc.build(false);
        sim.run(sc.steps(), |_| true).unwrap();
        let x = sim.particles()[0].position;
        (x.x * x.x + x.y * x.y).sqrt()
    };
    let held = radius_after(0.95 * omega_c);
    let thrown = radius_after(1.05 * omega_c);
    eprintln!("after 0.4 s: r = {held:.6} m at 0.95 Ω_c, {thrown:.6} m at 1.05 Ω_c");
    assert!((held / 0.05 - 1.0).abs() < 1e-3, "{held}");
    assert!(thrown > 0.055, "{thrown}");
}

/// `motion` keys: rpm needs an axis, rpm and angular_velocity exclude each other, a motion
/// that moves nothing is refused; each error names its key.
#[test]
fn bad_wall_motions_are_refused_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.toml");
    for (motion, key) in [
        ("{ rpm = 100.0 }", "walls[0].motion.axis"),
        ("{ axis = [0.0, 0.0, 1.0] }", "walls[0].motion.axis"),
        (
            "{ rpm = 100.0, axis = [0.0, 0.0, 1.0], angular_velocity = [0.0, 0.0, 1.0] }",
            "walls[0].motion.angular_velocity",
        ),
        ("{ velocity = [0.0, 0.0, 0.0] }", "walls[0].motion"),
        ("{ spin = 3.0 }", "spin"),
    ] {
        std::fs::write(
            &path,
            format!("duration = 0.01\ndt = 1.0e-4\n[[walls]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmodel = \"rebound\"\nmotion = {motion}\n[[groups]]\nname = \"a\"\ndiameter = 1.0e-3\ndensity = 2500.0\npositions = [[0.0, 0.0, 0.01]]\n"),
        )
        .unwrap();
        let e = scg::scene::load(&path, &[]).unwrap_err().to_string();
        assert!(e.contains(key), "{motion}: {e}");
    }
}

/// A moving wall restarts and replays exactly: its pose follows the step counter, so a run
/// restarted from a checkpoint halfway equals the uninterrupted one bit for bit (a sphere
/// riding the turntable, its tangential spring on the moving surface in the checkpoint),
/// and `scg replay --verify` re-runs a recording of a rising, turning rebound wall.
#[test]
fn moving_walls_restart_and_replay_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let disc = "duration = 0.02\ndt = 2.0e-6\nrecord_every = 1000\n[gravity]\nacceleration = [0.0, 0.0, -9.81]\n[material]\nyoungs_modulus = 1.0e7\npoisson_ratio = 0.3\nrestitution = 0.3\nfriction = 0.3\n[[walls]]\nname = \"disc\"\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmotion = { rpm = 90.0, axis = [0.0, 0.0, 1.0] }\n[[groups]]\nname = \"a\"\ndiameter = 1.0e-3\ndensity = 2500.0\npositions = [[0.05, 0.0, 0.4999e-3]]\nvelocities = [[0.0, 0.2, 0.0]]\n";
    let path = dir.path().join("disc.toml");
    std::fs::write(&path, disc).unwrap();
    let sc = scg::scene::load(&path, &[]).unwrap();
    let total = sc.steps();
    let mut straight = sc.build(false);
    straight.run(total, |_| true).unwrap();
    let mut first = sc.build(false);
    first.run(total / 2 + 3, |_| true).unwrap();
    let half = first.checkpoint();
    let mut resumed = sc.build(false);
    resumed.restore(&half).unwrap();
    resumed.run(total - half.step, |_| true).unwrap();
    assert!(
        resumed.checkpoint() == straight.checkpoint(),
        "the restart diverged"
    );
    assert!(
        straight.particles()[0].velocity.length() > 0.1,
        "it rides the disc"
    );

    let lift = "duration = 0.02\ndt = 1.0e-4\nrecord_every = 10\n[[walls]]\nname = \"floor\"\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmodel = \"rebound\"\nrestitution = 0.7\nfriction = 0.2\nmotion = { velocity = [0.0, 0.0, 0.2], rpm = 300.0, axis = [0.0, 0.0, 1.0] }\n[[groups]]\nname = \"a\"\ndiameter = 1.0e-3\ndensity = 2500.0\npositions = [[0.01, 0.0, 0.004], [0.0, 0.01, 0.003]]\nvelocities = [[0.0, 0.0, -0.5], [0.1, 0.0, -0.4]]\n";
    let lp = dir.path().join("lift.toml");
    std::fs::write(&lp, lift).unwrap();
    let out = dir.path().join("out");
    common::scg_ok(
        dir.path(),
        &["run", lp.to_str().unwrap(), "--out", out.to_str().unwrap()],
    );
    common::assert_replays_bit_identical(&out.join("lift.mcap"));
}
