//! `scg study cyclone`, reduced: the coarse cyclone mesh, two classes (4 and 30 µm) of
//! the ten, α = 2, 2 s. Checks that the grade efficiency rises with size, that without SCG
//! the coarse-grained 4 µm (simulated 8 µm at the original density) are held while with
//! SCG they escape like the originals do, the bookkeeping (fed = escaped + held + lost, one
//! residence time per escape), and the report with an `--openfoam` column.
//!
//! Run: `cargo test --release --test cyclone_study -- --nocapture` (prints the counts).

mod common;

use scg::cli::study::cyclone::{
    self, ClassGrade, Cyclone, CycloneRun, ExternalGrade, cut_size, run_variant, variant_overrides,
};

/// Index of the 4 µm and 30 µm classes in cases/cyclone.toml.
const D4: usize = 3;
const D30: usize = 9;

/// The variant (α = 2, `law`) fed 1024 originals of 4 µm and 256 of 30 µm per second for
/// the first second (the other classes not at all: 128 and 32 simulated), run for 2 s.
fn run(law: &str) -> CycloneRun {
    let text = cyclone::scene_text().expect("cyclone mesh");
    let mut o = variant_overrides(2.0, law, 1.0, 2.0);
    for f in 0..10 {
        let rate = match f {
            D4 => 1024.0,
            D30 => 256.0,
            _ => 0.0,
        };
        o.push(format!("feeders.{f}.rate={rate}"));
    }
    run_variant(law, &text, &o, 1.0, None).expect("variant runs")
}

fn check_books(v: &CycloneRun) {
    for c in &v.classes {
        let collected = c.collected.expect("the scene collects");
        assert_eq!(
            c.fed,
            c.escaped + c.held + c.lost + collected,
            "{}: {c:?}",
            v.name
        );
        assert_eq!(c.residence_times.len() as u64, c.escaped, "{}", v.name);
        assert!(c.residence_times.iter().all(|&t| t > 0.0 && t < 2.0));
    }
    assert_eq!(v.unmatched, 0, "{}", v.name);
}

#[test]
fn grade_efficiency_rises_with_size_and_scg_keeps_the_fines_escaping() {
    let scg = run("scg");
    let none = run("none");
    for v in [&scg, &none] {
        for c in [&v.classes[D4], &v.classes[D30]] {
            println!(
                "{} {}: fed {} collected {:?} escaped {} held {} lost {}",
                v.name, c.group, c.fed, c.collected, c.escaped, c.held, c.lost
            );
        }
        check_books(v);
        assert_eq!((v.classes[D4].fed, v.classes[D30].fed), (128, 32));
    }
    let (s4, s30) = (&scg.classes[D4], &scg.classes[D30]);
    // Ordering with size: no 30 µm escapes (some may be blown back out of the inlet at
    // its no-slip corners, the lead's note in issue 16), the 4 µm partly do.
    assert_eq!(s30.escaped, 0, "{s30:?}");
    assert!(s4.escaped >= 5, "{s4:?}");
    // At 2 s the 30 µm have not reached the dust outlet yet (they are undecided, held):
    // the efficiency's upper bound, 1 − escaped/fed, rises with size.
    assert!(s4.escaped_share() > s30.escaped_share());
    // No SCG: the 4 µm are simulated as 8 µm of the original density, whose Stokes number
    // is 4× the original's: in 2 s they escape less than half as often as with SCG (30
    // against 70 of 128).
    let n4 = &none.classes[D4];
    assert!(2 * n4.escaped < s4.escaped, "none {n4:?} vs scg {s4:?}");
}

