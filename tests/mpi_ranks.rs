//! A run over N MPI ranks records the same bits as one rank (drag-only scenes: the
//! uniform and vortex cases, and the cyclone's feeders, mesh flow and outlet), for N = 2,
//! 3 and 4 (oversubscribed), with particles migrating between the slabs; a checkpoint
//! written over ranks restarts on another number of ranks as the uninterrupted run goes on.
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

/// The environment of a decomposition named `how`: `x`, `y` or `z` slabs along that axis
/// (`SCG_MPI_AXIS`), else `SCG_MPI_DECOMP` (`auto`, `slabs`, `bisection`, `ids`).
fn decomposed<'c>(cmd: &'c mut Command, how: &str) -> &'c mut Command {
    match how {
        "x" | "y" | "z" => cmd.env("SCG_MPI_AXIS", how).env("SCG_MPI_DECOMP", "slabs"),
        _ => cmd.env_remove("SCG_MPI_AXIS").env("SCG_MPI_DECOMP", how),
    }
}

/// Run `scg run` on `ranks` ranks (1: without mpirun) into `out`; returns stderr. `axis`
/// is the decomposition ([`decomposed`]).
fn run(ranks: usize, axis: &str, case: &str, set: &[&str], out: &Path) -> String {
    run_file(ranks, axis, &format!("cases/{case}.toml"), set, out)
}

/// [`run`] of the scene file `file` (relative to the repository).
fn run_file(ranks: usize, axis: &str, file: &str, set: &[&str], out: &Path) -> String {
    let mut args: Vec<String> = vec![
        "run".into(),
        repo(file).display().to_string(),
        "--out".into(),
        out.display().to_string(),
    ];
    for s in set {
        args.push("--set".into());
        args.push(s.to_string());
    }
    let o = decomposed(scg_cmd(ranks, ranks > 1).args(&args), axis)
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
        .filter_map(|l| l.split_whitespace().nth(7)?.parse::<u64>().ok())
        .sum()
}

/// The frames of the complete recording `<dir>/<stem>….mcap`: the one recording of a run
/// in `dir`, whose name adds the `--set` overrides that change the run to the stem
/// (`scg::cli::run::set_suffix`).
fn read_frames(dir: &Path, stem: &str) -> Vec<Frame> {
    let mut found: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension().is_some_and(|x| x == "mcap")
                && p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with(stem))
        })
        .collect();
    assert_eq!(
        found.len(),
        1,
        "{stem}: recordings in {}: {found:?}",
        dir.display()
    );
    let rec = scg::record::read_mcap(&found.pop().unwrap()).unwrap();
    assert!(rec.complete);
    rec.frames
}

/// The case on 1 rank and on each of `ranks`: the recorded frames have the same bits.
fn same_bits(case: &str, axis: &str, set: &[&str], ranks: &[usize]) {
    let dir = tempfile::tempdir().unwrap();
    let read = |d: &Path| read_frames(d, case);
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
        let sets: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        let stem = format!("{case}{}", scg::cli::run::set_suffix(&sets));
        assert!(out.join(format!("{stem}.rrd")).is_file(), "{stem}.rrd");
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
fn cyclone_in_bisection_boxes_is_bit_identical_on_4_ranks() {
    // Boxes by recursive bisection, cut again as the fed particles spread (they start
    // on nobody's): the particles swirl through the boxes.
    same_bits("cyclone", "bisection", &["duration=0.2"], &[4]);
}

#[test]
fn cyclone_shared_by_id_is_bit_identical_on_2_and_4_ranks() {
    // `SCG_MPI_DECOMP=ids`: fed particles kept by the rank their id hashes to.
    same_bits("cyclone", "ids", &["duration=0.2"], &[2, 4]);
}

/// `--per-rank` on 4 ranks: each rank writes its own particles of every frame and rank 0
/// the index; read through the index the set is one rank's recording to the bit (the
/// cyclone: fed particles, mesh flow, drained counts summed over the parts), no part
/// holds a whole frame, and `scg replay --verify` passes on the index (re-running the
/// scene on one rank against the merged frames) and `--vtk` writes its frames.
#[test]
fn a_4_rank_recording_written_per_rank_replays_and_verifies_as_one() {
    let dir = tempfile::tempdir().unwrap();
    let (one, four) = (dir.path().join("1"), dir.path().join("4"));
    let set = ["duration=0.2".to_string()];
    let stem = format!("cyclone{}", scg::cli::run::set_suffix(&set));
    run(1, "z", "cyclone", &["duration=0.2"], &one);
    let reference = read_frames(&one, "cyclone");
    let mut args: Vec<String> = vec![
        repo("cases/cyclone.toml").display().to_string(),
        "--out".into(),
        four.display().to_string(),
        "--per-rank".into(),
    ];
    args.extend(["--set".to_string(), set[0].clone()]);
    let report = run_args(4, "z", &args);
    assert!(migrated(&report) > 0, "{report}");
    assert!(!four.join(format!("{stem}.rrd")).exists(), "a whole .rrd");
    let index = four.join(format!("{stem}.mcap"));
    let rec = scg::record::read_mcap(&index).unwrap();
    assert!(rec.complete);
    assert_eq!(rec.meta.parts.len(), 4);
    assert_eq!(rec.frames.len(), reference.len());
    assert_eq!(
        digest(&rec.frames),
        digest(&reference),
        "the merged parts differ from 1 rank's recording"
    );
    let last = reference.last().unwrap();
    assert!(
        last.len() > 100,
        "{} particles: the test shows little",
        last.len()
    );
    let mut held = 0;
    for k in 0..4 {
        let part = scg::record::read_mcap(&four.join(format!("{stem}.rank{k}.mcap"))).unwrap();
        let n = part.frames.last().unwrap().len();
        assert!(n < last.len(), "rank {k} holds the whole frame");
        held += n;
    }
    assert_eq!(held, last.len());
    let vtk = dir.path().join("vtk");
    let o = Command::new(scg_bin())
        .args(["replay", "--verify", "--vtk"])
        .arg(&vtk)
        .arg(&index)
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.contains("frames bit-identical"), "{out}");
    let vtus = std::fs::read_dir(&vtk)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "vtu"))
        })
        .count();
    assert!(vtus >= reference.len(), "{vtus} VTK files");
}

