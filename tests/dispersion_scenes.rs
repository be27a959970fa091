//! `[dispersion]` in scene files: the CFD's turbulence fields on the cyclone's mesh
//! (k and ω, ε = 0.09·k·ω), and bad input named by file, key and line.
//!
//! Run: `cargo test --release --test dispersion_scenes`.

use std::path::Path;

/// cases/cyclone.toml without its own `[dispersion]` table, with `section` appended.
fn cyclone_with(section: &str) -> Result<scg::scene::Scene, scg::scene::SceneError> {
    let full = std::fs::read_to_string("cases/cyclone.toml").unwrap();
    let start = full
        .find("\n[dispersion]\n")
        .expect("the scene's [dispersion]");
    let end = start + 1 + full[start + 1..].find("\n\n").unwrap();
    let text = format!("{}{}", &full[..start], &full[end..]);
    scg::scene::parse_in(
        &format!("{text}\n{section}\n"),
        "cases/cyclone.toml",
        Path::new("cases"),
        "cyclone",
        &["duration=0.02".into(), "feed_scale=20".into()],
    )
}

/// The committed coarse cyclone carries kMean and omegaMean: a scene reads them, every
/// particle gets a fluctuation within a few eddy lifetimes of its entry (the cells' k/ε
/// are 6–190 ms, the check says), and a run's fluctuations are of the size √(2k/3) says.
#[test]
fn the_cyclone_reads_its_turbulence_fields() {
    let scene = cyclone_with(
        "[dispersion]\nmodel = \"stochastic_ras\"\nk = \"kMean\"\nomega = \"omegaMean\"",
    )
    .unwrap();
    let d = scene.dispersion.as_ref().unwrap();
    assert!(
        scene.dispersion_source.contains("0.09·k·ω"),
        "{}",
        scene.dispersion_source
    );
    let scg::core::physics::dispersion::Turbulence::Cells(c) = &d.turbulence else {
        panic!("cell turbulence expected");
    };
    assert_eq!(
        c.k.len(),
        scene.mesh_flow.as_ref().unwrap().flow.mesh().n_cells
    );
    let kmax = c.k.iter().cloned().fold(0.0, f64::max);
    assert!(kmax > 1.0 && kmax < 100.0, "k max {kmax}");
    assert!(c.epsilon.iter().all(|e| *e > 0.0));
    // A short run with the scene's feeders against the same run without dispersion:
    // the particles fed more than one eddy lifetime (≥ 6 ms) ago have left the mean
    // path, by less than the largest fluctuation times the time.
    let run = |scene: &scg::scene::Scene| {
        let mut sim = scene.build(false);
        sim.run(100, |_| true).unwrap(); // 20 ms
        let plan = sim.plan().render();
        (sim.particles(), plan)
    };
    let (with, plan) = run(&scene);
    assert!(
        plan.contains("mesh_flow + dispersion:stochastic_ras") && !plan.contains("modify_carrier"),
        "the dispersion runs inside the mesh move: {plan}"
    );
    let plain = cyclone_with("").unwrap();
    let (without, plan) = run(&plain);
    assert!(!plan.contains("dispersion"), "{plan}");
    assert_eq!(with.len(), without.len());
    assert!(!with.is_empty());
    let moved = with
        .iter()
        .zip(&without)
        .filter(|(a, b)| a.position != b.position)
        .count();
    assert!(moved > 0, "dispersion moved nobody");
}

/// Both models (the Langevin walk with and without Csanady's correction) inside the mesh
/// move give the bits of their own pass: 100 steps of the
/// cyclone's feed, every particle's position and velocity equal.
#[test]
fn the_fused_dispersion_gives_the_bits_of_its_own_pass() {
    let mut runs = Vec::new();
    for model in [
        "stochastic_ras\"",
        "langevin\"\nc0 = 2.1",
        "langevin\"\nc0 = 2.1\ncsanady = 1.0",
    ] {
        let section =
            format!("[dispersion]\nk = \"kMean\"\nomega = \"omegaMean\"\nmodel = \"{model}");
        let run = |own_pass: bool| {
            let mut scene = cyclone_with(&section).unwrap();
            scene.dispersion.as_mut().unwrap().own_pass = own_pass;
            let mut sim = scene.build(false);
            sim.run(100, |_| true).unwrap();
            (sim.particles(), sim.plan().render())
        };
        let (fused, plan) = run(false);
        assert!(!plan.contains("modify_carrier"), "{plan}");
        let (own, plan) = run(true);
        assert!(plan.contains("modify_carrier"), "{plan}");
        assert!(fused.len() > 10, "{model}: {} particles", fused.len());
        assert_eq!(fused.len(), own.len());
        for (a, b) in fused.iter().zip(&own) {
            assert_eq!(a.position, b.position, "{model}");
            assert_eq!(a.velocity, b.velocity, "{model}");
        }
        runs.push(fused);
    }
    // the correction is wired through: the particles' slip shortens their walk's time
    let moved = runs[1]
        .iter()
        .zip(&runs[2])
        .filter(|(a, b)| a.position != b.position);
    assert!(moved.count() > 0, "csanady changed nothing");
}

