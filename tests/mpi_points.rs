//! `scg cost` and `scg study` spread their independent points over MPI ranks: on 2 ranks
//! they write the same numbers as on one (timings aside), whichever rank ran a point.
//!
//! Needs the MPI build: `cargo build --release --features mpi && cargo test --release
//! --features mpi --test mpi_points` (OpenMPI's `mpirun` on the PATH; `.ci/run` does
//! this). Some 30 s on 2 loaded cores.
#![cfg(feature = "mpi")]

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// `scg` on `ranks` ranks through `mpirun --oversubscribe` (or alone when `mpirun` is
/// false), one thread per rank, allowed to run as root.
fn scg_cmd(ranks: usize, mpirun: bool) -> Command {
    let mut c = if mpirun {
        let mut c = Command::new("mpirun");
        c.args([
            "--oversubscribe",
            "-np",
            &ranks.to_string(),
            env!("CARGO_BIN_EXE_scg"),
        ]);
        c
    } else {
        Command::new(env!("CARGO_BIN_EXE_scg"))
    };
    c.env("SCG_THREADS", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
    c
}

/// `scg <args>` on `ranks` ranks (1: without mpirun), one thread per rank; returns stderr.
fn scg_on(ranks: usize, args: &[String]) -> String {
    let o = scg_cmd(ranks, ranks > 1)
        .args(args)
        .output()
        .expect("mpirun (OpenMPI) on the PATH");
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{ranks} ranks: {err}");
    err
}

/// The columns of a `cost.csv` that are not timings, row by row.
fn cost_numbers(dir: &Path) -> Vec<Vec<String>> {
    let csv = std::fs::read_to_string(dir.join("cost.csv")).unwrap();
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let timing = |h: &str| {
        h.starts_with("t_")
            || h.starts_with("wall")
            || h.contains("speedup")
            || ["particle_steps_per_s", "pareto"].contains(&h)
    };
    let keep: Vec<usize> = (0..head.len()).filter(|&i| !timing(head[i])).collect();
    assert!(keep.len() >= 10, "{head:?}");
    csv.lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| f[i].to_string()).collect()
        })
        .collect()
}

/// `scg cost CASE --quick ARGS` on 1 rank and on 2: the same points with the same
/// numbers (timings aside), and rank 0 wrote every file.
fn cost_same_on_2_ranks(case: &str, args: &[&str]) -> Vec<Vec<String>> {
    let dir = tempfile::tempdir().unwrap();
    let cost = |ranks: usize| {
        let out = dir.path().join(ranks.to_string());
        let mut a: Vec<String> = vec![
            "cost".into(),
            repo(&format!("cases/{case}.toml")).display().to_string(),
            "--quick".into(),
            "--out".into(),
            out.display().to_string(),
        ];
        a.extend(args.iter().map(|s| s.to_string()));
        let err = scg_on(ranks, &a);
        for f in ["cost.md", "cost.csv", "cost.svg"] {
            assert!(out.join(f).is_file(), "{ranks} ranks: no {f}: {err}");
        }
        (cost_numbers(&out), err)
    };
    let (one, _) = cost(1);
    let (two, err) = cost(2);
    assert!(err.contains("spread over 2 processes"), "{err}");
    assert!(one.len() > 3, "{one:?}");
    assert_eq!(two, one, "{case}: cost.csv on 2 ranks vs 1 (timings aside)");
    one
}

#[test]
fn cost_points_spread_over_2_ranks_give_the_same_numbers() {
    // Single-particle scene: populations and trajectory errors.
    let rows = cost_same_on_2_ranks("uniform", &[]);
    let err = rows[0].iter().position(|h| h == "error").unwrap();
    assert!(
        rows[1..]
            .iter()
            .any(|r| r[err].parse::<f64>().unwrap() > 0.1),
        "no point with an error: the comparison shows little"
    );
    // Classifier scene: per-class W1 and d50 from the analysis travelling between ranks.
    let rows = cost_same_on_2_ranks(
        "classifier",
        &[
            "--alphas",
            "1,2",
            "--laws",
            "scg,none",
            "--set",
            "feed_scale=0.004",
        ],
    );
    let w1 = rows[0].iter().position(|h| h == "w1_per_class").unwrap();
    assert!(
        rows[1..].iter().any(|r| r[w1]
            .split(';')
            .any(|x| x.parse::<f64>().is_ok_and(|x| x > 1e-3))),
        "{rows:?}"
    );
}