/// `scg run ARGS…` on `ranks` ranks (1: without mpirun), decomposed as `axis` says
/// ([`decomposed`]); returns stderr.
fn run_args(ranks: usize, axis: &str, args: &[String]) -> String {
    let o = decomposed(scg_cmd(ranks, ranks > 1).arg("run").args(args), axis)
        .output()
        .expect("mpirun (OpenMPI) on the PATH");
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{ranks} ranks: {err}");
    err
}

/// A checkpoint written over ranks restarts on another number of ranks as the
/// uninterrupted run goes on: the squareBend duct (fed particles, mesh flow, patch logs;
/// two thirds of the finest class drained by the checkpoint) checkpointed halfway on 3
/// ranks and finished on 2, and checkpointed on 2 and finished on 1 (the single-rank
/// path, the same file format), record 1 rank's uninterrupted bits from the restart on.
#[test]
fn checkpoints_restart_on_another_number_of_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let one = dir.path().join("1");
    run(1, "auto", "squarebend", &["duration=0.2"], &one);
    let reference = read_frames(&one, "squarebend");
    let case = repo("cases/squarebend.toml").display().to_string();
    for (first, then) in [(3, 2), (2, 1)] {
        let a = dir.path().join(format!("{first}-{then}-a"));
        let b = dir.path().join(format!("{first}-{then}-b"));
        let ckpt = a.join("half.ckpt").display().to_string();
        let report = run_args(
            first,
            "auto",
            &[
                case.clone(),
                "--out".into(),
                a.display().to_string(),
                "--set".into(),
                "duration=0.1".into(),
                "--checkpoint-every".into(),
                "0.1".into(),
                "--checkpoint".into(),
                ckpt.clone(),
            ],
        );
        assert!(report.contains("checkpoint"), "{report}");
        if first > 1 {
            assert!(migrated(&report) > 0, "{report}");
        }
        let report = run_args(
            then,
            "auto",
            &[
                "--restart".into(),
                ckpt,
                "--out".into(),
                b.display().to_string(),
                "--set".into(),
                "duration=0.2".into(),
            ],
        );
        assert!(report.contains("restarting"), "{report}");
        let resumed = read_frames(&b, "squarebend");
        let from = resumed[0].step;
        assert!(from > 0, "the restart begins at the checkpoint's step");
        let after =
            |f: &[Frame]| -> Vec<Frame> { f.iter().filter(|f| f.step > from).cloned().collect() };
        let (r, t) = (after(&reference), after(&resumed));
        // particles drained before the checkpoint: the restarted counts go on from them
        let drained = |f: &Frame| {
            f.stats
                .iter()
                .filter(|(k, _)| k.starts_with("drained"))
                .map(|(_, v)| *v)
                .sum::<f64>()
        };
        assert!(drained(&resumed[0]) > 100.0, "{:?}", resumed[0].stats);
        assert!(r.len() > 2 && r.iter().any(|f| f.len() > 1));
        assert_eq!(r.len(), t.len(), "{first} → {then} ranks: frames");
        assert_eq!(
            digest(&t),
            digest(&r),
            "{first} → {then} ranks: the restarted bits differ from the uninterrupted run's"
        );
    }
}

#[test]
fn wheel_rotating_frame_is_bit_identical_on_2_ranks() {
    // The SRF wheel (cases/wheel.toml): particles spiralling through x slabs in the
    // rotating frame (centrifugal and Coriolis forces), rebounding on the blades.
    same_bits(
        "wheel",
        "x",
        &["duration=0.06", "feed_scale=0.2", "record_every=250"],
        &[2],
    );
}

