//! The command line itself: help text and the thread option.

use std::process::Command;

fn scg() -> Command {
    Command::new(env!("CARGO_BIN_EXE_scg"))
}

#[test]
fn help_describes_the_tool_and_shows_examples() {
    let out = scg().arg("--help").output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("simpler"), "{text}");
    assert!(text.contains("Kushimoto"), "{text}");
    assert!(
        text.contains("Examples:") && text.contains("scg run"),
        "{text}"
    );
    assert!(text.contains("--threads"), "{text}");
}

/// `SCG_PORTABLE=1` forces the portable kernels (the CI leg that checks their bits runs
/// with it); without it a CPU with AVX2 runs the four-lane ones.
#[test]
fn portable_switch_forces_the_portable_kernels() {
    let run = |portable: Option<&str>| {
        let mut c = scg();
        c.args(["bench", "drag", "--particles", "1000", "--steps", "5"]);
        c.env_remove("SCG_PORTABLE");
        if let Some(v) = portable {
            c.env("SCG_PORTABLE", v);
        }
        let out = c.output().unwrap();
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    assert!(
        run(Some("1")).contains("; portable kernels)"),
        "{}",
        run(Some("1"))
    );
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        assert!(
            run(None).contains("four-lane AVX2 kernels"),
            "{}",
            run(None)
        );
    }
}

#[test]
fn threads_option_sets_the_team_and_overrides_the_environment() {
    for (arg, env, want) in [("1", "2", "on 1 threads"), ("2", "1", "on 2 threads")] {
        let out = scg()
            .args(["--threads", arg, "bench", "drag", "--particles", "1000"])
            .args(["--steps", "5"])
            .env("SCG_THREADS", env)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{text}");
        // A machine with one core runs one thread whatever is asked.
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        if cores >= 2 {
            assert!(text.contains(want), "--threads {arg}: {text}");
        }
    }
}

