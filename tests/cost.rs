//! `scg cost`: the sweep's files, and SCG exact while `none` and `mass` grow with α.

mod common;

use std::process::Command;

fn rows(csv: &str) -> Vec<Vec<String>> {
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

#[test]
fn cost_sweep_on_the_uniform_case() {
    sweep_checks("uniform");
}

/// The paper's vortex: SCG at round-off at every α, `none` and `mass` errors grow with α.
#[test]
fn cost_sweep_on_the_vortex_case() {
    sweep_checks("vortex");
}

fn sweep_checks(case: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args([
            "cost",
            common::repo(&format!("cases/{case}.toml"))
                .to_str()
                .unwrap(),
        ])
        .args(["--quick", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("run sequentially"), "{err}");
    for f in ["cost.md", "cost.csv", "cost.svg"] {
        assert!(dir.path().join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(dir.path().join("cost.csv")).unwrap();
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
    }
    for l in ["none", "mass"] {
        let e: Vec<f64> = ["2", "4", "8"].iter().map(|a| err_of(l, a)).collect();
        assert!(e[0] > 1e-6 && e[0] < e[1] && e[1] < e[2], "{l}: {e:?}");
    }
    let md = std::fs::read_to_string(dir.path().join("cost.md")).unwrap();
    // Neither scene declares contacts: no neighbour search is paid for.
    assert!(
        md.contains("| neighbour_search | (nothing — no cost) |"),
        "{md}"
    );
    if case == "uniform" {
        assert!(md.contains("| forces | (nothing — no cost) |"), "{md}");
    }
    assert!(md.contains("Speed-up of each α"));
    let svg = std::fs::read_to_string(dir.path().join("cost.svg")).unwrap();
    assert!(svg.contains("Pareto front"));
}