/// Moving walls over ranks (tests/fixtures/moving-floor.toml): a rising, turning floor and
/// a turning drum, both impulse walls whose pose follows the step counter on every rank,
/// fling beads across the x slabs; 2 and 3 ranks record 1 rank's bits.
#[test]
fn moving_walls_are_bit_identical_on_2_and_3_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let file = "tests/fixtures/moving-floor.toml";
    let one = dir.path().join("1");
    run_file(1, "x", file, &[], &one);
    let reference = read_frames(&one, "moving-floor");
    assert!(reference.len() > 2);
    for n in [2, 3] {
        let out = dir.path().join(n.to_string());
        let report = run_file(n, "x", file, &[], &out);
        assert!(
            migrated(&report) > 0,
            "{n} ranks: nothing migrated: {report}"
        );
        let frames = read_frames(&out, "moving-floor");
        assert_eq!(digest(&frames), digest(&reference), "{n} ranks");
    }
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

/// The Wasserstein-1 distance between two samples (any sizes): ∫|F_a − F_b| dx over
/// their empirical distribution functions.
fn w1(mut a: Vec<f64>, mut b: Vec<f64>) -> f64 {
    a.sort_unstable_by(f64::total_cmp);
    b.sort_unstable_by(f64::total_cmp);
    let (na, nb) = (a.len() as f64, b.len() as f64);
    let mut all: Vec<f64> = a.iter().chain(&b).copied().collect();
    all.sort_unstable_by(f64::total_cmp);
    let (mut ia, mut ib, mut sum) = (0, 0, 0.0);
    for w in all.windows(2) {
        while ia < a.len() && a[ia] <= w[0] {
            ia += 1;
        }
        while ib < b.len() && b[ib] <= w[0] {
            ib += 1;
        }
        sum += (ia as f64 / na - ib as f64 / nb).abs() * (w[1] - w[0]);
    }
    sum
}

#[test]
fn w1_of_shifted_and_resized_samples() {
    let a: Vec<f64> = (0..100).map(f64::from).collect();
    let b: Vec<f64> = a.iter().map(|x| x + 0.5).collect();
    assert!((w1(a.clone(), b) - 0.5).abs() < 1e-12);
    assert_eq!(w1(a.clone(), a.clone()), 0.0);
    // {0, 1} against {0, 0, 1, 1}: the same distribution.
    assert!(w1(vec![0.0, 1.0], vec![1.0, 0.0, 0.0, 1.0]).abs() < 1e-15);
    assert!((w1(vec![0.0], vec![0.0, 2.0]) - 1.0).abs() < 1e-15);
}