#[test]
fn coarse_grained_variants_get_their_own_recordings() {
    let dir = tempfile::tempdir().unwrap();
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/classifier.toml");
    for extra in [
        &[][..],
        &["--set", "coarse_grain.alpha=2"][..],
        &[
            "--set",
            "coarse_grain.alpha=2",
            "--set",
            "coarse_grain.law=none",
        ][..],
    ] {
        let out = scg()
            .args(["run", case, "--out"])
            .arg(dir.path())
            .args(["--set", "duration=2e-5"])
            .args(extra)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    for stem in ["classifier", "classifier-scg-a2", "classifier-none-a2"] {
        for ext in ["rrd", "mcap"] {
            let f = dir.path().join(format!("{stem}.{ext}"));
            assert!(f.is_file(), "{} missing", f.display());
        }
    }
}

#[test]
fn summary_json_accounts_for_every_particle_fed() {
    // The cyclone with inlet-patch feeders (cases/cyclone/vs-openfoam.sh reads this file):
    // 0.3 s, 120 particles per group, some go back out (lost) near the inlet.
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("summary.json");
    let case = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/cyclone/fixture-patch-feeders.toml"
    );
    let out = scg()
        .args(["--threads", "1", "run", case, "--no-record"])
        .args(["--set", "duration=0.3", "--summary-json"])
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(s["code"], "scg");
    assert_eq!(s["steps"], 1500);
    assert_eq!(s["threads"], 1);
    let groups = s["groups"].as_array().unwrap();
    let names: Vec<&str> = groups
        .iter()
        .map(|g| g["group"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["d2", "d5", "d10", "d20"]);
    let mut held = 0;
    for g in groups {
        let n = |k: &str| g[k].as_u64().unwrap();
        // ⌊400/s · 0.3 s⌋ fed, each drained, lost or still in the cyclone
        assert_eq!(n("fed"), 120, "{g}");
        assert_eq!(n("drained") + n("lost") + n("held"), n("fed"), "{g}");
        assert_eq!(g["lost_times"].as_array().unwrap().len() as u64, n("lost"));
        assert_eq!(
            g["drained_times"].as_array().unwrap().len() as u64,
            n("drained")
        );
        for t in g["lost_times"].as_array().unwrap() {
            assert!((0.0..=0.3).contains(&t.as_f64().unwrap()), "{g}");
        }
        held += n("held");
    }
    assert_eq!(groups[2]["diameter"], 1e-5);
    assert_eq!(groups[2]["density"], 2000.0);
    // the particle-steps: at least the particles held at the end, once each
    let ps = s["particle_steps"].as_u64().unwrap();
    assert!(ps > held && ps < 480 * 1500, "{ps}");
    let rate = s["particle_steps_per_s"].as_f64().unwrap();
    let wall = s["wall_s"].as_f64().unwrap();
    assert!((rate * wall - ps as f64).abs() < 1e-6 * ps as f64);
}

/// `scg bench neighbours` builds both clouds on the grids meant for them and ends with its
/// rate; it takes no `--scene-out`.
#[test]
fn neighbours_benchmark_names_its_grids() {
    let out = scg()
        .args([
            "bench",
            "neighbours",
            "--particles",
            "20000",
            "--steps",
            "1",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let lines: Vec<&str> = text.lines().collect();
    assert!(
        lines[0].starts_with("spread: 20000") && lines[0].contains("Coarse grid"),
        "{text}"
    );
    assert!(
        lines[1].starts_with("clustered: 20000") && lines[1].contains("Hashed grid"),
        "{text}"
    );
    assert!(
        lines[2].starts_with("packed: 20000") && lines[2].contains("Dense grid"),
        "{text}"
    );
    let rate: f64 = lines[3]
        .strip_prefix("particle-builds/s: ")
        .and_then(|r| r.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    assert!(rate > 0.0, "{text}");
    let out = scg()
        .args(["bench", "neighbours", "--scene-out", "x.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// `scg bench case SCENE` runs the scene (here the elbow, shortened with `--set`) and
/// prints each system of its step with its time, the shares adding up to the step's
/// whole, and the rate last; a missing scene is bad input.
#[test]
fn bench_case_times_each_system_of_a_scene() {
    let out = scg()
        .args(["--threads", "1", "bench", "case", "cases/elbow.toml"])
        .args(["--set", "duration=0.005"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("bench case cases/elbow.toml: 200 steps"),
        "{text}"
    );
    let shares: Vec<f64> = text
        .lines()
        .filter(|l| l.ends_with('%'))
        .map(|l| l.split_whitespace().rev().nth(1).unwrap().parse().unwrap())
        .collect();
    // the dispersion runs inside the mesh move: no pass of its own
    assert!(!text.contains("modify_carrier"), "{text}");
    for name in [
        "integrate_mesh_flow",
        "mesh_flow + dispersion:stochastic_ras",
        "feed_particles",
        "mesh_boundary",
    ] {
        assert!(text.contains(name), "{name}: {text}");
    }
    let sum: f64 = shares.iter().sum();
    assert!((sum - 100.0).abs() < 0.5, "shares sum to {sum}: {text}");
    let last = text.lines().last().unwrap();
    let rate: f64 = last
        .strip_prefix("particle-steps/s: ")
        .unwrap()
        .parse()
        .unwrap();
    assert!(rate > 0.0, "{last}");
    let bad = scg().args(["bench", "case"]).output().unwrap();
    assert_eq!(bad.status.code(), Some(2));
}

/// `scg bench mesh --shape hex|tet` builds the box of that cell shape, says how much the
/// tracker's records take per cell (hexahedra: 24 tetrahedra each, several kB; tetrahedra
/// under one) and ends with its rate.
#[test]
fn mesh_benchmark_builds_hexahedra_or_tetrahedra() {
    let kb = |shape: &str| -> (String, f64) {
        let out = scg()
            .args(["bench", "mesh", "--shape", shape, "--cells", "2000"])
            .args(["--particles", "500", "--steps", "2"])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(out.status.success(), "{text}");
        let line = text.lines().find(|l| l.starts_with("mesh: ")).unwrap();
        let at = line
            .find(" kB per cell")
            .unwrap_or_else(|| panic!("{line}"));
        let per_cell: f64 = line[..at].rsplit('(').next().unwrap().parse().unwrap();
        assert!(
            text.lines()
                .last()
                .unwrap()
                .starts_with("particle-steps/s: ")
        );
        (line.to_string(), per_cell)
    };
    let (hex, hex_kb) = kb("hex");
    let (tet, tet_kb) = kb("tet");
    assert!(
        hex.contains("Hex cells") && tet.contains("Tet cells"),
        "{hex}\n{tet}"
    );
    assert!(hex_kb > 2.0 && tet_kb < 1.0, "{hex}\n{tet}");
}