/// A study's `summary.json` without its wall and CPU times (and what is derived from
/// them: rates, time ratios, the criteria on times).
fn summary_numbers(dir: &Path) -> serde_json::Value {
    fn timing(k: &str) -> bool {
        ["time_s", "total_s", "cpu_s", "particle_steps_per_s"].contains(&k)
            || k.ends_with("_ratio_to_original")
    }
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.retain(|k, _| !timing(k));
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => {
                a.retain(|c| !c["what"].as_str().is_some_and(|w| w.contains(" time")));
                a.iter_mut().for_each(strip);
            }
            _ => {}
        }
    }
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    strip(&mut v);
    v
}

#[test]
fn study_variants_spread_over_2_ranks_give_the_same_outputs() {
    // The classifier study at a tiny feed (some 10 s): the three variants on 2 ranks
    // (the original alone on rank 0, both α = 2 on rank 1).
    let dir = tempfile::tempdir().unwrap();
    let study = |ranks: usize| {
        let out = dir.path().join(ranks.to_string());
        let a: Vec<String> = [
            "study",
            "classifier",
            "--quick",
            "--no-record",
            "--set",
            "feed_scale=0.001",
            "--out",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain([out.display().to_string()])
        .collect();
        scg_on(ranks, &a);
        out
    };
    let one = study(1);
    let two = study(2);
    let s = summary_numbers(&one);
    assert!(
        s["variants"]["original"]["fates_decided"].as_u64().unwrap() > 10,
        "{s}"
    );
    assert_eq!(summary_numbers(&two), s, "summary.json on 2 ranks vs 1");
    for f in ["w1.csv", "partition.csv", "radial.csv"] {
        let read = |d: &Path| std::fs::read_to_string(d.join(f)).unwrap();
        assert_eq!(read(&two), read(&one), "{f} on 2 ranks vs 1");
    }
    assert!(two.join("report.txt").is_file() && two.join("radial.svg").is_file());
}

#[test]
fn cyclone_study_variants_spread_over_2_ranks_give_the_same_outputs() {
    // Three variants of the cyclone study, shortened and at a tenth of the quick feed
    // (a few seconds): grade.csv and summary.json equal one rank's, times aside.
    let dir = tempfile::tempdir().unwrap();
    let study = |ranks: usize| {
        let out = dir.path().join(ranks.to_string());
        let a: Vec<String> = [
            "study",
            "cyclone",
            "--quick",
            "--no-record",
            "--run",
            "original,scg2,none2",
            "--set",
            "duration=1.2",
            "--set",
            "feed_scale=0.1",
            "--out",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain([out.display().to_string()])
        .collect();
        let mut c = scg_cmd(ranks, ranks > 1);
        let o = c
            .args(&a)
            .env("SCG_CASES", repo("cases"))
            .output()
            .expect("mpirun (OpenMPI) on the PATH");
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{ranks} ranks: {err}");
        out
    };
    let one = study(1);
    let two = study(2);
    let s = summary_numbers(&one);
    let fed: u64 = s["variants"]["original"]["classes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["fed"].as_u64().unwrap())
        .sum();
    assert!(fed > 100, "{s}");
    assert_eq!(summary_numbers(&two), s, "summary.json on 2 ranks vs 1");
    let read = |d: &Path| std::fs::read_to_string(d.join("grade.csv")).unwrap();
    assert_eq!(read(&two), read(&one), "grade.csv on 2 ranks vs 1");
}
