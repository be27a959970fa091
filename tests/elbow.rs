//! The conveying elbow (`cases/elbow.toml`, issue 41): sand in air at 20 m/s through a
//! 90° bend, rebounding and wearing the wall by Finnie, with OpenFOAM's stochastic
//! dispersion. Side by side with OpenFOAM's own tracker on the same frozen field
//! (`bash cases/elbow/vs-openfoam.sh`, its results committed in
//! docs/data/elbow-vs-openfoam), and `scg study elbow` (quick here; the full study's
//! summary committed in docs/data/elbow-study).
//!
//! Run: `cargo test --release --test elbow -- --nocapture`.

mod common;

use std::path::Path;

use glam::DVec3;
use scg::cli::study::elbow::{self, wear};
use scg::core::stages::erosion::ErosionLog;

fn json(path: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(common::repo(path)).unwrap()).unwrap()
}

fn overlap(a: (f64, f64), b: (f64, f64)) -> bool {
    a.0 <= b.1 && b.0 <= a.1
}

/// The same particles in both codes (2000 per class, the scene as committed): every
/// class's fates (outlet, inlet, still inside) within overlapping 95 % Wilson intervals
/// of OpenFOAM's counts; OpenFOAM's total wear inside scg's 95 % interval; the same
/// deepest face; and the same zone of most wear (30° of the bend, 50 mm of the legs).
#[test]
fn elbow_fates_and_wear_agree_with_openfoams_tracker() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/elbow.toml");
    let sc = scg::scene::load(Path::new(path), &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sim = sc.build(false);
    sim.world.resource_mut::<ErosionLog>().keep_impacts();
    sim.run(sc.steps(), |_| true).unwrap();
    let fates = scg::cli::fates::fates(&sc, &mut sim);
    println!("{}", scg::cli::fates::render(&fates));
    let of = json("docs/data/elbow-vs-openfoam/grade.json");
    let classes = of["classes"].as_array().unwrap();
    assert_eq!(classes.len(), fates.len());
    for (f, c) in fates.iter().zip(classes) {
        assert_eq!(c["group"].as_str().unwrap(), f.group);
        let n = c["fed"].as_u64().unwrap();
        assert_eq!(n, f.entered(), "{}", f.group);
        assert_eq!(f.accounted(), f.entered(), "{}", f.group);
        let escaped = |patch: &str| f.patches.iter().find(|p| p.0 == patch).map_or(0, |p| p.2);
        for (what, ours, theirs) in [
            ("outlet", escaped("outlet"), c["escaped"].as_u64().unwrap()),
            ("inlet", escaped("inlet"), c["lost"].as_u64().unwrap()),
            ("inside", f.airborne, c["held"].as_u64().unwrap()),
        ] {
            let a = scg::cli::analysis::interval::wilson95(ours, n);
            let b = scg::cli::analysis::interval::wilson95(theirs, n);
            println!("{} {what}: scg {ours}, OpenFOAM {theirs} of {n}", f.group);
            assert!(
                overlap(a, b),
                "{} {what}: scg {ours} vs OpenFOAM {theirs} of {n}",
                f.group
            );
        }
    }
    // the wear
    let log = sim.world.resource::<ErosionLog>();
    let entered: u64 = fates.iter().map(|f| f.entered()).sum();
    let (total, lo, hi) = log.total_interval(entered);
    let e = json("docs/data/elbow-vs-openfoam/erosion.json");
    let of_total = e["openfoam_total"].as_f64().unwrap();
    println!("wear: scg {total:.4e} [{lo:.4e}, {hi:.4e}], OpenFOAM {of_total:.4e} m³");
    assert!((lo..=hi).contains(&of_total));
    let m = sc.mesh_flow.as_ref().unwrap();
    let g = m.flow.geometry();
    let (deepest, _) = log
        .faces
        .iter()
        .max_by(|a, b| a.1.volume.total_cmp(&b.1.volume))
        .unwrap();
    let c = g.face_centres[*deepest as usize];
    let b = json("docs/data/elbow-vs-openfoam/bend.json");
    let of_c = &b["openfoam_deepest"]["centre"];
    let of_c = DVec3::new(
        of_c[0].as_f64().unwrap(),
        of_c[1].as_f64().unwrap(),
        of_c[2].as_f64().unwrap(),
    );
    println!("deepest face: scg {c}, OpenFOAM {of_c}");
    assert!(c.distance(of_c) < 1e-6, "{c} vs {of_c}");
    let w = wear::wear(
        log.impacts.as_deref().unwrap(),
        |f| {
            (
                g.face_centres[f as usize],
                g.face_areas[f as usize].length(),
            )
        },
        (total, lo, hi),
        entered,
        sim.time(),
    );
    assert_eq!(w.top, b["openfoam_top_zone"].as_str().unwrap());
    assert_eq!(w.top, "bend outer 30-60°");
    // every zone's share: OpenFOAM's inside scg's interval, zone by zone (the zones of
    // bend.py and of the study are the same)
    for z in b["zones"].as_array().unwrap() {
        let name = z["zone"].as_str().unwrap();
        let ours = w.zones.iter().find(|s| s.zone == name).expect(name);
        let theirs = z["openfoam"].as_f64().unwrap();
        assert!(
            theirs >= ours.lo - 1e-12 && theirs <= ours.hi + 1e-12,
            "{name}: OpenFOAM {theirs} outside scg's {} [{}, {}]",
            ours.share,
            ours.lo,
            ours.hi
        );
    }
}

