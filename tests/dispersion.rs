//! Turbulent dispersion against its analytic references (docs/dispersion.md): Taylor
//! dispersion of tracers in homogeneous turbulence under OpenFOAM's eddy model and the
//! Langevin model, their velocity variances, inertial particles against an independent
//! implementation of the eddy model, the well-mixed condition (which the Langevin model's
//! drift correction keeps and the eddy model fails), SCG under dispersion, and
//! determinism over thread counts and restarts.
//!
//! Run: `cargo test --release --test dispersion -- --nocapture` (prints every measured
//! figure with its interval).

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use scg::core::exec::{ExecSettings, with_settings};
use scg::core::physics::dispersion::{Model, Profile, Turbulence, lagrangian_time};
use scg::core::physics::drag::DragLaw;
use scg::core::physics::flow::{FlowField, Fluid};
use scg::core::physics::integrate::Integrator;
use scg::core::physics::scaling::CoarseGrainLaw;
use scg::core::stages::carrier::{CarrierModifier, Dispersion};
use scg::core::{ParticleSpec, SimConfig, Simulation};

const MU: f64 = 1.8e-5;
const RHO: f64 = 1000.0;
/// A tracer: 1 µm, τ = 3.1 µs.
const TRACER: f64 = 1e-6;

fn tau_of(d: f64) -> f64 {
    RHO * d * d / (18.0 * MU)
}

fn sim(dt: f64, model: Model, turbulence: Turbulence, seed: u64) -> Simulation {
    Simulation::new(SimConfig {
        dt,
        integrator: Integrator::Exponential,
        drag: Some(DragLaw::Stokes),
        fluid: Some(Fluid {
            density: 1.2,
            viscosity: MU,
        }),
        flow: FlowField::Still,
        mesh_flow: None,
        gravity: None,
        buoyancy: false,
        scg_at_original: false,
        extra_forces: Default::default(),
        walls: None,
        contacts: None,
        record_every: None,
        groups: vec!["p".into()],
        carrier: Some(CarrierModifier::Dispersion(Dispersion {
            model,
            turbulence,
            seed,
            mask: DVec3::ONE,
            own_pass: false,
        })),
    })
}

fn spec(d: f64, alpha: f64, position: DVec3) -> ParticleSpec {
    ParticleSpec {
        group: 0,
        diameter: d,
        density: RHO,
        alpha,
        law: CoarseGrainLaw::Scg,
        position,
        velocity: DVec3::ZERO,
    }
}

/// Mean square of the three components of each particle's displacement, per component,
/// with its 95 % interval (1.96 standard errors over the particles).
fn spread(s: &mut Simulation) -> (f64, f64) {
    let ps = s.particles();
    let n = ps.len() as f64;
    let sq: Vec<f64> = ps
        .iter()
        .map(|p| p.position.length_squared() / 3.0)
        .collect();
    let m = sq.iter().sum::<f64>() / n;
    let var = sq.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, 1.96 * (var / n).sqrt())
}

/// OpenFOAM's eddy model, homogeneous turbulence, tracers: each eddy lasts the first whole
/// number of steps whose age exceeds k/ε, and a particle enters with no fluctuation for
/// its first lifetime. So after the entry steps n0 and M eddies of n steps each, the
/// position variance per component is exactly M·⟨u'_x²⟩·(n·dt)² with OpenFOAM's
/// ⟨u'_x²⟩ = 2k/9 — a long-time diffusivity D = ⟨u'_x²⟩·n·dt/2. 20 000 tracers, 30 eddies;
/// tolerance 3 % (the 95 % interval is about 1.3 %). The velocity variance: ⟨|v|²⟩ of
/// the tracers sampled in 10 eddies equals 2k/3 within 2 % (interval about 0.7 %).
#[test]
fn stochastic_ras_tracers_follow_taylor_dispersion() {
    let (k, eps) = (1.5, 15.0); // σ = 1 m/s, k/ε = 0.1 s
    let dt = 0.012; // 0.1/0.012 = 8.33: an eddy lasts 9 steps
    let n_eddy = 9u64;
    let n0 = 8u64; // steps before the first draw (age 0.108 > 0.1 at the ninth)
    let mut s = sim(
        dt,
        Model::StochasticRas,
        Turbulence::Uniform { k, epsilon: eps },
        3,
    );
    let n = 20_000;
    for _ in 0..n {
        s.spawn(&spec(TRACER, 1.0, DVec3::ZERO));
    }
    for _ in 0..n0 {
        s.step().unwrap();
    }
    assert_eq!(
        spread(&mut s).0,
        0.0,
        "no fluctuation before the first lifetime"
    );
    let mut v2 = Vec::new();
    let eddies = 30;
    for e in 0..eddies {
        for _ in 0..n_eddy {
            s.step().unwrap();
        }
        if e % 3 == 0 {
            v2.extend(s.particles().iter().map(|p| p.velocity.length_squared()));
        }
    }
    let ux2 = 2.0 * k / 9.0;
    let t_eddy = n_eddy as f64 * dt;
    let want = eddies as f64 * ux2 * t_eddy * t_eddy;
    let (got, ci) = spread(&mut s);
    println!(
        "stochastic_ras tracers: <x^2> = {got:.5e} ± {ci:.1e} m^2, model {want:.5e} \
         (D = {:.4e} m^2/s)",
        ux2 * t_eddy / 2.0
    );
    assert!((got / want - 1.0).abs() < 0.03, "{got} vs {want}");
    let m = v2.iter().sum::<f64>() / v2.len() as f64;
    println!(
        "stochastic_ras tracers: <|u'|^2> = {m:.5} m^2/s^2, model 2k/3 = {}",
        2.0 * k / 3.0
    );
    assert!((m / (2.0 * k / 3.0) - 1.0).abs() < 0.02, "{m}");
}

