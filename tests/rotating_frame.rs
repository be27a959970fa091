//! `[frame]` (issue 40): a flow given in a rotating frame (OpenFOAM's SRF: the relative
//! velocity) with the particles tracked in that frame under the centrifugal and Coriolis
//! accelerations. The same motion computed in the absolute frame and in a rotating one
//! agree once rotated back; the cut size of a vortex with inflow, d50 = √(18·μ·v_r·r /
//! (ρ_p·(Ω·r)²)), is reproduced within the class spacing in the rotating frame; bad input
//! is refused.
//!
//! Run: `cargo test --release --test rotating_frame -- --nocapture`.

use std::path::Path;

use glam::{DMat3, DVec3};

/// The scene: 10 µm particles (ρ 1000) in `flow`, Stokes drag, optionally a frame.
fn scene(
    dir: &Path,
    flow: &str,
    frame: &str,
    groups: &str,
    duration: f64,
    dt: f64,
) -> scg::scene::Scene {
    let text = format!(
        "duration = {duration}\ndt = {dt}\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n{flow}\n[drag]\nlaw = \"stokes\"\n{frame}\n{groups}"
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn end(sc: &scg::scene::Scene) -> Vec<(DVec3, DVec3)> {
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    sim.particles()
        .iter()
        .map(|p| (p.position, p.velocity))
        .collect()
}

/// The rotation by Ω·t about z.
fn turn(omega: f64, t: f64) -> DMat3 {
    DMat3::from_rotation_z(omega * t)
}

/// The paper's vortex (300 rpm, inflow 0.1 of the swirl) seen from a frame turning at
/// half its rate is a vortex of 150 rpm with inflow 0.2 of that swirl; a particle started
/// with the same absolute state moves the same: its rotating-frame position turned back
/// equals the absolute one to 1e-9 relative (dt 1 µs; the mid-step fictitious forces are
/// second order). Still air seen from a frame turning at 120 rpm is a vortex of −120 rpm:
/// a particle thrown through it decelerates along a straight line in the absolute frame.
#[test]
fn the_absolute_and_the_rotating_frame_give_one_motion() {
    let dir = tempfile::tempdir().unwrap();
    let wa = 300.0 * std::f64::consts::TAU / 60.0;
    let (x0, t, dt) = (DVec3::new(0.1, 0.0, 0.0), 0.05, 1e-6);
    let u0 = DVec3::new(-0.1 * wa * 0.1, 0.1 * wa, 0.0); // the fluid's absolute velocity there
    let v0 = u0 + DVec3::new(0.3, -0.2, 0.0);
    let group = |v: DVec3| {
        format!(
            "[[groups]]\nname = \"a\"\ndiameter = 1.0e-5\ndensity = 1000.0\npositions = [[0.1, 0.0, 0.0]]\nvelocities = [[{}, {}, {}]]\n",
            v.x, v.y, v.z
        )
    };
    let absolute = scene(
        dir.path(),
        "[flow]\nkind = \"vortex\"\nrpm = 300.0\ninflow_ratio = 0.1",
        "",
        &group(v0),
        t,
        dt,
    );
    let half = 0.5 * wa;
    let v_rel = v0 - DVec3::new(0.0, 0.0, half).cross(x0);
    let rotating = scene(
        dir.path(),
        "[flow]\nkind = \"vortex\"\nrpm = 150.0\ninflow_ratio = 0.2",
        "[frame]\nrpm = 150.0\naxis = [0.0, 0.0, 1.0]",
        &group(v_rel),
        t,
        dt,
    );
    let a = end(&absolute)[0].0;
    let r = turn(half, t) * end(&rotating)[0].0;
    let err = (a - r).length() / a.length();
    eprintln!("vortex: absolute {a}, rotating turned back {r}: {err:.2e}");
    assert!(err < 1e-9, "{err}");
    assert!((a - x0).length() > 0.01, "it moved");

    // still air from a frame turning at 120 rpm
    let w = 120.0 * std::f64::consts::TAU / 60.0;
    let v0 = DVec3::new(0.0, 1.0, 0.0);
    let still = scene(dir.path(), "", "", &group(v0), t, dt);
    let spun = scene(
        dir.path(),
        "[flow]\nkind = \"vortex\"\nrpm = -120.0\ninflow_ratio = 0.0",
        "[frame]\nrpm = 120.0\naxis = [0.0, 0.0, 1.0]",
        &group(v0 - DVec3::new(0.0, 0.0, w).cross(x0)),
        t,
        dt,
    );
    let a = end(&still)[0].0;
    let r = turn(w, t) * end(&spun)[0].0;
    let err = (a - r).length() / a.length();
    eprintln!("still air: absolute {a}, rotating turned back {r}: {err:.2e}");
    assert!(err < 1e-9, "{err}");
    assert!(a.x == 0.1 && a.y > 0.0, "a straight line: {a}");
}

/// The vortex of 300 rpm with inflow 0.1 of its swirl, given in the frame turning at
/// 150 rpm: the equilibrium of drag on the inflow against the centrifugal pull, d50 =
/// √(18·μ·v_r·r / (ρ_p·(Ω·r)²)) = √(18·μ·k/(ρ_p·Ω)) (v_r = k·Ω·r) = 22.7 µm at ρ_p = 2000,
/// at every radius. Classes 5 % apart around it, started at 0.1 m at the fluid's velocity,
/// drift inward below d50 and outward above it: the rotating frame resolves the cut
/// within the class spacing.
#[test]
fn the_cut_size_in_the_rotating_frame() {
    let dir = tempfile::tempdir().unwrap();
    let wa = 300.0 * std::f64::consts::TAU / 60.0;
    let d50 = (18.0 * 1.8e-5 * 0.1 / (2000.0 * wa)).sqrt();
    let sizes = [0.9, 0.95, 1.05, 1.1].map(|f| f * d50);
    let half = 0.5 * wa;
    // the relative fluid velocity at (0.1, 0, 0): swirl (Ω_a − Ω)·r, inflow k·Ω_a·r
    let u = DVec3::new(-0.1 * wa * 0.1, 0.1 * (wa - half), 0.0);
    let groups: String = sizes
        .iter()
        .enumerate()
        .map(|(i, d)| {
            format!(
                "[[groups]]\nname = \"g{i}\"\ndiameter = {d:e}\ndensity = 2000.0\npositions = [[0.1, 0.0, 0.0]]\nvelocities = [[{}, {}, 0.0]]\n",
                u.x, u.y
            )
        })
        .collect();
    let sc = scene(
        dir.path(),
        "[flow]\nkind = \"vortex\"\nrpm = 150.0\ninflow_ratio = 0.2",
        "[frame]\nrpm = 150.0\naxis = [0.0, 0.0, 1.0]",
        &groups,
        2.0,
        2e-5,
    );
    let plan = sc.build(false).plan().render();
    assert!(plan.contains("[frame] rotating at 150"), "{plan}");
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    let mut r: Vec<(u32, f64)> = sim
        .particles()
        .iter()
        .map(|p| (p.group, p.position.truncate().length()))
        .collect();
    r.sort_by_key(|x| x.0);
    eprintln!("d50 {:.2} µm; radius after 2 s per class: {r:?}", d50 * 1e6);
    assert!(r[0].1 < 0.1 && r[1].1 < 0.1, "below d50 inward: {r:?}");
    assert!(r[2].1 > 0.1 && r[3].1 > 0.1, "above d50 outward: {r:?}");
}

/// `[frame]` needs drag, an axis along gravity, no force whose fluid acceleration would
/// need the frame's terms; each refusal names its key.
#[test]
fn bad_frames_are_refused_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f.toml");
    let group = "[[groups]]\nname = \"a\"\ndiameter = 1.0e-5\ndensity = 1000.0\npositions = [[0.1, 0.0, 0.0]]\n";
    let frame = "[frame]\nrpm = 100.0\naxis = [0.0, 0.0, 1.0]\n";
    let fluid = "[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n[drag]\nlaw = \"stokes\"\n";
    for (text, key) in [
        (
            format!("duration = 0.01\ndt = 1e-4\n{frame}{group}"),
            "frame",
        ),
        (
            format!(
                "duration = 0.01\ndt = 1e-4\n{fluid}{frame}[gravity]\nacceleration = [0.0, -9.81, 0.0]\n{group}"
            ),
            "frame.axis",
        ),
        (
            format!(
                "duration = 0.01\ndt = 1e-4\n{fluid}{frame}[forces]\nadded_mass = 0.5\n{group}"
            ),
            "forces.added_mass",
        ),
        (
            format!(
                "duration = 0.01\ndt = 1e-4\n{fluid}[frame]\nrpm = 100.0\naxis = [0.0, 0.0, 0.0]\n{group}"
            ),
            "frame.axis",
        ),
    ] {
        std::fs::write(&path, text).unwrap();
        let e = scg::scene::load(&path, &[]).unwrap_err().to_string();
        assert!(e.contains(key), "{key}: {e}");
    }
}

/// A blade turning with the frame: a plane through the axis rotating at 150 rpm (an
/// impulse wall, e = 0.8) in the paper's vortex, computed in the absolute frame (the blade
/// moves, `[[walls]] motion`) and in the frame turning with it (the blade rests, the flow
/// is the 150 rpm vortex with inflow 0.2): a particle thrown at the blade rebounds off it
/// in both, and the two motions agree once turned back (1e-9 relative).
#[test]
fn a_rotating_blade_in_the_absolute_frame_is_a_resting_one_in_the_rotating_frame() {
    let dir = tempfile::tempdir().unwrap();
    let wa = 300.0 * std::f64::consts::TAU / 60.0;
    let half = 0.5 * wa;
    let (t, dt) = (0.02, 1e-6);
    let x0 = DVec3::new(0.08, 0.004, 0.0);
    // relative to the blade (the plane y = 0 in its frame): toward it at 0.5 m/s
    let v_rel = DVec3::new(0.0, -0.5, 0.0);
    let v_abs = v_rel + DVec3::new(0.0, 0.0, half).cross(x0);
    let blade = |motion: &str| {
        format!(
            "[[walls]]\nname = \"blade\"\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\nmodel = \"rebound\"\nrestitution = 0.8\n{motion}\n[[groups]]\nname = \"a\"\ndiameter = 1.0e-4\ndensity = 2500.0\npositions = [[{}, {}, 0.0]]\n",
            x0.x, x0.y
        )
    };
    let group = |v: DVec3| format!("velocities = [[{}, {}, {}]]\n", v.x, v.y, v.z);
    let absolute = scene(
        dir.path(),
        "[flow]\nkind = \"vortex\"\nrpm = 300.0\ninflow_ratio = 0.1",
        "",
        &(blade("motion = { rpm = 150.0, axis = [0.0, 0.0, 1.0] }") + &group(v_abs)),
        t,
        dt,
    );
    let rotating = scene(
        dir.path(),
        "[flow]\nkind = \"vortex\"\nrpm = 150.0\ninflow_ratio = 0.2",
        "[frame]\nrpm = 150.0\naxis = [0.0, 0.0, 1.0]",
        &(blade("") + &group(v_rel)),
        t,
        dt,
    );
    let (a, va) = end(&absolute)[0];
    let (r, vr) = end(&rotating)[0];
    let turned = turn(half, t) * r;
    let err = (a - turned).length() / a.length();
    eprintln!("blade: absolute {a}, rotating turned back {turned}: {err:.2e}; v_rel {vr}");
    assert!(err < 1e-9, "{err}");
    // it struck the blade and came back off it: on the blade's side, moving away from it
    assert!(r.y > 0.0 && vr.y > 0.0, "{r} {vr}");
    let va_rel = turn(half, t).transpose() * va - DVec3::new(0.0, 0.0, half).cross(r);
    assert!(
        (va_rel - vr).length() < 1e-9 * vr.length().max(1.0),
        "{va_rel} vs {vr}"
    );
}
