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