/// The Langevin model, homogeneous turbulence, tracers starting at rest in a stationary
/// fluctuation: Taylor's 2σ²T_L[t − T_L(1 − e^(−t/T_L))] per component (σ² = 2k/3,
/// T_L = 4k/(3·C₀·ε)), at t = 0.5, 2 and 8 T_L, within 3 %; dt = T_L/20 (the
/// discrete walk's own variance differs from the continuous curve by less than 1 % there).
/// The tracers' velocity variance is 2k/3 per component within 2 %.
#[test]
fn langevin_tracers_follow_taylors_curve() {
    let (k, eps, c0) = (0.6, 0.8, 2.1);
    let tl = lagrangian_time(k, eps, c0);
    let dt = tl / 20.0;
    let sigma2 = 2.0 * k / 3.0;
    let mut s = sim(
        dt,
        Model::Langevin { c0, csanady: None },
        Turbulence::Uniform { k, epsilon: eps },
        5,
    );
    let n = 20_000;
    for _ in 0..n {
        s.spawn(&spec(TRACER, 1.0, DVec3::ZERO));
    }
    let mut step = 0u64;
    for t_over in [0.5, 2.0, 8.0] {
        let target = (t_over * 20.0_f64).round() as u64;
        while step < target {
            s.step().unwrap();
            step += 1;
        }
        let t = step as f64 * dt;
        let want = 2.0 * sigma2 * tl * (t - tl * (1.0 - (-t / tl).exp()));
        let (got, ci) = spread(&mut s);
        println!(
            "langevin tracers at t = {t_over} T_L: <x^2> = {got:.5e} ± {ci:.1e}, Taylor {want:.5e}"
        );
        assert!((got / want - 1.0).abs() < 0.03, "t {t}: {got} vs {want}");
    }
    let ps = s.particles();
    let m = ps.iter().map(|p| p.velocity.length_squared()).sum::<f64>() / (3.0 * n as f64);
    println!("langevin tracers: <u'_i^2> = {m:.5}, model 2k/3 = {sigma2:.5}");
    assert!((m / sigma2 - 1.0).abs() < 0.02);
}

/// One inertial particle under OpenFOAM's eddy model, written out independently of scg
/// (exact Stokes relaxation over each step, OpenFOAM's update with a ChaCha stream):
/// the position variance after `steps` steps, per component, with its 95 % interval.
fn reference_eddy_model(k: f64, eps: f64, tau: f64, dt: f64, steps: u64, n: usize) -> (f64, f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let sigma = (2.0 * k / 3.0).sqrt();
    let e = (-dt / tau).exp();
    let mut sq = Vec::with_capacity(n);
    for _ in 0..n {
        let (mut x, mut v, mut ut, mut age) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO, 0.0);
        for _ in 0..steps {
            let slip = (v - ut).length();
            let life = (k / eps).min(0.16432 * k.powf(1.5) / eps / (slip + 1e-15));
            if dt < life {
                age += dt;
                if age > life {
                    age = 0.0;
                    let theta = rng.random::<f64>() * std::f64::consts::TAU;
                    let u: f64 = 2.0 * rng.random::<f64>() - 1.0;
                    let a = (1.0 - u * u).sqrt();
                    // |N(0,1)| by Box–Muller
                    let r = (-2.0 * (1.0 - rng.random::<f64>()).ln()).sqrt();
                    let g = (r * (std::f64::consts::TAU * rng.random::<f64>()).cos()).abs();
                    ut = sigma * g * DVec3::new(a * theta.cos(), a * theta.sin(), u);
                }
            } else {
                age = 1e15;
                ut = DVec3::ZERO;
            }
            x += ut * dt + (v - ut) * tau * (1.0 - e);
            v = ut + (v - ut) * e;
        }
        sq.push(x.length_squared() / 3.0);
    }
    let m = sq.iter().sum::<f64>() / n as f64;
    let var = sq.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n as f64 - 1.0);
    (m, 1.96 * (var / n as f64).sqrt())
}

