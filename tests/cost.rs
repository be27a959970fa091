//! `scg cost`: the sweep's files, SCG exact while `none` and `mass` grow with α, and on the
//! vortex the measured cost of a represented population: SCG at α = 2 takes at most a
//! sixth of the original's time for the same originals.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, OnceLock};

/// The sweeps of this file run one at a time: the vortex's timings are asserted, and a
/// concurrent sweep would share its core.
static ONE_SWEEP_AT_A_TIME: Mutex<()> = Mutex::new(());

/// The quick vortex sweep, run once for the two tests that read it (under
/// [`ONE_SWEEP_AT_A_TIME`], which both hold).
static VORTEX: OnceLock<PathBuf> = OnceLock::new();

fn vortex_sweep() -> &'static Path {
    VORTEX.get_or_init(|| quick_sweep("vortex", "cost_vortex_quick"))
}

fn rows(csv: &str) -> Vec<Vec<String>> {
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn cost_sweep_on_the_uniform_case() {
    let _one = ONE_SWEEP_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let dir = quick_sweep("uniform", "cost_uniform_quick");
    sweep_checks("uniform", &dir);
    estimate_column(&dir);
}

/// The paper's vortex: SCG at round-off at every α, `none` and `mass` errors grow with α.
#[test]
fn cost_sweep_on_the_vortex_case() {
    let _one = ONE_SWEEP_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    sweep_checks("vortex", vortex_sweep());
}

/// Issue 18: `scg cost cases/vortex.toml --quick` times populations standing for the same
/// originals (2000 by default under `--quick`), not one particle × α³. SCG's measured
/// whole-run time at α = 2 (250 particles) is at most a sixth of the original's (2000
/// particles; the ideal is an eighth, the rest is the per-step overhead). The α³ estimate
/// is only an extra, labelled column. Wall times on a shared machine can be disturbed by
/// other load: a miss is re-measured once by a second sweep, and both ratios are reported.
#[test]
fn cost_vortex_times_the_represented_population() {
    let _one = ONE_SWEEP_AT_A_TIME
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let mut ratios = Vec::new();
    for attempt in 0..2 {
        let dir = match attempt {
            0 => vortex_sweep().to_path_buf(),
            _ => quick_sweep("vortex", "cost_vortex_quick_again"),
        };
        estimate_column(&dir);
        let csv = std::fs::read_to_string(dir.join("cost.csv")).unwrap();
        let (head, rows) = table(&csv);
        let col = |n: &str| {
            head.iter()
                .position(|h| h == n)
                .unwrap_or_else(|| panic!("column {n}: {head:?}"))
        };
        let (law, alpha, dt, wall, particles, represented, speedup) = (
            col("law"),
            col("alpha"),
            col("dt"),
            col("wall_s"),
            col("particles"),
            col("represented"),
            col("speedup"),
        );
        let base_dt = rows[0][dt].clone();
        let row = |l: &str, a: &str| {
            rows.iter()
                .find(|r| r[law] == l && r[alpha] == a && r[dt] == base_dt)
                .unwrap_or_else(|| panic!("{l} {a}"))
        };
        let (orig, scg2) = (row("original", "1"), row("scg", "2"));
        // The same originals represented; α³ fewer particles simulated.
        assert_eq!(orig[represented], "2000");
        assert_eq!(scg2[represented], "2000");
        assert_eq!(orig[particles], "2000");
        assert_eq!(scg2[particles], "250");
        assert_eq!(row("scg", "8")[particles], "4");
        let f = |r: &Vec<String>, c: usize| -> f64 { r[c].parse().unwrap() };
        let ratio = f(scg2, wall) / f(orig, wall);
        // The speed-up column is the measured ratio of wall times.
        assert!(
            (f(scg2, speedup) * ratio - 1.0).abs() < 1e-3,
            "speedup {} vs 1/{ratio}",
            scg2[speedup]
        );
        ratios.push(ratio);
        if ratio <= 1.0 / 6.0 {
            break;
        }
    }
    let last = *ratios.last().unwrap();
    assert!(
        last <= 1.0 / 6.0,
        "SCG α = 2 / original wall time for the same 2000 originals: {ratios:?} > 1/6"
    );
}

/// The α³ estimate: a labelled extra CSV column, filled for single-particle scenes, and
/// named as an estimate in cost.md; the main speed-up is the measured one.
fn estimate_column(dir: &Path) {
    let csv = std::fs::read_to_string(dir.join("cost.csv")).unwrap();
    let (head, rows) = table(&csv);
    let est = head
        .iter()
        .position(|h| h == "est_speedup_alpha3")
        .unwrap_or_else(|| panic!("est_speedup_alpha3: {head:?}"));
    assert!(head.iter().any(|h| h == "speedup"), "{head:?}");
    assert!(head.iter().any(|h| h == "wall_alone_s"), "{head:?}");
    for r in &rows {
        let e: f64 = r[est].parse().unwrap_or_else(|_| panic!("{r:?}"));
        assert!(e.is_finite() && e > 0.0, "{r:?}");
    }
    let md = std::fs::read_to_string(dir.join("cost.md")).unwrap();
    assert!(md.contains("speed-up (measured)"), "{md}");
    assert!(md.contains("| est. α³ |"), "{md}");
    assert!(
        md.contains("est. α³ (`est_speedup_alpha3`): the old estimate"),
        "{md}"
    );
}

fn table(csv: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let head = csv
        .lines()
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    (head, rows(csv))
}

/// `scg cost cases/<case>.toml --quick` into the emptied folder `name` of the test
/// scratch space.
fn quick_sweep(case: &str, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args([
            "cost",
            common::repo(&format!("cases/{case}.toml"))
                .to_str()
                .unwrap(),
        ])
        .args(["--quick", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("run sequentially"), "{err}");
    dir
}

fn sweep_checks(case: &str, dir: &Path) {
    for f in ["cost.md", "cost.csv", "cost.svg"] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(dir.join("cost.csv")).unwrap();
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    for c in [
        "law",
        "alpha",
        "dt",
        "integrator",
        "wall_s",
        "particle_steps",
        "error",
    ] {
        assert!(head.contains(&c), "column {c}: {head:?}");
    }
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (law, alpha, dt, error) = (col("law"), col("alpha"), col("dt"), col("error"));
    let rows = rows(&csv);
    let base_dt = &rows[0][dt];
    let err_of = |l: &str, a: &str| -> f64 {
        rows.iter()
            .find(|r| r[law] == l && r[alpha] == a && &r[dt] == base_dt)
            .unwrap_or_else(|| panic!("{l} {a}"))[error]
            .parse()
            .unwrap()
    };
    for a in ["2", "4", "8"] {
        assert!(err_of("scg", a) < 1e-12, "scg α={a}: {}", err_of("scg", a));
        // The sampling control: its particle 0 is the original itself (no model error),
        // and it simulates as many particles as SCG does.
        assert!(err_of("sample", a) < 1e-12, "sample α={a}");
        let particles = |l: &str| {
            rows.iter()
                .find(|r| r[law] == l && r[alpha] == a && &r[dt] == base_dt)
                .unwrap()[col("particles")]
            .clone()
        };
        assert_eq!(particles("sample"), particles("scg"), "α={a}");
    }
    for l in ["none", "mass"] {
        let e: Vec<f64> = ["2", "4", "8"].iter().map(|a| err_of(l, a)).collect();
        assert!(e[0] > 1e-6 && e[0] < e[1] && e[1] < e[2], "{l}: {e:?}");
    }
    let md = std::fs::read_to_string(dir.join("cost.md")).unwrap();
    // Neither scene declares contacts: no neighbour search is paid for.
    assert!(
        md.contains("| neighbour_search | (nothing — no cost) |"),
        "{md}"
    );
    if case == "uniform" {
        assert!(md.contains("| forces | (nothing — no cost) |"), "{md}");
    }
    assert!(md.contains("Speed-up of each α"));
    // Without contacts SCG is no better than sampling: both exact, the same count.
    assert!(md.contains("## Against plain sampling"), "{md}");
    assert!(
        md.contains("| 2 | scg |") && !md.contains("| yes |"),
        "{md}"
    );
    let svg = std::fs::read_to_string(dir.join("cost.svg")).unwrap();
    assert!(svg.contains("Pareto front"));
}