/// W1 of the heights (z) and of the distances from the z axis between two frames, and
/// the largest distance between the two positions of a particle present in both, m.
fn frame_stats(a: &Frame, b: &Frame) -> (f64, f64, f64) {
    let z = |f: &Frame| f.position.iter().map(|p| p[2]).collect::<Vec<_>>();
    let r = |f: &Frame| {
        f.position
            .iter()
            .map(|p| p[0].hypot(p[1]))
            .collect::<Vec<_>>()
    };
    let at: std::collections::HashMap<u32, [f64; 3]> =
        b.id.iter()
            .copied()
            .zip(b.position.iter().copied())
            .collect();
    let apart =
        a.id.iter()
            .zip(&a.position)
            .filter_map(|(id, p)| {
                let q = at.get(id)?;
                Some((0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt())
            })
            .fold(0.0, f64::max);
    (w1(z(a), z(b)), w1(r(a), r(b)), apart)
}

/// A scene with particle contacts on 1 rank and on each of `ranks` (slabs along `axis`),
/// frame by frame against 1 rank: W1 of the heights and radial distances, the largest
/// per-particle distance and the count. Also 1 rank with `control` (a change that only
/// reorders the force sums, e.g. another Verlet skin) against 1 rank: the spread that
/// the chaos of the contacts alone gives (none when `control` is empty). Returns, per
/// frame, (step, count on 1 rank, collisions on 1 rank) and, per run (control first,
/// then the ranks), per frame (count, W1 z, W1 r, largest distance).
#[allow(clippy::type_complexity)]
fn contact_runs(
    file: &str,
    stem: &str,
    axis: &str,
    set: &[&str],
    control: &[&str],
    ranks: &[usize],
) -> (Vec<(u64, usize, f64)>, Vec<Vec<(usize, f64, f64, f64)>>) {
    let dir = tempfile::tempdir().unwrap();
    let read = |d: &Path| read_frames(d, stem);
    let one = dir.path().join("1");
    run_file(1, axis, file, set, &one);
    let reference = read(&one);
    assert!(reference.len() > 2, "{stem}: {} frames", reference.len());
    let collisions = |f: &Frame| -> f64 {
        f.stats
            .iter()
            .filter(|(k, _)| k.starts_with("collisions/"))
            .map(|(_, v)| v)
            .sum()
    };
    let frames_1 = reference
        .iter()
        .map(|f| (f.step, f.len(), collisions(f)))
        .collect();
    let mut runs = Vec::new();
    let mut all = Vec::new();
    if !control.is_empty() {
        let ctl = dir.path().join("control");
        let with_control: Vec<&str> = set.iter().chain(control).copied().collect();
        run_file(1, axis, file, &with_control, &ctl);
        all.push((String::from("1 rank with control"), read(&ctl)));
    }
    for &n in ranks {
        let out = dir.path().join(n.to_string());
        let report = run_file(n, axis, file, set, &out);
        assert!(
            migrated(&report) > 0,
            "{stem} on {n} ranks: no particle migrated: {report}"
        );
        let ghosts: f64 = report
            .lines()
            .skip_while(|l| !l.starts_with("ghost exchange"))
            .filter(|l| l.trim_start().starts_with("rank "))
            .filter_map(|l| l.split_whitespace().nth(3)?.parse::<f64>().ok())
            .sum();
        assert!(ghosts > 1.0, "{stem} on {n} ranks: no ghosts: {report}");
        if axis == "bisection" {
            assert!(
                report.contains(&format!("in {n} boxes by recursive bisection")),
                "{report}"
            );
        }
        all.push((format!("{n} ranks"), read(&out)));
        // Its recording cannot be verified by a one-rank re-run, and `--verify` says why.
        let mcap = std::fs::read_dir(&out)
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .find(|p| p.extension().is_some_and(|x| x == "mcap"))
            .expect("a recording");
        let o = Command::new(scg_bin())
            .arg("replay")
            .arg(&mcap)
            .arg("--verify")
            .output()
            .unwrap();
        let said = String::from_utf8_lossy(&o.stdout);
        assert!(
            said.contains(&format!("recorded on {n} MPI ranks with particle contacts"))
                && o.status.code() == Some(1),
            "{said}"
        );
    }
    for (name, frames) in all {
        assert_eq!(frames.len(), reference.len(), "{stem} on {name}: frames");
        let mut per = Vec::new();
        for (a, b) in frames.iter().zip(&reference) {
            assert_eq!(a.step, b.step);
            assert!(
                a.id.windows(2).all(|w| w[0] < w[1]),
                "{stem} on {name}, step {}: a particle twice",
                a.step
            );
            let (wz, wr, apart) = frame_stats(a, b);
            eprintln!(
                "{stem}, {name}, step {}: {} particles ({} on 1 rank), {} collisions, W1 z {wz:.2e} m, W1 r {wr:.2e} m, largest distance from 1 rank {apart:.2e} m",
                b.step,
                a.len(),
                b.len(),
                collisions(b)
            );
            per.push((a.len(), wz, wr, apart));
        }
        runs.push(per);
    }
    (frames_1, runs)
}

#[test]
fn settling_bed_with_contacts_agrees_with_one_rank_on_2_and_4_ranks() {
    // The golden scene: 150 particles settle into a cup and 200 more are fed on top, a
    // dense bed of Hertz–Mindlin contacts with friction and rolling friction, cut into
    // slabs across the bed (x), 9 634 steps (25 ms; about 13 s for the five runs). The
    // force sums run in another order than on one rank (scg-mpi's ghosts module), so
    // the last bits differ and the contacts' chaos amplifies them (about ×100 per 1000
    // steps here).
    settling_bed("x", &[2, 4]);
}

/// The same bed on 4 ranks in boxes by recursive bisection (cuts along x and y: each
/// box touches three others, one of them only along the cup's axis).
#[test]
fn settling_bed_with_contacts_agrees_with_one_rank_in_4_bisection_boxes() {
    settling_bed("bisection", &[4]);
}

fn settling_bed(how: &str, ranks_run: &[usize]) {
    let (frames, runs) = contact_runs(
        "tests/fixtures/golden.toml",
        "golden",
        how,
        &["record_every=1000", "duration=0.025"],
        &["seed=12"],
        ranks_run,
    );
    let cup = 4.0e-3;
    let (control, ranks) = runs.split_first().unwrap();
    let max_of = |r: &[(usize, f64, f64, f64)], f: fn(&(usize, f64, f64, f64)) -> f64| {
        r.iter().map(f).fold(0.0, f64::max)
    };
    let count_gap = |r: &[(usize, f64, f64, f64)]| {
        r.iter()
            .zip(&frames)
            .map(|(a, b)| a.0.abs_diff(b.1))
            .max()
            .unwrap()
    };
    for (n, r) in ranks_run.iter().zip(ranks) {
        // Before the chaos has grown (step 2000, over 1000 contacts started, among them
        // contacts across the slabs): every particle where one rank has it, to 1 nm. A
        // missing or wrong ghost moves its partner by the overlap (µm) at once.
        for (f, a) in frames.iter().zip(r).take_while(|(f, _)| f.0 <= 2000) {
            assert_eq!(a.0, f.1, "{n} ranks, step {}: count", f.0);
            assert!(
                a.3 < 1e-9,
                "{n} ranks, step {}: a particle {:.3e} m from where 1 rank has it",
                f.0,
                a.3
            );
        }
        assert!(frames.iter().any(|f| f.0 <= 2000 && f.2 > 1000.0));
        // After it: the bed is another realisation, as far from 1 rank's as a bed from
        // another seed is (W1 of heights and radial distances, counts: particles thrown
        // out of the domain by overlapping feeds).
        let (wz, wr) = (max_of(r, |x| x.1), max_of(r, |x| x.2));
        let (cz, cr) = (max_of(control, |x| x.1), max_of(control, |x| x.2));
        eprintln!(
            "{n} ranks: largest W1 z {:.2e}, r {:.2e} of the cup radius; another seed: {:.2e}, {:.2e}; count gaps {} and {}",
            wz / cup,
            wr / cup,
            cz / cup,
            cr / cup,
            count_gap(r),
            count_gap(control)
        );
        assert!(
            wz <= cz && wr <= cr,
            "{n} ranks: W1 z {wz:.3e}, r {wr:.3e} m"
        );
        assert!(count_gap(r) <= count_gap(control));
    }
}

/// The classifier fed five times denser than the paper's (so that particles touch
/// within the 4 ms it runs: about 40 contacts between particles and 2600 particles) on
/// 4 ranks, slabs along the axis cut again as the particles descend: the same counts
/// at every frame (nothing drains yet) and W1 of heights and radial positions within
/// 0.005 of the vessel radius. About 35 s on 2 shared cores (each step exchanges
/// ghosts, migrates and rebuilds the list near the cuts, all latency-bound):
/// `cargo test --release --features mpi --test mpi_ranks classifier_with_contacts -- --ignored`.
#[test]
#[ignore]
fn classifier_with_contacts_agrees_with_one_rank_on_4_ranks() {
    let mut set = vec!["duration=0.004", "record_every=2500"];
    let rates: Vec<String> = (0..4)
        .map(|k| format!("feeders.{k}.volume_rate=3e-7"))
        .collect();
    set.extend(rates.iter().map(String::as_str));
    let (frames, runs) = contact_runs("cases/classifier.toml", "classifier", "z", &set, &[], &[4]);
    let vessel = 3.0e-2;
    let r = &runs[0];
    for (f, a) in frames.iter().zip(r) {
        assert_eq!(a.0, f.1, "4 ranks, step {}: count", f.0);
        assert!(
            a.1 < 0.005 * vessel && a.2 < 0.005 * vessel,
            "4 ranks, step {}: W1 z {:.3e}, r {:.3e} m",
            f.0,
            a.1,
            a.2
        );
    }
    let last = frames.last().unwrap();
    assert!(
        last.1 > 2000 && last.2 > 20.0,
        "{last:?}: nothing to compare"
    );
    eprintln!(
        "classifier on 4 ranks: largest W1 z {:.2e}, r {:.2e} of the vessel radius",
        r.iter().map(|x| x.1).fold(0.0, f64::max) / vessel,
        r.iter().map(|x| x.2).fold(0.0, f64::max) / vessel
    );
}

#[test]
fn contacts_are_refused_when_shared_by_id() {
    let dir = tempfile::tempdir().unwrap();
    let o = scg_cmd(2, true)
        .arg("run")
        .arg(repo("cases/classifier.toml"))
        .arg("--out")
        .arg(dir.path())
        .env("SCG_MPI_DECOMP", "ids")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("particle contacts over MPI ranks need regions"),
        "{err}"
    );
}

