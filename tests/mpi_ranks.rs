//! A run over N MPI ranks records the same bits as one rank (drag-only scenes: the
//! uniform and vortex cases, and the cyclone's feeders, mesh flow and outlet), for N = 2,
//! 3 and 4 (oversubscribed), with particles migrating between the slabs.
//!
//! Needs the MPI build: `cargo build --release --features mpi && cargo test --release
//! --features mpi --test mpi_ranks` (OpenMPI's `mpirun` on the PATH; `.ci/run` does this).
#![cfg(feature = "mpi")]

use std::path::{Path, PathBuf};
use std::process::Command;

use scg::core::frame::Frame;

fn scg_bin() -> &'static str {
    env!("CARGO_BIN_EXE_scg")
}

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// `scg` on `ranks` ranks through `mpirun --oversubscribe` (or alone when `mpirun` is
/// false), one thread per rank, allowed to run as root (mpirun refuses root without the
/// two variables; CI runs as root).
fn scg_cmd(ranks: usize, mpirun: bool) -> Command {
    let mut c = if mpirun {
        let mut c = Command::new("mpirun");
        c.args(["--oversubscribe", "-np", &ranks.to_string(), scg_bin()]);
        c
    } else {
        Command::new(scg_bin())
    };
    c.env("SCG_THREADS", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
    c
}

/// Run `scg run` on `ranks` ranks (1: without mpirun) into `out`; returns stderr. `axis`
/// is `SCG_MPI_AXIS`, or `ids` for `SCG_MPI_DECOMP=ids`.
fn run(ranks: usize, axis: &str, case: &str, set: &[&str], out: &Path) -> String {
    let mut args: Vec<String> = vec![
        "run".into(),
        repo(&format!("cases/{case}.toml")).display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ];
    for s in set {
        args.push("--set".into());
        args.push(s.to_string());
    }
    let o = scg_cmd(ranks, ranks > 1)
        .args(&args)
        .env("SCG_MPI_AXIS", axis)
        .env(
            "SCG_MPI_DECOMP",
            if axis == "ids" { "ids" } else { "slabs" },
        )
        .output()
        .expect("mpirun (OpenMPI) on the PATH");
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{ranks} ranks: {err}");
    err
}

/// FNV-1a over the bits of everything a frame holds.
fn digest(frames: &[Frame]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    let mut eat = |x: u64| h = (h ^ x).wrapping_mul(0x100000001b3);
    for f in frames {
        eat(f.step);
        eat(f.time.to_bits());
        eat(f.len() as u64);
        for i in 0..f.len() {
            eat(u64::from(f.id[i]));
            eat(u64::from(f.group[i]));
            for v in f.position[i].iter().chain(&f.velocity[i]) {
                eat(v.to_bits());
            }
            eat(f.diameter[i].to_bits());
            eat(f.density[i].to_bits());
        }
        for (k, v) in &f.stats {
            k.bytes().for_each(|b| eat(u64::from(b)));
            eat(v.to_bits());
        }
    }
    h
}

/// Particles migrated in, summed over the ranks (from the run's report).
fn migrated(report: &str) -> u64 {
    report
        .lines()
        .filter(|l| l.trim_start().starts_with("rank "))
        .filter_map(|l| l.split_whitespace().nth(6)?.parse::<u64>().ok())
        .sum()
}

/// The case on 1 rank and on each of `ranks`: the recorded frames have the same bits.
fn same_bits(case: &str, axis: &str, set: &[&str], ranks: &[usize]) {
    let dir = tempfile::tempdir().unwrap();
    let read = |d: &Path| {
        let rec = scg::record::read_mcap(&d.join(format!("{case}.mcap"))).unwrap();
        assert!(rec.complete);
        rec.frames
    };
    let one = dir.path().join("1");
    run(1, axis, case, set, &one);
    let reference = read(&one);
    assert!(reference.len() > 2, "{case}: {} frames", reference.len());
    assert!(reference.iter().any(|f| f.len() > 1));
    for &n in ranks {
        let out = dir.path().join(n.to_string());
        let report = run(n, axis, case, set, &out);
        let frames = read(&out);
        assert_eq!(frames.len(), reference.len(), "{case} on {n} ranks: frames");
        for (a, b) in frames.iter().zip(&reference) {
            assert_eq!(a.id, b.id, "{case} on {n} ranks: ids at step {}", b.step);
        }
        assert_eq!(
            digest(&frames),
            digest(&reference),
            "{case} on {n} ranks: the recorded bits differ from 1 rank's"
        );
        if axis == "ids" {
            assert!(report.contains("by id (no migration)"), "{report}");
            assert_eq!(migrated(&report), 0, "{report}");
        } else {
            assert!(
                migrated(&report) > 0,
                "{case} on {n} ranks: no particle migrated, the test shows nothing: {report}"
            );
        }
        assert!(out.join(format!("{case}.rrd")).is_file());
    }
}

#[test]
fn uniform_flow_is_bit_identical_on_2_3_4_ranks() {
    // Slabs along the flow: the particles start on one plane, so the slabs are cut again
    // (rebalanced) as they spread and migrate downstream.
    same_bits("uniform", "x", &["duration=0.5"], &[2, 3, 4]);
}

#[test]
fn vortex_is_bit_identical_on_2_3_4_ranks() {
    // Slabs across the vortex (x): the particles circle through them; walls carry their
    // contact history along.
    same_bits(
        "vortex",
        "x",
        &["duration=0.06", "dt=1e-5", "record_every=200"],
        &[2, 3, 4],
    );
}

#[test]
fn cyclone_feeders_and_mesh_flow_are_bit_identical_on_3_ranks() {
    // Fed particles (drawn on every rank, kept by their slab's), CFD mesh cells, outlet.
    same_bits("cyclone", "z", &["duration=0.2"], &[3]);
}

#[test]
fn cyclone_shared_by_id_is_bit_identical_on_2_and_4_ranks() {
    // `SCG_MPI_DECOMP=ids`: fed particles kept by the rank their id hashes to.
    same_bits("cyclone", "ids", &["duration=0.2"], &[2, 4]);
}

#[test]
fn replay_verifies_a_2_rank_recording() {
    let dir = tempfile::tempdir().unwrap();
    run(2, "x", "uniform", &["duration=0.3"], dir.path());
    let o = Command::new(scg_bin())
        .args(["replay", "--verify"])
        .arg(dir.path().join("uniform.mcap"))
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}");
    assert!(out.contains("frames bit-identical"), "{out}");
}

