use super::*;

const ONES: DVec3 = DVec3::ONE;

fn uniform(k: f64, epsilon: f64) -> Local {
    Local {
        k,
        epsilon,
        grad_sigma: DVec3::ZERO,
    }
}

/// OpenFOAM's convention: |u'| = σ|N(0,1)| in a uniform direction, σ² = 2k/3, so
/// ⟨u'_x²⟩ = ⟨u'_y²⟩ = ⟨u'_z²⟩ = 2k/9 and ⟨|u'|²⟩ = 2k/3. 2·10^5 eddies: the relative
/// standard error of a component's mean square is about √(⟨u⁴⟩/⟨u²⟩² − 1)/√n ≈ 0.5 %
/// (for this law ⟨u_x⁴⟩/⟨u_x²⟩² = 27/5); the tolerance is 2 %.
#[test]
fn stochastic_ras_fluctuation_has_openfoams_variance() {
    let (k, eps, dt) = (1.5, 2.0, 1e-3);
    let n = 200_000;
    let mut sum = DVec3::ZERO;
    let mut sum2 = DVec3::ZERO;
    for id in 0..n {
        // A particle whose eddy has just expired draws a new one.
        let mut s = State {
            age: 10.0,
            ..State::default()
        };
        let mut d = Draws::new(1, id, 0);
        stochastic_ras(
            dt,
            &uniform(k, eps),
            DVec3::ZERO,
            DVec3::ZERO,
            ONES,
            &mut s,
            &mut d,
        );
        assert_eq!(s.age, 0.0);
        sum += s.u;
        sum2 += s.u * s.u;
    }
    let nf = n as f64;
    let want = 2.0 * k / 9.0;
    for c in 0..3 {
        let ms = sum2[c] / nf;
        assert!(
            (ms / want - 1.0).abs() < 0.02,
            "component {c}: {ms} vs {want}"
        );
        assert!((sum[c] / nf).abs() < 5.0 * (want / nf).sqrt(), "mean {c}");
    }
}

/// The eddy lives min(k/ε, C_ps k^1.5/(ε|slip|)); a new particle (age 0, no
/// fluctuation) keeps u' = 0 until its age passes it, then draws; with dt ≥ the lifetime
/// the fluctuation is off and the age is "great" (so the next step with a shorter dt draws
/// at once).
#[test]
fn stochastic_ras_eddy_lifetime_and_switch_off() {
    let (k, eps) = (1.0, 10.0);
    assert_eq!(eddy_lifetime(k, eps, 0.0), k / (eps + 1e-150));
    let slip = 2.0;
    let want = C_PS * k.powf(1.5) / eps / (slip + 1e-15);
    assert!((eddy_lifetime(k, eps, slip) - want).abs() < 1e-15);
    assert!(want < k / eps);

    let t = uniform(k, eps); // lifetime 0.1 s at zero slip
    let dt = 0.03;
    let mut s = State::default();
    let mut steps = 0;
    while s.u == DVec3::ZERO {
        let mut d = Draws::new(2, 0, steps);
        stochastic_ras(dt, &t, DVec3::ZERO, DVec3::ZERO, ONES, &mut s, &mut d);
        steps += 1;
        assert!(steps < 10);
    }
    // ages 0.03, 0.06, 0.09 (≤ 0.1), then 0.12 > 0.1: the fourth step draws.
    assert_eq!(steps, 4);
    let u = s.u;
    for i in 0..3 {
        let mut d = Draws::new(2, 0, 10 + i);
        // a particle moving with its eddy: slip 0
        stochastic_ras(dt, &t, u, DVec3::ZERO, ONES, &mut s, &mut d);
        assert_eq!(s.u, u, "kept for ages 0.03, 0.06, 0.09");
    }
    let mut d = Draws::new(2, 0, 20);
    stochastic_ras(dt, &t, u, DVec3::ZERO, ONES, &mut s, &mut d);
    assert_ne!(s.u, u, "renewed at age 0.12");

    stochastic_ras(0.2, &t, u, DVec3::ZERO, ONES, &mut s, &mut d);
    assert_eq!((s.u, s.age), (DVec3::ZERO, GREAT));
    stochastic_ras(dt, &t, DVec3::ZERO, DVec3::ZERO, ONES, &mut s, &mut d);
    assert_ne!(s.u, DVec3::ZERO, "drawn at once after a switch-off");
    // k = 0: no turbulence, lifetime 0 < dt: off.
    stochastic_ras(
        dt,
        &uniform(0.0, 1.0),
        DVec3::ZERO,
        DVec3::ZERO,
        ONES,
        &mut s,
        &mut d,
    );
    assert_eq!(s.u, DVec3::ZERO);
}

/// A 2-D case's mask zeroes the unsolved direction.
#[test]
fn the_mask_constrains_the_direction() {
    let mask = DVec3::new(1.0, 1.0, 0.0);
    for id in 0..100 {
        let mut s = State {
            age: 1.0,
            ..State::default()
        };
        let mut d = Draws::new(1, id, 0);
        stochastic_ras(
            1e-3,
            &uniform(1.0, 1.0),
            DVec3::ZERO,
            DVec3::ZERO,
            mask,
            &mut s,
            &mut d,
        );
        assert_eq!(s.u.z, 0.0);
        let mut d = Draws::new(1, id, 0);
        langevin(1e-3, &uniform(1.0, 1.0), 2.1, None, mask, &mut s, &mut d);
        assert_eq!(s.u.z, 0.0);
    }
}