/// Checkpoints with particle contacts over ranks: the classifier fed five times denser
/// (binary contacts, 30-odd started by 4 ms, across the cuts too) checkpointed at 2 ms
/// on 3 ranks and finished on 2, and on 2 and finished on 1: every frame after the
/// restart holds the same particles as the uninterrupted run on one rank, each within
/// 1 nm of it (the force sums' order is the only difference, and with binary contacts
/// there is none to speak of), the same counts and collisions.
#[test]
fn checkpoints_with_contacts_restart_on_another_number_of_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let rates: Vec<String> = (0..4)
        .map(|k| format!("feeders.{k}.volume_rate=3e-7"))
        .collect();
    let mut set: Vec<String> = vec!["record_every=1000".into()];
    set.extend(rates);
    let with = |d: &str| -> Vec<String> {
        let mut a = Vec::new();
        for s in set.iter().map(String::as_str).chain([d]) {
            a.push("--set".to_string());
            a.push(s.to_string());
        }
        a
    };
    let case = repo("cases/classifier.toml").display().to_string();
    let one = dir.path().join("1");
    let mut args = vec![case.clone(), "--out".into(), one.display().to_string()];
    args.extend(with("duration=0.004"));
    run_args(1, "z", &args);
    let reference = read_frames(&one, "classifier");
    for (first, then) in [(3, 2), (2, 1)] {
        let a = dir.path().join(format!("{first}-{then}-a"));
        let b = dir.path().join(format!("{first}-{then}-b"));
        let ckpt = a.join("half.ckpt").display().to_string();
        let mut args = vec![case.clone(), "--out".into(), a.display().to_string()];
        args.extend(with("duration=0.002"));
        args.extend(["--checkpoint-every", "0.002", "--checkpoint", &ckpt].map(String::from));
        let report = run_args(first, "z", &args);
        assert!(report.contains("checkpoint"), "{report}");
        let mut args = vec!["--restart".to_string(), ckpt, "--out".into()];
        args.push(b.display().to_string());
        args.extend(with("duration=0.004"));
        let report = run_args(then, "z", &args);
        assert!(report.contains("restarting"), "{report}");
        let resumed = read_frames(&b, "classifier");
        let from = resumed[0].step;
        let after =
            |f: &[Frame]| -> Vec<Frame> { f.iter().filter(|f| f.step > from).cloned().collect() };
        let (r, t) = (after(&reference), after(&resumed));
        assert!(
            r.len() >= 2 && t.len() == r.len(),
            "{first} → {then}: frames"
        );
        let collisions = |f: &Frame| {
            f.stats
                .iter()
                .filter(|(k, _)| k.starts_with("collisions"))
                .map(|(_, v)| *v)
                .sum::<f64>()
        };
        let last = r.last().unwrap();
        assert!(
            collisions(last) > 20.0,
            "{:?}: nothing to carry",
            last.stats
        );
        let mut worst: f64 = 0.0;
        for (x, y) in t.iter().zip(&r) {
            assert_eq!(x.id, y.id, "{first} → {then}: particles at step {}", y.step);
            assert_eq!(
                x.stats, y.stats,
                "{first} → {then}: counts at step {}",
                y.step
            );
            for (p, q) in x.position.iter().zip(&y.position) {
                let d = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
                worst = worst.max(d);
            }
        }
        eprintln!("{first} → {then} ranks: largest distance from one rank's run {worst:.2e} m");
        assert!(worst < 1e-9, "{first} → {then}: {worst:.2e} m");
    }
}