fn err(section: &str) -> String {
    cyclone_with(section).unwrap_err().to_string()
}

/// Bad input is an error naming the file, the key (with its line) and the value.
#[test]
fn bad_dispersion_input_names_file_key_and_line() {
    let e = err("[dispersion]\nmodel = \"eddy_walk\"\nk = \"k\"\nomega = \"omega\"");
    assert!(
        e.contains("cases/cyclone.toml:") && e.contains("eddy_walk"),
        "{e}"
    );
    assert!(
        e.contains("stochastic_ras") && e.contains("langevin"),
        "{e}"
    );
    let e = err("[dispersion]\nmodel = \"stochastic_ras\"\nk = \"kk\"\nomega = \"omega\"");
    assert!(e.contains("dispersion.k") && e.contains("kk"), "{e}");
    let e = err("[dispersion]\nmodel = \"stochastic_ras\"\nk = \"k\"");
    assert!(
        e.contains("dispersion.epsilon") && e.contains("missing"),
        "{e}"
    );
    let e = err("[dispersion]\nmodel = \"stochastic_ras\"\nk = 1.0\nomega = \"omega\"");
    assert!(e.contains("dispersion.k") && e.contains("field"), "{e}");
    let e = err("[dispersion]\nmodel = \"stochastic_ras\"\nk = \"k\"\nomega = \"omega\"\nc0 = 2");
    assert!(e.contains("dispersion.c0"), "{e}");
    let e =
        err("[dispersion]\nmodel = \"stochastic_ras\"\nk = \"k\"\nomega = \"omega\"\ncsanady = 1");
    assert!(
        e.contains("dispersion.csanady") && e.contains("langevin"),
        "{e}"
    );
    let e = err(
        "[dispersion]\nmodel = \"langevin\"\nc0 = 2.1\nk = \"k\"\nomega = \"omega\"\ncsanady = -1",
    );
    assert!(e.contains("dispersion.csanady"), "{e}");
    let e = err("[dispersion]\nmodel = \"langevin\"\nk = \"k\"\nomega = \"omega\"\nsmoothing = 1");
    assert!(e.contains("smoothing"), "{e}");
}

/// Analytic flows: numbers or a profile; a negative or non-finite k, or a field name,
/// is refused with its key.
#[test]
fn analytic_flows_take_numbers_or_a_profile() {
    let base = std::fs::read_to_string("cases/uniform.toml").unwrap();
    let parse = |s: &str| {
        scg::scene::parse_in(
            &format!("{base}\n{s}\n"),
            "cases/uniform.toml",
            Path::new("cases"),
            "u",
            &[],
        )
    };
    let ok = parse("[dispersion]\nmodel = \"langevin\"\nc0 = 2.1\nk = 0.5\nepsilon = 2.0").unwrap();
    assert!(ok.dispersion.is_some());
    let ok = parse(
        "[dispersion]\nmodel = \"stochastic_ras\"\n[dispersion.profile]\naxis = \"y\"\nat = [0, 1]\nk = [0.1, 0.2]\nomega = [10, 20]",
    )
    .unwrap();
    assert!(
        ok.dispersion_source.contains("ω"),
        "{}",
        ok.dispersion_source
    );
    // C₀ is stated: no value is right for every field
    let e = parse("[dispersion]\nmodel = \"langevin\"\nk = 0.5\nepsilon = 2.0")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("dispersion.c0") && e.contains("8.9") && e.contains("2.1"),
        "{e}"
    );
    for (s, key) in [
        (
            "[dispersion]\nmodel = \"langevin\"\nc0 = 2.1\nk = -0.5\nepsilon = 2.0",
            "dispersion.k",
        ),
        (
            "[dispersion]\nmodel = \"langevin\"\nc0 = 2.1\nk = nan\nepsilon = 2.0",
            "dispersion.k",
        ),
        (
            "[dispersion]\nmodel = \"langevin\"\nc0 = 2.1\nk = \"k\"\nepsilon = 2.0",
            "dispersion.k",
        ),
        (
            "[dispersion]\nmodel = \"langevin\"\nc0 = 2.1\nk = 0.5\nepsilon = 0.0",
            "dispersion.epsilon",
        ),
        (
            "[dispersion]\nmodel = \"langevin\"\nc0 = 2.1\n[dispersion.profile]\naxis = \"w\"\nat = [0, 1]\nk = [1, 1]\nepsilon = [1, 1]",
            "dispersion.profile.axis",
        ),
        (
            "[dispersion]\nmodel = \"langevin\"\nc0 = 2.1\n[dispersion.profile]\naxis = \"x\"\nat = [1, 0]\nk = [1, 1]\nepsilon = [1, 1]",
            "dispersion.profile.at",
        ),
    ] {
        let e = parse(s).unwrap_err().to_string();
        assert!(
            e.contains(key) && e.contains("cases/uniform.toml"),
            "{s}: {e}"
        );
    }
}