#[test]
fn cut_size_theory_and_openfoam_column() {
    let t = Cyclone::OPENFOAM_TUTORIAL;
    assert!(t.barth_muschelknautz_d50(2000.0) < t.lapple_d50(2000.0));
    // A hand-made OpenFOAM grade.json beside a hand-made run: its column and curve.
    let dir = std::env::temp_dir().join(format!("scg-cyclone-study-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let of = dir.join("grade.json");
    std::fs::write(
        &of,
        r#"{"code": "openfoam", "classes": [
        {"group": "d2", "diameter": 2e-6, "density": 2000, "fed": 100, "escaped": 60, "held": 40, "lost": 0, "efficiency": 0.4, "residence_times": [1.0, 1.5]},
        {"group": "d8", "diameter": 8e-6, "density": 2000, "fed": 100, "escaped": 10, "held": 90, "lost": 0, "efficiency": 0.9, "residence_times": [2.0]}],
        "d50": null, "particle_steps_per_s": 2.5e6}"#,
    )
    .unwrap();
    let g = ExternalGrade::read(&of).unwrap();
    // 0.4 → 0.9 between 2 and 8 µm: 0.5 at 2 + 6·0.1/0.5 = 3.2 µm.
    assert!((cut_size(&g.classes).unwrap() - 3.2e-6).abs() < 1e-15);
    let class = |group: &str, d: f64, esc: u64, times: Vec<f64>| {
        ClassGrade::new(group, d, 2000.0, [100, esc, 100 - esc, 0], times)
    };
    let mk = |name: &str, times: Vec<f64>| CycloneRun {
        name: name.into(),
        alpha: 1.0,
        law: "scg".into(),
        classes: vec![
            class("d2", 2e-6, 70, times.clone()),
            class("d8", 8e-6, 20, times),
        ],
        total_s: 12.0,
        cpu_s: None,
        particle_steps: 1000,
        duration: 2.0,
        held_moving: vec![0, 0],
        escaped_late: vec![0, 0],
        unmatched: 0,
        snapshot: (1.0, vec![(glam::DVec3::ZERO, 0), (glam::DVec3::X * 0.3, 1)]),
    };
    let mut scg2 = mk("scg2", vec![1.1, 1.6]);
    scg2.total_s = 1.0;
    let runs = vec![mk("original", vec![1.0, 1.5]), scg2];
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let tracers = cyclone::TracerCheck {
        diameter: 1e-7,
        fed: 100,
        escaped: 90,
        within: 89,
        collected: 8,
        lost: 0,
        held: 2,
        v_over_q: 1.5,
        mean_residence: 1.65,
        mean_residence_95: 0.1,
        total_s: 1.0,
    };
    assert!(!tracers.leave() && (tracers.ratio() - 1.1).abs() < 1e-12);
    cyclone::write_tables(&runs, &t, Some(&g), Some(&tracers), &out).unwrap();
    cyclone::write_plots(&runs, Some(&g), &t, &[], &out).unwrap();
    let report = std::fs::read_to_string(out.join("report.txt")).unwrap();
    println!("{report}");
    assert!(report.contains("openfoam"), "{report}");
    assert!(
        report.contains("89.0 % within 5·V/Q: FAIL") && report.contains("= 1.100·V/Q (FAIL"),
        "{report}"
    );
    // The 2 µm row: original 30.0, scg2 30.0, openfoam 40.0.
    assert!(
        report
            .lines()
            .any(|l| l.split_whitespace().take(4).collect::<Vec<_>>()
                == ["2.0", "30.0", "30.0", "40.0"]),
        "{report}"
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["tracers"]["collected"], 8);
    assert_eq!(
        cyclone::read_tracers(&out).as_ref(),
        Some(&tracers),
        "read back from summary.json"
    );
    let of_classes = s["openfoam"]["classes"].as_array().unwrap();
    assert_eq!(of_classes[0]["efficiency"], 0.4);
    assert!((of_classes[0]["delta_efficiency_pp"].as_f64().unwrap() - 10.0).abs() < 1e-9);
    let v = &s["variants"]["scg2"];
    assert_eq!(v["classes"][0]["group"], "d2");
    assert_eq!(v["classes"][0]["fed"], 100);
    // W1 of [1.1, 1.6] to [1.0, 1.5] is 0.1 s over the mean 1.25 s.
    assert!((v["classes"][0]["w1_over_mean"].as_f64().unwrap() - 0.08).abs() < 1e-12);
    assert_eq!(v["time_ratio_to_original"], 1.0 / 12.0);
    let crit = s["criteria"].as_array().unwrap();
    let time = crit
        .iter()
        .find(|c| c["what"].as_str().unwrap().contains("wall time"))
        .unwrap();
    assert_eq!(time["pass"], true);
    let w1 = crit
        .iter()
        .find(|c| c["what"].as_str().unwrap().starts_with("scg2: max W1"))
        .unwrap();
    assert_eq!(w1["pass"], false);
    for f in [
        "partition.svg",
        "residence.svg",
        "snapshot-original.svg",
        "grade.csv",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_input_exits_2_naming_it() {
    let scg = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_scg"))
            .args(args)
            .current_dir(common::repo(""))
            .output()
            .unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, err) = scg(&[
        "study",
        "cyclone",
        "--quick",
        "--set",
        "dt=-1",
        "--no-record",
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("key `dt`"), "{err}");
    let (code, err) = scg(&["study", "cyclone", "--from", "/nonexistent-scg-study"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("summary.json"), "{err}");
    let (code, err) = scg(&["study", "cyclone", "--openfoam", "/nonexistent-grade.json"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("grade.json"), "{err}");
    let (code, err) = scg(&["study", "cyclone", "--run", "scg2,scg8"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("unknown variant `scg8`"), "{err}");
    let (code, err) = scg(&["study", "cyclone", "--run", "scg2"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("must include `original`"), "{err}");
    let (code, err) = scg(&["study", "cyclone", "--cg-feed", "0"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--cg-feed"), "{err}");
    let (code, err) = scg(&["study", "classifier", "--openfoam", "x.json"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("`scg study cyclone` only"), "{err}");
}

/// The study's tracer check, reduced (100 tracers over the first second, the scene's
/// models): the books add up, V/Q is the committed mesh's over the inlet's 0.8 m³/s, and
/// most tracers leave (the eddy model lets some reach the dust outlet: docs/cyclone.md).
#[test]
fn the_tracer_check_runs_with_the_studys_models() {
    let text = cyclone::scene_text().expect("cyclone mesh");
    let t = cyclone::run_tracers(&text, &[], 100.0).unwrap();
    println!("{}", t.text());
    assert_eq!(t.fed, 100);
    assert_eq!(t.fed, t.escaped + t.collected + t.lost + t.held);
    assert!(t.within <= t.escaped);
    assert!(
        (t.v_over_q - 1.146 / 0.8).abs() < 0.02,
        "V/Q {}",
        t.v_over_q
    );
    assert!(t.escaped >= 75, "{t:?}");
    assert!(t.mean_residence > 0.5 * t.v_over_q && t.mean_residence < 2.0 * t.v_over_q);
}

/// The sampling control: `sample2` feeds originals (α = 1, the scg law) at the simulated
/// count of `scg2` (1/8 of the feed), and the run is labelled `sample`.
#[test]
fn the_sampling_variant_feeds_originals_at_the_coarse_grained_count() {
    let s = variant_overrides(2.0, "sample", 10.0, 4.0);
    let c = variant_overrides(2.0, "scg", 10.0, 4.0);
    assert_eq!(s[0], "coarse_grain.alpha=1");
    assert_eq!(s[1], "coarse_grain.law=\"scg\"");
    assert_eq!((&s[2], &s[3]), (&c[2], &c[3]));
    assert!(cyclone::VARIANTS.contains(&("sample2", 2.0, "sample")));
    let text = cyclone::scene_text().expect("cyclone mesh");
    let mut o = variant_overrides(2.0, "sample", 0.8, 0.05);
    o.push("dispersion.model=\"langevin\"".into());
    let r = run_variant("sample2", &text, &o, 0.0, None).unwrap();
    assert_eq!((r.alpha, r.law.as_str()), (1.0, "sample"));
    assert!(r.classes.iter().all(|c| c.fed == 1), "{:?}", r.classes);
}