/// A chute in a periodic box: 300 spheres of 1 mm in a simple cubic packing (10 × 10 × 3,
/// touching) on a floor, periodic in x and y, gravity tilted 26° along x, each sliding off
/// at 0.6–1 m/s along x with a little y: at once every particle has several contacts,
/// among them contacts across the box's x sides. Slabs along x wrap round the box; the
/// particles cross the cuts and the box's side. The force sums run in another order than on one rank,
/// so only the early frames agree bit-near; counts agree throughout.
fn chute_scene(dir: &Path) -> PathBuf {
    let (n, d) = (10usize, 1e-3);
    let (mut ps, mut vs) = (Vec::new(), Vec::new());
    for k in 0..3 {
        for j in 0..n {
            for i in 0..n {
                ps.push(format!(
                    "[{:e}, {:e}, {:e}]",
                    (i as f64 + 0.5) * d,
                    (j as f64 + 0.5) * d,
                    (k as f64 + 0.5) * d
                ));
                let vx = 0.8 + 0.2 * ((i + j + k) % 3) as f64 - 0.2;
                let vy = 0.05 * ((i * 7 + j * 3) % 5) as f64 - 0.1;
                vs.push(format!("[{vx:e}, {vy:e}, 0.0]"));
            }
        }
    }
    let theta = 26f64.to_radians();
    let scene = format!(
        r#"name = "chute"
duration = 4e-3
dt = 2e-6
record_every = 250
seed = 3
[gravity]
acceleration = [{gx:e}, 0.0, {gz:e}]
[material]
youngs_modulus = 1e8
poisson_ratio = 0.3
restitution = 0.9
friction = 0.5
[contacts]
skin = 1e-4
periodic = [1e-2, 1e-2, 2e-2]
[[walls]]
name = "floor"
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[groups]]
name = "p"
diameter = 1e-3
density = 2500.0
positions = [{p}]
velocities = [{v}]
"#,
        gx = 9.81 * theta.sin(),
        gz = -9.81 * theta.cos(),
        p = ps.join(", "),
        v = vs.join(", "),
    );
    let file = dir.join("chute.toml");
    std::fs::write(&file, scene).unwrap();
    file
}