#[test]
fn contacts_are_refused_on_several_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let o = scg_cmd(2, true)
        .arg("run")
        .arg(repo("cases/classifier.toml"))
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("particle contacts are not yet decomposed"),
        "{err}"
    );
}

/// The per-step log of `SCG_MPI_COUNTS` (step, count, id digest) of a run on `ranks`
/// ranks (through mpirun even for 1), and its report.
fn counts(ranks: usize, axis: &str, case: &str, set: &[&str], log: &Path) -> (String, String) {
    let mut cmd = scg_cmd(ranks, true);
    cmd.arg("run")
        .arg(repo(&format!("cases/{case}.toml")))
        .arg("--no-record");
    for s in set {
        cmd.args(["--set", s]);
    }
    let o = cmd
        .env("SCG_MPI_AXIS", axis)
        .env("SCG_MPI_COUNTS", log)
        .output()
        .expect("mpirun (OpenMPI) on the PATH");
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{ranks} ranks: {err}");
    (std::fs::read_to_string(log).unwrap(), err)
}

#[test]
fn no_particle_lost_or_duplicated_over_10k_cyclone_steps_on_4_ranks() {
    // 10^4 steps of the cyclone (fed for 1 s, drained through the outlet and lost through
    // the inlet), slabs along its axis and cut again as the particles descend: after
    // every step the count and an id digest over all ranks equal one rank's.
    let dir = tempfile::tempdir().unwrap();
    let set = [
        "duration=2.0",
        "feeders.0.rate=100",
        "feeders.1.rate=100",
        "feeders.2.rate=100",
        "feeders.3.rate=100",
    ];
    let (one, _) = counts(1, "z", "cyclone", &set, &dir.path().join("1.txt"));
    let (four, report) = counts(4, "z", "cyclone", &set, &dir.path().join("4.txt"));
    let one: Vec<&str> = one.lines().collect();
    let four: Vec<&str> = four.lines().collect();
    assert_eq!(one.len(), 10_000);
    assert_eq!(four.len(), one.len());
    for (a, b) in four.iter().zip(&one) {
        assert_eq!(a, b, "step, count, id digest on 4 ranks vs 1");
    }
    let peak = one
        .iter()
        .filter_map(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        .max()
        .unwrap();
    let last: u64 = one[one.len() - 1]
        .split_whitespace()
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!(peak > 300 && last < peak, "fed {peak}, left {last}");
    let rebalances: u64 = report
        .split("particle-steps/s, ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0);
    assert!(rebalances > 0, "no rebalance: {report}");
    assert!(migrated(&report) > 0, "{report}");
}