/// The Langevin model is stationary at ⟨u'_i²⟩ = 2k/3 per component (it starts there)
/// and its one-step autocorrelation is e^(−dt/T_L): 10^5 particles for 20 steps of
/// dt = T_L/4. Tolerances: 2 % on the variance (standard error 0.45 %), 0.01 on the
/// correlation (standard error 0.003).
#[test]
fn langevin_is_stationary_with_its_lagrangian_time() {
    let (k, eps, c0) = (0.6, 0.3, 2.1);
    let tl = lagrangian_time(k, eps, c0);
    assert!((tl - 2.0 * sigma_of(k).powi(2) / (c0 * eps)).abs() < 1e-12);
    let dt = tl / 4.0;
    let t = uniform(k, eps);
    let n = 100_000u32;
    let mut states = vec![State::default(); n as usize];
    let (mut s2, mut c) = (0.0, 0.0);
    for step in 0..20u64 {
        for (id, s) in states.iter_mut().enumerate() {
            let before = s.u.x;
            let mut d = Draws::new(9, id as u32, step);
            langevin(dt, &t, c0, None, ONES, s, &mut d);
            if step == 19 {
                s2 += s.u.x * s.u.x;
                c += before * s.u.x;
            }
        }
    }
    let var = s2 / n as f64;
    let want = 2.0 * k / 3.0;
    assert!((var / want - 1.0).abs() < 0.02, "variance {var} vs {want}");
    let rho = c / s2;
    assert!((rho - (-0.25f64).exp()).abs() < 0.01, "correlation {rho}");
}

/// With Csanady's correction a particle slipping along x at 1.5σ (β = 1) keeps the
/// stationary variance 2k/3 per component, and its one-step autocorrelation is
/// e^(−dt/(T_L·f)) with f = 1/√(1 + ξ²) along the slip, 1/√(1 + 4ξ²) across it (ξ = 1.5):
/// 10^5 particles for 20 steps of dt = T_L/8. Tolerances as above.
#[test]
fn csanady_shortens_the_time_along_and_across_the_slip() {
    let (k, eps, c0) = (0.6, 0.3, 2.1);
    let tl = lagrangian_time(k, eps, c0);
    let dt = tl / 8.0;
    let t = uniform(k, eps);
    let sigma = sigma_of(k);
    let crossing = Some(Crossing {
        beta: 1.0,
        slip: DVec3::new(1.5 * sigma, 0.0, 0.0),
    });
    let (along, across) = csanady_factors(1.0, DVec3::new(1.5 * sigma, 0.0, 0.0), sigma);
    assert!((along - 1.0 / 3.25f64.sqrt()).abs() < 1e-12);
    assert!((across - 1.0 / 10.0f64.sqrt()).abs() < 1e-12);
    let n = 100_000u32;
    let mut states = vec![State::default(); n as usize];
    let (mut s2, mut c) = (DVec3::ZERO, DVec3::ZERO);
    for step in 0..20u64 {
        for (id, s) in states.iter_mut().enumerate() {
            let before = s.u;
            let mut d = Draws::new(9, id as u32, step);
            langevin(dt, &t, c0, crossing, ONES, s, &mut d);
            if step == 19 {
                s2 += s.u * s.u;
                c += before * s.u;
            }
        }
    }
    let want = 2.0 * k / 3.0;
    for i in 0..3 {
        let var = s2[i] / n as f64;
        assert!(
            (var / want - 1.0).abs() < 0.02,
            "variance {i}: {var} vs {want}"
        );
        let f = if i == 0 { along } else { across };
        let rho = c[i] / s2[i];
        let expect = (-dt / (tl * f)).exp();
        assert!(
            (rho - expect).abs() < 0.01,
            "correlation {i}: {rho} vs {expect}"
        );
    }
}

/// The profile interpolates linearly, clamps or wraps, and its ∇σ is σ's derivative
/// (central differences, to 1e-6 relative).
#[test]
fn profile_values_and_gradient() {
    let p = Profile {
        axis: 1,
        at: vec![0.0, 1.0, 2.0],
        k: vec![1.0, 3.0, 1.0],
        epsilon: vec![2.0, 4.0, 2.0],
        periodic: true,
    };
    let at = |y: f64| p.at(DVec3::new(5.0, y, -3.0));
    assert!((at(0.5).k - 2.0).abs() < 1e-15);
    assert!((at(0.5).epsilon - 3.0).abs() < 1e-15);
    assert!((at(2.5).k - 2.0).abs() < 1e-12, "wrapped");
    assert!((at(-1.5).k - 2.0).abs() < 1e-12, "wrapped below");
    for y in [0.3, 0.7, 1.4] {
        let h = 1e-6;
        let fd = (sigma_of(at(y + h).k) - sigma_of(at(y - h).k)) / (2.0 * h);
        let g = at(y).grad_sigma;
        assert!((g.y - fd).abs() < 1e-6 * fd.abs(), "y {y}: {} vs {fd}", g.y);
        assert_eq!((g.x, g.z), (0.0, 0.0));
    }
    let clamped = Profile {
        periodic: false,
        ..p.clone()
    };
    assert_eq!(clamped.at(DVec3::new(0.0, 7.0, 0.0)).k, 1.0);
    assert_eq!(
        clamped.at(DVec3::new(0.0, 7.0, 0.0)).grad_sigma,
        DVec3::ZERO
    );
}
