//! Checkpoint and restart (issue 17): a run restarted from a checkpoint is bit-identical to
//! the uninterrupted run: particles (position, velocity, ω, force, torque, wall history),
//! contact list and pair histories, feeder random streams, outlet log, tally and clock.
//! Also from the checkpoint a SIGKILLed run left behind.

mod common;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use scg::core::checkpoint::Checkpoint;
use scg::record::checkpoint::{read_checkpoint, write_checkpoint};
use scg::scene::{Scene, parse};

/// Every stage at once: contacts with friction and rolling resistance, frictional walls, a
/// feeder, an outlet, drag and gravity.
const GOLDEN: &str = include_str!("fixtures/golden.toml");

fn scene(set: &[&str]) -> Scene {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    parse(GOLDEN, "golden.toml", "golden", &set).unwrap()
}

fn run_to(scene: &Scene, from: Option<&Checkpoint>, steps: u64) -> Checkpoint {
    let mut sim = scene.build(false);
    if let Some(c) = from {
        sim.restore(c).unwrap();
    }
    let left = steps - sim.step_count();
    sim.run(left, |_| true).unwrap();
    sim.checkpoint()
}

#[test]
fn restart_is_bit_identical_in_process_and_through_a_file() {
    let s = scene(&[]);
    let total = s.steps();
    let straight = run_to(&s, None, total);
    // Something happened that a restart must carry: contacts, wall history, feeding.
    let cs = straight.contacts.as_ref().unwrap();
    assert!(
        cs.pairs.iter().any(|p| p.touching),
        "no pair in contact at the end"
    );
    assert!(straight.tally[1].iter().sum::<u64>() > 0, "nothing fed");
    assert!(
        straight
            .particles
            .iter()
            .any(|p| p.wall_history.as_ref().is_some_and(|h| !h.is_empty())),
        "no wall contact at the end"
    );
    // A step after which a feeder added particles: the contact arrays then still describe
    // the rows before it (the next neighbour stage gathers them again).
    let fed_step = {
        let mut sim = s.build(false);
        let n0 = sim.particles().len();
        let mut k = 0;
        while sim.particles().len() == n0 {
            sim.step().unwrap();
            k += 1;
        }
        k
    };
    for cut in [1, fed_step, total / 3, total / 2 + 7] {
        let half = run_to(&s, None, cut);
        assert_eq!(half.step, cut);
        // Through a file.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("half.ckpt");
        write_checkpoint(&path, &half).unwrap();
        let back = read_checkpoint(&path).unwrap();
        assert_eq!(back, half);
        let resumed = run_to(&s, Some(&back), total);
        assert!(resumed == straight, "restart at step {cut} diverged");
    }
}

#[test]
fn restore_refuses_another_scene() {
    let c = run_to(&scene(&[]), None, 10);
    // Without contacts.
    let mut other = parse(
        &GOLDEN.replace("[contacts]", "[unused_contacts]"),
        "g.toml",
        "g",
        &[],
    )
    .map(|s| s.build(false));
    if let Ok(sim) = other.as_mut() {
        assert!(sim.restore(&c).is_err());
    }
    // Another dt.
    let mut sim = scene(&["dt=1e-6"]).build(false);
    let err = sim.restore(&c).unwrap_err();
    assert!(err.contains("dt"), "{err}");
}

fn scg(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

fn without_scene(mut c: Checkpoint) -> Checkpoint {
    c.scene.clear();
    c.scene_file.clear();
    c
}

/// `scg run --checkpoint-every`, killed with SIGKILL after its first checkpoint, then
/// `scg run --restart`: the final state equals the uninterrupted run's to the last bit.
#[test]
fn restart_after_sigkill_matches_the_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("golden.toml"), GOLDEN).unwrap();
    // Long enough (≈ 100 000 steps, several seconds) to be killed mid-run.
    let common = [
        "--no-record",
        "--set",
        "duration=0.25",
        "--checkpoint-every",
        "0.005",
    ];
    let out = scg(
        &[
            &["run", "golden.toml"][..],
            &common,
            &["--checkpoint", "full.ckpt"],
        ]
        .concat(),
        dir.path(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let full = read_checkpoint(&dir.path().join("full.ckpt")).unwrap();

    let mut child = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(
            [
                &["run", "golden.toml"][..],
                &common,
                &["--checkpoint", "k.ckpt"],
            ]
            .concat(),
        )
        .current_dir(dir.path())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let ckpt = dir.path().join("k.ckpt");
    let t0 = Instant::now();
    while !ckpt.exists() && t0.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(5));
    }
    std::thread::sleep(Duration::from_millis(200));
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let killed = read_checkpoint(&ckpt).unwrap();
    assert!(killed.step > 0);
    eprintln!(
        "killed; checkpoint at step {} of {}",
        killed.step, full.step
    );

    let out = scg(
        &[
            "run",
            "--restart",
            "k.ckpt",
            "--no-record",
            "--checkpoint-every",
            "0.005",
            "--checkpoint",
            "resumed.ckpt",
        ],
        dir.path(),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("restarting `golden`"), "{err}");
    let resumed = read_checkpoint(&dir.path().join("resumed.ckpt")).unwrap();
    assert_eq!(resumed.step, full.step);
    assert!(
        without_scene(resumed) == without_scene(full),
        "restarted run diverged"
    );
}