/// Inertial particles (τ = k/ε) under the eddy model: the crossing-trajectory lifetime
/// shortens their eddies, so they spread less than tracers; scg's spread agrees with the
/// independent implementation within the two 95 % intervals combined.
#[test]
fn inertial_particles_follow_the_eddy_models_reduced_diffusivity() {
    let (k, eps) = (1.5, 15.0);
    let dt = 0.004;
    let steps = 500; // 2 s = 20 k/ε
    let d = (0.1 * 18.0 * MU / RHO).sqrt(); // τ = 0.1 s
    assert!((tau_of(d) - 0.1).abs() < 1e-12);
    let n = 10_000;
    let mut s = sim(
        dt,
        Model::StochasticRas,
        Turbulence::Uniform { k, epsilon: eps },
        7,
    );
    let mut t = sim(
        dt,
        Model::StochasticRas,
        Turbulence::Uniform { k, epsilon: eps },
        7,
    );
    for _ in 0..n {
        s.spawn(&spec(d, 1.0, DVec3::ZERO));
        t.spawn(&spec(TRACER, 1.0, DVec3::ZERO));
    }
    for _ in 0..steps {
        s.step().unwrap();
        t.step().unwrap();
    }
    let (got, ci) = spread(&mut s);
    let (tracer, tci) = spread(&mut t);
    let (want, wci) = reference_eddy_model(k, eps, 0.1, dt, steps, n);
    println!(
        "eddy model, τ = k/ε: scg <x^2> = {got:.4e} ± {ci:.1e}, reference {want:.4e} ± {wci:.1e}; \
         tracers {tracer:.4e} ± {tci:.1e}"
    );
    assert!((got - want).abs() < ci + wci, "{got} vs {want}");
    assert!(got + ci < tracer - tci, "inertial particles spread less");
}

/// A k field varying along x (×4 over a period of 0.2 m, ε ∝ k so T_L is uniform): tracers
/// released uniformly must stay uniform (the well-mixed condition). With the Langevin
/// model's drift correction the 10 bins of a period hold their share within 5 % after
/// 1 s (12 Lagrangian times); OpenFOAM's eddy model has no such correction and unmixes —
/// tracers gather where k is low (the bins' max/min ratio is printed and asserted > 1.2).
#[test]
fn langevin_keeps_tracers_well_mixed_and_the_eddy_model_does_not() {
    let l = 0.2;
    let nodes = 17;
    let at: Vec<f64> = (0..nodes)
        .map(|i| l * i as f64 / (nodes - 1) as f64)
        .collect();
    let k: Vec<f64> = at
        .iter()
        .map(|x| 0.5 + 0.3 * (std::f64::consts::TAU * x / l).sin())
        .collect();
    let mut k = k;
    k[nodes - 1] = k[0];
    let epsilon: Vec<f64> = k.iter().map(|k| 12.7 * k).collect();
    let profile = Turbulence::Profile(Profile {
        axis: 0,
        at,
        k,
        epsilon,
        periodic: true,
    });
    let dt = 0.0025;
    let steps = 400;
    let n = 100_000;
    let bins = |s: &mut Simulation| -> Vec<f64> {
        let mut b = vec![0.0; 10];
        for p in s.particles() {
            let x = p.position.x.rem_euclid(l);
            b[((x / l * 10.0) as usize).min(9)] += 10.0 / n as f64;
        }
        b
    };
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let starts: Vec<DVec3> = (0..n)
        .map(|_| DVec3::new(rng.random::<f64>() * l, 0.0, 0.0))
        .collect();
    let mut results = Vec::new();
    for model in [
        Model::Langevin {
            c0: 2.1,
            csanady: None,
        },
        Model::StochasticRas,
    ] {
        let mut s = sim(dt, model, profile.clone(), 9);
        for x in &starts {
            s.spawn(&spec(TRACER, 1.0, *x));
        }
        for _ in 0..steps {
            s.step().unwrap();
        }
        let b = bins(&mut s);
        let (lo, hi) = b
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, c), &x| (a.min(x), c.max(x)));
        println!(
            "well-mixed, {}: bin shares (1 = uniform) {b:.3?}, max/min {:.3}",
            model.name(),
            hi / lo
        );
        results.push((b, hi / lo));
    }
    for (i, x) in results[0].0.iter().enumerate() {
        assert!((x - 1.0).abs() < 0.05, "langevin bin {i}: {x}");
    }
    assert!(
        results[1].1 > 1.2,
        "the eddy model unmixes: max/min {}",
        results[1].1
    );
}