#[test]
fn periodic_chute_with_contacts_agrees_with_one_rank_on_2_and_3_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let file = chute_scene(dir.path());
    let (frames, runs) = contact_runs(&file.display().to_string(), "chute", "x", &[], &[], &[2, 3]);
    assert!(frames[1].2 > 100.0, "{:?}: too few contacts", frames[1]);
    for (n, r) in [2, 3].iter().zip(&runs) {
        for (f, a) in frames.iter().zip(r) {
            assert_eq!(a.0, f.1, "{n} ranks, step {}: count", f.0);
        }
        // Before the chaos has grown: every particle where one rank has it, to 1 nm. A
        // missing ghost across the box's side leaves its partners a contact short at
        // once (its overlap, µm, in a few steps).
        for (f, a) in frames.iter().zip(r).take_while(|(f, _)| f.0 <= 500) {
            assert!(
                a.3 < 1e-9,
                "{n} ranks, step {}: a particle {:.3e} m from where 1 rank has it",
                f.0,
                a.3
            );
        }
    }
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
    let o = decomposed(&mut cmd, axis)
        .env("SCG_MPI_COUNTS", log)
        .output()
        .expect("mpirun (OpenMPI) on the PATH");
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{ranks} ranks: {err}");
    (std::fs::read_to_string(log).unwrap(), err)
}

/// 10^4 steps of `case` on 1 and on 4 ranks (slabs along z, cut again as the counts
/// drift): after every step the step, count and id digest over all ranks equal one
/// rank's; the 4 ranks rebalanced and migrated. Returns the count after every step and
/// the 4-rank report.
fn same_counts_on_4_ranks(case: &str, set: &[&str]) -> (Vec<u64>, String) {
    let dir = tempfile::tempdir().unwrap();
    let (one, _) = counts(1, "z", case, set, &dir.path().join("1.txt"));
    let (four, report) = counts(4, "z", case, set, &dir.path().join("4.txt"));
    let one: Vec<&str> = one.lines().collect();
    let four: Vec<&str> = four.lines().collect();
    assert_eq!(one.len(), 10_000);
    assert_eq!(four.len(), one.len());
    for (a, b) in four.iter().zip(&one) {
        assert_eq!(a, b, "step, count, id digest on 4 ranks vs 1");
    }
    let rebalances: u64 = report
        .split("particle-steps/s, ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0);
    assert!(rebalances > 0, "no rebalance: {report}");
    assert!(migrated(&report) > 0, "{report}");
    let per_step = one
        .iter()
        .map(|l| l.split_whitespace().nth(1).unwrap().parse().unwrap())
        .collect();
    (per_step, report)
}

#[test]
fn no_particle_lost_or_duplicated_over_10k_cyclone_steps_on_4_ranks() {
    // 10^4 steps of the cyclone (fed for 1 s, drained through the outlet and lost through
    // the inlet).
    let (n, _) = same_counts_on_4_ranks(
        "cyclone",
        &[
            "duration=2.0",
            "feeders.0.rate=100",
            "feeders.1.rate=100",
            "feeders.2.rate=100",
            "feeders.3.rate=100",
        ],
    );
    let peak = n.iter().copied().max().unwrap();
    let last = n[n.len() - 1];
    assert!(peak > 300 && last < peak, "fed {peak}, left {last}");
}

#[test]
fn no_particle_lost_or_duplicated_over_10k_classifier_steps_with_contacts_on_4_ranks() {
    // 10^4 steps of the classifier with its particle and wall contacts (2 ms: fed from
    // the top, nothing drains yet): new ghost sets only at rebuilds (a particle moved
    // half the skin, or a feed), the ghosts' states forwarded on the other steps.
    let (n, report) = same_counts_on_4_ranks("classifier", &["duration=0.002"]);
    let last = n[n.len() - 1];
    assert!(last > 300, "fed {last}");
    let words: Vec<u64> = report
        .lines()
        .find(|l| l.starts_with("ghosts: "))
        .unwrap_or_else(|| panic!("no ghosts line: {report}"))
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    let (sets, forwarded) = (words[0], words[1]);
    // (a step whose flags rode on the forward and then asked for a rebuild counts both)
    assert!(sets + forwarded >= 10_000, "{report}");
    assert!(
        sets > 10 && forwarded > 5 * sets,
        "{sets} ghost sets, {forwarded} steps forwarded: {report}"
    );
}

/// The tables a run ends with from logs each rank holds its share of, merged on rank 0:
/// the elbow (fed sand rebounding and wearing the bend, `[erosion]`) on 3 ranks writes
/// one rank's `--fates-csv` and `--summary-json` (but for the wall time and the thread
/// count) and its `--erosion-csv` to rounding (a face's impacts summed rank by rank).
#[test]
fn end_tables_over_3_ranks_are_one_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let files = |n: usize| -> [PathBuf; 3] {
        ["fates.csv", "summary.json", "erosion.csv"].map(|f| dir.path().join(format!("{n}-{f}")))
    };
    let mut got = Vec::new();
    for n in [1, 3] {
        let [fates, summary, erosion] = files(n);
        let args: Vec<String> = [
            repo("cases/elbow.toml").display().to_string(),
            "--no-record".into(),
            "--set".into(),
            "duration=0.05".into(),
            "--fates-csv".into(),
            fates.display().to_string(),
            "--summary-json".into(),
            summary.display().to_string(),
            "--erosion-csv".into(),
            erosion.display().to_string(),
        ]
        .into();
        let report = run_args(n, "auto", &args);
        assert!(report.contains("erosion (finnie"), "{report}");
        let read = |p: &Path| std::fs::read_to_string(p).unwrap();
        got.push((read(&fates), read(&summary), read(&erosion)));
        if n > 1 {
            assert!(migrated(&report) > 0, "{report}");
        }
    }
    let (one, three) = (&got[0], &got[1]);
    assert!(one.0.lines().count() > 3, "{}", one.0);
    assert_eq!(one.0, three.0, "fates");
    let json = |t: &str| {
        let mut v: serde_json::Value = serde_json::from_str(t).unwrap();
        for k in ["wall_s", "particle_steps_per_s", "threads"] {
            v.as_object_mut().unwrap().remove(k);
        }
        v
    };
    assert_eq!(json(&one.1), json(&three.1), "summary");
    let (a, b): (Vec<&str>, Vec<&str>) = (one.2.lines().collect(), three.2.lines().collect());
    assert!(a.len() > 100, "{} eroded faces", a.len());
    assert_eq!(a.len(), b.len());
    let mut differ = 0;
    for (x, y) in a.iter().zip(&b) {
        for (p, q) in x.split(',').zip(y.split(',')) {
            match (p.parse::<f64>(), q.parse::<f64>()) {
                (Ok(p), Ok(q)) => {
                    assert!((p - q).abs() <= 1e-12 * p.abs().max(q.abs()), "{x}\n{y}");
                    differ += usize::from(p != q);
                }
                _ => assert_eq!(p, q),
            }
        }
    }
    eprintln!("erosion CSV: {differ} values differ in their last bits");
}