/// A checkpoint of a scene with relative paths (cases/cyclone.toml's CFD case), written
/// from the repository, restarts from another working folder: it keeps the scene file's
/// absolute path.
#[test]
fn restart_from_another_folder_finds_the_scenes_relative_paths() {
    let dir = tempfile::tempdir().unwrap();
    let ckpt = dir.path().join("c.ckpt");
    let ckpt_s = ckpt.display().to_string();
    let sets = ["--set", "duration=0.02", "--set", "feed_scale=0.25"];
    let out = scg(
        &[
            &["run", "cases/cyclone.toml", "--no-record"][..],
            &sets,
            &["--checkpoint-every", "0.02", "--checkpoint", &ckpt_s],
        ]
        .concat(),
        Path::new(env!("CARGO_MANIFEST_DIR")),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let c = read_checkpoint(&ckpt).unwrap();
    assert!(Path::new(&c.scene_file).is_absolute(), "{}", c.scene_file);
    let out = scg(
        &[
            "run",
            "--restart",
            "c.ckpt",
            "--no-record",
            "--set",
            "duration=0.04",
        ],
        dir.path(),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("restarting `cyclone`"), "{err}");
}

#[test]
fn damaged_checkpoints_are_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let c = run_to(&scene(&[]), None, 50);
    let good = dir.path().join("good.ckpt");
    let mut full = c.clone();
    full.scene = GOLDEN.to_string();
    full.scene_file = "golden.toml".into();
    write_checkpoint(&good, &full).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    for (name, data) in [
        ("empty.ckpt", Vec::new()),
        ("text.ckpt", b"hello".to_vec()),
        ("cut.ckpt", bytes[..bytes.len() / 2].to_vec()),
        ("tail.ckpt", [&bytes[..], b"x"].concat()),
    ] {
        std::fs::write(dir.path().join(name), &data).unwrap();
        let out = scg(&["run", "--restart", name, "--no-record"], dir.path());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains(name) && !err.contains("panicked"),
            "{name}: {err}"
        );
    }
    // The good one runs to the end.
    let out = scg(
        &["run", "--restart", "good.ckpt", "--no-record"],
        dir.path(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Every component of the particle layout (`spawn::visit_layout`) that is not scratch
/// comes back from a checkpoint bit for bit, column by column in table order: the recorded
/// state, the identity and what the spawn path derives again. A component added to the
/// layout as recorded but missing from the particle record fails here. The scene carries
/// every optional group: walls (force, torque, spin, wall history), gravity, a mesh flow
/// (cell hints) and a carrier modifier (offsets).
#[test]
fn every_component_of_the_layout_survives_a_checkpoint() {
    use scg::core::spawn::{LayoutVisitor, Role, visit_layout};
    let scene = scg::scene::parse(&common::cfd_box_scene(), "box.toml", "box", &[]).unwrap();
    let build = || {
        let mut cfg = scene.sim_config(false);
        cfg.carrier = Some(scg::core::stages::carrier::CarrierModifier::ConstantOffset(
            glam::DVec3::new(0.01, 0.0, 0.0),
        ));
        let mut sim = scg::core::Simulation::with_inlet_outlet(cfg, scene.inlet_outlet());
        for p in scene.initial_particles() {
            sim.spawn(&p);
        }
        sim
    };
    let mut a = build();
    a.run(scene.steps() / 2, |_| true).unwrap();
    let c = a.checkpoint();
    let mut b = build();
    b.restore(&c).unwrap();
    /// Each visited component's column (Debug text per row, in table order), or `None`
    /// when the particles do not carry it.
    struct Columns<'a>(
        &'a mut bevy_ecs::world::World,
        Vec<(Role, String, Option<Vec<String>>)>,
    );
    impl LayoutVisitor for Columns<'_> {
        fn visit<T: scg::core::spawn::LayoutComponent>(&mut self, role: Role) {
            let mut q = self.0.query::<&T>();
            let rows: Vec<String> = q.iter(self.0).map(|x| format!("{x:?}")).collect();
            let name = std::any::type_name::<T>().to_string();
            self.1
                .push((role, name, (!rows.is_empty()).then_some(rows)));
        }
    }
    let mut ca = Columns(&mut a.world, Vec::new());
    visit_layout(&mut ca);
    let (ca, mut cb) = (ca.1, Columns(&mut b.world, Vec::new()));
    visit_layout(&mut cb);
    let mut carried = 0;
    for ((role, name, x), (_, _, y)) in ca.iter().zip(&cb.1) {
        if *role == Role::Scratch {
            continue;
        }
        assert_eq!(x.is_some(), y.is_some(), "{name}");
        if let (Some(x), Some(y)) = (x, y) {
            assert!(x.len() > 10, "{name}: {} particles", x.len());
            assert_eq!(x, y, "{name} ({role:?}) after a restore");
            carried += 1;
        }
    }
    // Identity, state and derived columns of walls, gravity and the mesh all present,
    // the carrier offset among them (the dispersion's fluctuation is state: recorded).
    assert_eq!(carried, 17, "{ca:?}");
}
