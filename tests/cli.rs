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