/// `scg study elbow --quick`: every variant runs, the tracers behave as the air (all
/// leave within 5·V/Q, mean residence V/Q within 5 %), the originals wear the extrados
/// between 30° and 60° most, and SCG at α = 2 and sampling at α = 2 reach the outlet as
/// the originals do, class by class (within 3σ of the sampling).
#[test]
fn the_quick_elbow_study_runs_and_scg_agrees() {
    let out = std::env::temp_dir().join(format!("scg-elbow-study-{}", std::process::id()));
    let a = scg::cli::study::StudyArgs {
        quick: true,
        out: Some(out.clone()),
        no_record: true,
        ..scg::cli::study::StudyArgs::new("elbow")
    };
    assert_eq!(scg::cli::study::study(a, &scg::cli::points::Local), 0);
    let (runs, tracers) = elbow::read_summary(&out).unwrap();
    let names: Vec<&str> = runs.iter().map(|r| r.run.name.as_str()).collect();
    assert_eq!(names, elbow::VARIANTS.map(|v| v.0));
    let t = tracers.unwrap();
    assert!(t.leave() && (t.ratio() - 1.0).abs() <= 0.05, "{}", t.text());
    assert_eq!(runs[0].wear.top, "bend outer 30-60°");
    // SCG at α = 2 and sampling at α = 2 reach the outlet as the originals do, class by
    // class: a two-proportion test at 3σ (6 comparisons: a false alarm 1.6 % of the
    // time). The study's own verdict compares some twenty shares per variant at 95 % and
    // expects an occasional ✗ (cases/elbow/README.md); the committed full study's wear is
    // checked below.
    for v in [1, 5] {
        for (o, c) in runs[0].run.classes.iter().zip(&runs[v].run.classes) {
            let (no, nv) = (o.fed as f64, c.fed as f64);
            let (po, pv) = (o.escaped as f64 / no, c.escaped as f64 / nv);
            let p = (o.escaped + c.escaped) as f64 / (no + nv);
            let sd = (p * (1.0 - p) * (1.0 / no + 1.0 / nv)).sqrt();
            assert!(
                (pv - po).abs() <= 3.0 * sd.max(1e-12),
                "{} {}: reached the outlet {pv:.3} (of {nv}) against the originals' {po:.3} (of {no}), 3σ = {:.3}",
                runs[v].run.name,
                c.group,
                3.0 * sd
            );
        }
    }
    for r in &runs {
        for c in &r.run.classes {
            assert_eq!(c.fed, c.escaped + c.held + c.lost, "{}", r.run.name);
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// The committed full study (docs/data/elbow-study, `scg study elbow`): SCG at α = 2 and
/// 4 wears the elbow as much as the originals do (the originals' total inside each one's
/// interval), the laws that move particles as originals do agree at α = 2, and without
/// SCG (`none2`: 100 µm at the original density for 50 µm) the total wear is beyond the
/// intervals, so the comparison can tell.
#[test]
fn in_the_committed_study_scg_keeps_the_wear_and_none_does_not() {
    let (runs, _) = elbow::read_summary(&common::repo("docs/data/elbow-study")).unwrap();
    let by = |n: &str| runs.iter().find(|r| r.run.name == n).unwrap();
    let o = by("original").wear.total.0;
    for v in ["scg2", "scg4"] {
        let (_, lo, hi) = by(v).wear.total;
        assert!((lo..=hi).contains(&o), "{v}: {lo} {hi} vs {o}");
    }
    for v in ["scg2", "parcel2", "sample2"] {
        let (ok, line) = elbow::report::verdict(by("original"), by(v));
        assert!(ok, "{line}");
    }
    let (ok, _) = elbow::report::verdict(by("original"), by("none2"));
    assert!(!ok);
    let (_, lo, hi) = by("none2").wear.total;
    assert!(!(lo..=hi).contains(&o));
}