/// An unsteady field (`[flow] series` of three OpenFOAM snapshots of a vortex whose rate
/// swings, cycling) on 2 and 3 ranks records the same bits as on one, with particles
/// migrating: each rank reads the snapshots ahead on its own, and what a particle keeps of
/// the last landing does not cross ranks.
#[test]
fn an_unsteady_series_is_bit_identical_on_2_and_3_ranks() {
    use glam::DVec3;
    use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
    use scg_mesh::foam::{Format, write_case, write_vector_field};
    let dir = tempfile::tempdir().unwrap();
    let mesh = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [8, 8, 4])
        .shape(CellShape::Hex)
        .naming(PatchNaming::Sides)
        .perturbed(0.15, 3)
        .build()
        .unwrap();
    let geom = scg_mesh::MeshGeometry::new(&mesh).unwrap();
    let case = dir.path().join("case");
    write_case(&case, &mesh, None, Format::Binary).unwrap();
    for (k, t) in [0.0, 0.25, 0.5].into_iter().enumerate() {
        let omega = [2.0, 3.5, 1.0][k];
        let u = scg_mesh::CellField::at_cell_centres(&mesh, &geom, |c| {
            DVec3::new(-(c.y - 0.5), c.x - 0.5, 0.05) * omega
        });
        write_vector_field(&case, &format!("{t}"), "U", &mesh, &u, Format::Binary).unwrap();
    }
    let scene = dir.path().join("series.toml");
    std::fs::write(
        &scene,
        "duration = 1.0\ndt = 1.0e-3\nrecord_every = 100\n[fluid]\ndensity = 1.2\n\
         viscosity = 1.8e-5\n[flow]\nkind = \"openfoam\"\ncase = \"case\"\n\
         series = { cycle = true }\n[flow.patches]\n\
         walls = [\"xmin\", \"xmax\", \"ymin\", \"ymax\", \"zmin\", \"zmax\"]\n\
         wall_model = \"rebound\"\nrestitution = 0.8\n[drag]\nlaw = \"schiller_naumann\"\n\
         [[groups]]\nname = \"p\"\ndiameter = 1.0e-4\ndensity = 1.0e3\ncount = 300\n\
         region = { kind = \"box\", min = [0.1, 0.1, 0.1], max = [0.9, 0.9, 0.9] }\n",
    )
    .unwrap();
    let file = scene.display().to_string();
    let one = dir.path().join("1");
    run_file(1, "x", &file, &[], &one);
    let reference = read_frames(&one, "series");
    assert!(reference.len() > 5 && reference.iter().all(|f| f.len() == 300));
    for n in [2, 3] {
        let out = dir.path().join(n.to_string());
        let report = run_file(n, "x", &file, &[], &out);
        let frames = read_frames(&out, "series");
        assert_eq!(digest(&frames), digest(&reference), "{n} ranks");
        assert!(migrated(&report) > 0, "{n} ranks: no migration: {report}");
    }
}
