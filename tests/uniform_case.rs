//! The paper's uniform-flow case (Table 1, Figs 2–3, Appendix A), end to end.

mod common;

use common::rel;

/// Groups of cases/uniform.toml: 0 original, 1–3 scg (α = 2, 4, 8), 4–6 none, 7–9 mass.
#[test]
fn scg_matches_original_none_lags_mass_leads() {
    let scene = common::case("uniform", &[]);
    let (_, frames) = common::run_frames(&scene);
    assert_eq!(frames.len() as u64, scene.steps() / scene.record_every + 1);
    let u = 1.0;
    let tau0 = 1000.0 * 1e-3 * 1e-3 / (18.0 * 1.8e-5);
    for f in &frames {
        assert_eq!(f.len(), 10);
        let speed = |i: usize| {
            let v = f.velocity[i];
            (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
        };
        let v0 = speed(0);
        // Exact solution for a particle starting at rest.
        let exact = |tau: f64| -u * (-f.time / tau).exp_m1();
        assert!(rel(v0, exact(tau0)) < 1e-12 || f.time == 0.0);
        for (k, alpha) in [2.0_f64, 4.0, 8.0].into_iter().enumerate() {
            // SCG: identical speed at every frame.
            let vs = speed(1 + k);
            assert!(
                rel(vs, v0) < 1e-12 || (vs == 0.0 && v0 == 0.0),
                "scg α={alpha} t={}: {vs} vs {v0}",
                f.time
            );
            if f.time > 0.0 {
                // Without SCG τ grows as α²: slower.
                let vn = speed(4 + k);
                assert!(vn < v0, "none α={alpha} must lag");
                assert!(
                    rel(vn, exact(tau0 * alpha * alpha)) < 1e-12,
                    "none α={alpha} t={}: {vn} vs {}",
                    f.time,
                    exact(tau0 * alpha * alpha)
                );
                // Mass-equivalent: τ shrinks as 1/α: faster.
                let vm = speed(7 + k);
                assert!(vm > v0, "mass α={alpha} must lead");
                assert!(rel(vm, exact(tau0 / alpha)) < 1e-12);
            }
        }
    }
}

/// SCG keeps ρ·d² of every CG group equal to the original's; diameters scale by α.
#[test]
fn table_1_diameters_and_densities() {
    let scene = common::case("uniform", &[]);
    let (mut sim, _) = (scene.build(false), ());
    let ps = sim.particles();
    let rd2 = |i: usize| ps[i].density * ps[i].diameter * ps[i].diameter;
    for (k, alpha, rho) in [(1, 2.0, 250.0), (2, 4.0, 62.5), (3, 8.0, 15.625)] {
        assert!(rel(ps[k].diameter, alpha * 1e-3) < 1e-15);
        assert!(rel(ps[k].density, rho) < 1e-14);
        assert!(rel(rd2(k), rd2(0)) < 1e-15);
        assert_eq!(ps[k + 3].density, 1000.0);
        let m = |i: usize| ps[i].density * ps[i].diameter.powi(3);
        assert!(rel(m(k + 6), m(0)) < 1e-14, "mass law keeps mass");
    }
}

/// Beyond Stokes drag (issue 37): under Schiller–Naumann at the original's Re ≈ 67 (1 mm
/// in 1 m/s air), with gravity and buoyancy, SCG particles whose forces are evaluated as
/// the original's (`[coarse_grain] forces_at = "original"`) follow the original's velocity
/// to 1e-12 at every frame (the default); evaluated for the simulated sphere (`"coarse"`)
/// the α = 8 particle's correction is taken at 8·Re and its buoyancy at its own density,
/// and it departs from the original by more than 10 %.
#[test]
fn scg_forces_at_the_original_keep_equal_acceleration_under_schiller_naumann() {
    let set = [
        "drag.law=\"schiller_naumann\"",
        "gravity.acceleration=[0.0, 0.0, -9.81]",
        "gravity.buoyancy=true",
    ];
    let run = |forces_at: &str| {
        let mut s: Vec<&str> = set.to_vec();
        let f = format!("coarse_grain.forces_at=\"{forces_at}\"");
        s.push(&f);
        let scene = common::case("uniform", &s);
        assert_eq!(scene.scg_at_original, forces_at == "original");
        common::run_frames(&scene).1
    };
    let gap = |frames: &[scg::core::frame::Frame], k: usize| {
        frames
            .iter()
            .filter(|f| f.time > 0.0)
            .map(|f| {
                let (a, b) = (f.velocity[0], f.velocity[k]);
                let d =
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
                d / (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
            })
            .fold(0.0, f64::max)
    };
    let original = run("original");
    let coarse = run("coarse");
    for k in 1..=3 {
        assert!(
            gap(&original, k) < 1e-12,
            "α group {k}: {}",
            gap(&original, k)
        );
    }
    println!(
        "forces_at = \"coarse\": largest relative velocity gap of α = 2, 4, 8: {:.3e} {:.3e} {:.3e}",
        gap(&coarse, 1),
        gap(&coarse, 2),
        gap(&coarse, 3)
    );
    assert!(gap(&coarse, 3) > 0.1, "{}", gap(&coarse, 3));
    // The laws that do not claim equal acceleration are untouched by the option.
    for k in 4..=9 {
        assert_eq!(gap(&original, k), gap(&coarse, k), "group {k}");
    }
}

/// `coarse_grain.forces_at` takes "original" or "coarse": anything else is an error naming
/// the file, the key and the line.
#[test]
fn bad_forces_at_names_the_key() {
    let e = scg::scene::load(
        &common::repo("cases/uniform.toml"),
        &["coarse_grain.forces_at=\"simulated\"".to_string()],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("uniform.toml") && e.contains("forces_at") && e.contains("simulated"),
        "{e}"
    );
}

/// `scg check` says which `forces_at` is in force for each SCG group beyond Stokes drag,
/// and what the other would change (none under Stokes drag, where they agree).
#[test]
fn check_names_the_forces_at_in_force() {
    let msgs = |set: &[&str]| {
        let scene = common::case("uniform", set);
        scg::scene::check::check(&scene).messages().join("\n")
    };
    let m = msgs(&[
        "drag.law=\"schiller_naumann\"",
        "coarse_grain.forces_at=\"original\"",
    ]);
    assert!(
        m.contains("group `scg_8mm` (SCG α = 8): forces_at = \"original\"")
            && m.contains("would take it at"),
        "{m}"
    );
    let m = msgs(&[
        "drag.law=\"schiller_naumann\"",
        "coarse_grain.forces_at=\"coarse\"",
    ]);
    assert!(
        m.contains("forces_at = \"coarse\": the drag correction at the simulated"),
        "{m}"
    );
    // the default is "original"
    let m = msgs(&["drag.law=\"schiller_naumann\""]);
    assert!(m.contains("forces_at = \"original\""), "{m}");
    assert!(!msgs(&[]).contains("forces_at"));
}