/// SCG under dispersion: 10 µm-class inertial particles (τ = 20 ms) coarse-grained by
/// α = 1, 2, 4 (ρ·d² constant, so τ and the slip are the original's) spread alike in
/// homogeneous turbulence under both models: each pair of position variances agrees
/// within the two 95 % intervals combined. Independent samples (a different seed each).
#[test]
fn scg_ratios_spread_alike_under_dispersion() {
    let d = (0.02 * 18.0 * MU / RHO).sqrt();
    let (k, eps) = (1.5, 15.0);
    for model in [
        Model::StochasticRas,
        Model::Langevin {
            c0: 2.1,
            csanady: None,
        },
    ] {
        let mut out = Vec::new();
        for (i, alpha) in [1.0, 2.0, 4.0].into_iter().enumerate() {
            let mut s = sim(
                0.004,
                model,
                Turbulence::Uniform { k, epsilon: eps },
                20 + i as u64,
            );
            for _ in 0..8000 {
                s.spawn(&spec(d, alpha, DVec3::ZERO));
            }
            for _ in 0..250 {
                s.step().unwrap();
            }
            out.push(spread(&mut s));
        }
        println!("{}: α = 1, 2, 4: {out:?}", model.name());
        for i in 0..3 {
            for j in i + 1..3 {
                let ((a, ca), (b, cb)) = (out[i], out[j]);
                assert!((a - b).abs() < ca + cb, "{}: {a} vs {b}", model.name());
            }
        }
    }
}

/// The particles' bits after a run of `steps`.
fn bits(s: &mut Simulation) -> Vec<[u64; 6]> {
    s.particles()
        .iter()
        .map(|p| {
            let (x, v) = (p.position, p.velocity);
            [x.x, x.y, x.z, v.x, v.y, v.z].map(f64::to_bits)
        })
        .collect()
}

/// Same seed, same bits: on 1 and 2 threads (pieces cut small so both threads work), and
/// after a checkpoint and restore halfway (the fluctuation and the eddy's age are state).
#[test]
fn dispersion_is_bit_identical_over_threads_and_restarts() {
    for model in [
        Model::StochasticRas,
        Model::Langevin {
            c0: 2.1,
            csanady: None,
        },
    ] {
        let build = || {
            let mut s = sim(
                0.004,
                model,
                Turbulence::Uniform {
                    k: 1.5,
                    epsilon: 15.0,
                },
                4,
            );
            for i in 0..3000 {
                let d = if i % 2 == 0 { TRACER } else { 50e-6 };
                s.spawn(&spec(d, 1.0, DVec3::new(i as f64 * 1e-3, 0.0, 0.0)));
            }
            s
        };
        let run = |threads: usize| {
            with_settings(
                ExecSettings {
                    threads,
                    parallel_min: 64,
                    ..ExecSettings::default()
                },
                || {
                    let mut s = build();
                    for _ in 0..100 {
                        s.step().unwrap();
                    }
                    bits(&mut s)
                },
            )
        };
        let one = run(1);
        assert_eq!(one, run(2), "{}: 1 vs 2 threads", model.name());
        let mut a = build();
        for _ in 0..50 {
            a.step().unwrap();
        }
        let c = a.checkpoint();
        let mut b = build();
        b.restore(&c).unwrap();
        for _ in 0..50 {
            b.step().unwrap();
        }
        assert_eq!(one, bits(&mut b), "{}: after a restart", model.name());
    }
}
