//! The cyclone in its unsteady LES field (cases/cyclone-les.toml: the committed series
//! cases/cyclone/les of cases/cyclone/build-series.sh, 21 snapshots 0.05 s apart, cycled).
//! The sanity check first: fluid tracers fed with the air leave with a mean residence of
//! V/Q in the time-dependent field too (volume is conserved in every snapshot and so in
//! every blend of two); and the series holds more swirl at Barth–Muschelknautz's control
//! surface than the steady k-ω SST field it started from (docs/cyclone.md, "An unsteady
//! field").
//!
//! Run: `cargo test --release --test cyclone_les -- --nocapture`.

mod common;

use scg::cli::study::cyclone::{field_swirl, run_tracers};

/// The LES scene's text with its case as an absolute path (as `scg study cyclone --scene`
/// makes it).
fn les() -> (String, Vec<String>) {
    let text = std::fs::read_to_string(common::repo("cases/cyclone-les.toml")).unwrap();
    let case = common::repo("cases/cyclone/les");
    (
        text,
        vec![format!("flow.case={:?}", case.display().to_string())],
    )
}

#[test]
fn les_tracers_leave_with_mean_residence_v_over_q() {
    let (text, set) = les();
    let t = run_tracers(&text, &set, 1000.0).unwrap();
    println!("{}", t.text());
    assert_eq!(t.fed, 1000);
    assert_eq!(t.lost, 0);
    // the LES's recirculations hold a few tracers past 5·V/Q (the steady field: none)
    assert!(t.within as f64 >= 0.95 * t.fed as f64, "{}", t.text());
    assert!((t.ratio() - 1.0).abs() <= 0.05, "{}", t.text());
}

#[test]
fn the_les_series_holds_more_swirl_than_the_steady_field() {
    let (text, set) = les();
    let les = scg::scene::parse(&text, "cases/cyclone-les.toml", "cyclone-les", &set).unwrap();
    let series = les
        .mesh_flow
        .as_ref()
        .unwrap()
        .series
        .as_ref()
        .expect("a series");
    assert_eq!(series.times.len(), 21);
    let steady = common::case("cyclone", &[]);
    let (vt_les, vr_les) = field_swirl(&les).unwrap();
    let (vt_rans, vr_rans) = field_swirl(&steady).unwrap();
    println!(
        "control surface: LES v_θ {vt_les:.2} m/s, v_r {vr_les:.3}; steady SST v_θ {vt_rans:.2}, v_r {vr_rans:.3}"
    );
    // both carry Q inward through the surface (0.53 m/s by Barth–Muschelknautz's area)
    assert!((vr_les - vr_rans).abs() < 0.1, "{vr_les} {vr_rans}");
    assert!(vt_les > 1.05 * vt_rans, "{vt_les} against {vt_rans}");
}
