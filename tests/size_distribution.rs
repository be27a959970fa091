//! Feeds as size distributions (`groups[i].size`), end to end on cases/settling.toml: a
//! laminar settling chamber whose grade efficiency is known in closed form. The fed sizes
//! follow the distribution per report bin, each bin's share collected on the floor
//! matches theory, and so does the collected share of the mass (the quadrature over the
//! bins) within its 95 % interval — for the originals, SCG α = 2 and plain sampling
//! α = 2. Bad `size` tables are refused naming their key.

use scg::core::components::{CoarseGrain, GroupId};
use scg::core::physics::size_distribution::Basis;

fn scene(set: &[&str]) -> scg::scene::Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/settling.toml");
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    scg::scene::load(&path, &set).unwrap_or_else(|e| panic!("{e}"))
}

/// The chamber's grade efficiency at original size `d` (m) for a particle of simulated
/// radius `r` (m): the share of inlet heights h ∈ [0.001, 0.101] m with h − r ≤ the Stokes
/// fall from rest v_t·(T − τ(1 − e^(−T/τ))) within the transit T = (L − r)/U.
fn eta(d: f64, r: f64) -> f64 {
    let (rho, mu, g, u, l) = (1000.0, 1.8e-5, 9.81, 1.0, 1.0);
    let tau = rho * d * d / (18.0 * mu);
    let vt = tau * g;
    let t = (l - r) / u;
    let fall = vt * (t - tau * (1.0 - (-t / tau).exp()));
    ((fall + r - 0.001) / 0.1).clamp(0.0, 1.0)
}

/// Number-weighted mean of `f` over the sizes in [lo, hi] of the distribution.
fn number_mean(s: &scg::scene::SizeBin, f: impl Fn(f64) -> f64) -> f64 {
    let (lo, hi) = s.range();
    let k = 2000;
    let (mut sum, mut w) = (0.0, 0.0);
    for i in 0..k {
        let (a, b) = (
            lo + (hi - lo) * i as f64 / k as f64,
            lo + (hi - lo) * (i + 1) as f64 / k as f64,
        );
        let dq = s.distribution.share(a, b, Basis::Number);
        sum += dq * f(0.5 * (a + b));
        w += dq;
    }
    sum / w
}

struct Outcome {
    /// Per bin: (mass share, collected, fed, expected share collected).
    bins: Vec<(f64, u64, u64, f64)>,
    /// The collected share of the mass and its 95 % interval.
    by_mass: (f64, f64, f64),
    /// Σ w·E[η | bin] (what the bin estimate estimates) and ∫ η·q₃ dd.
    expected: (f64, f64),
}

fn run(set: &[&str]) -> Outcome {
    let scene = scene(set);
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    let fates = scg::cli::fates::fates(&scene, &mut sim);
    let floor = "stuck on `wall floor` (wall)";
    let mut bins = Vec::new();
    for (g, f) in scene.groups.iter().zip(&fates) {
        let s = g.size.as_ref().expect("a size bin");
        let stuck = f
            .patches
            .iter()
            .find(|p| p.0 == "wall floor")
            .map_or(0, |p| p.3);
        let r = 0.5
            * scg::core::physics::scaling::coarse_grain(g.law, g.alpha, g.diameter, g.density)
                .diameter;
        bins.push((
            s.mass_share(),
            stuck,
            f.entered(),
            number_mean(s, |d| eta(d, r)),
        ));
        assert_eq!(
            f.accounted(),
            f.entered(),
            "{}: every particle has a fate",
            g.name
        );
        assert_eq!(f.airborne, 0, "{}: all have left by the end", g.name);
    }
    let d = scg::cli::distribution::by_mass(&scene, &fates);
    assert_eq!(d.len(), 1);
    let m = d[0]
        .shares
        .iter()
        .find(|m| m.what == floor)
        .expect("the floor's share");
    let dist = &scene.groups[0].size.as_ref().unwrap().distribution;
    let binned: f64 = bins.iter().map(|b| b.0 * b.3).sum();
    let exact = dist.total_efficiency(|d| eta(d, 0.5 * d));
    Outcome {
        bins,
        by_mass: (m.share, m.lo, m.hi),
        expected: (binned, exact),
    }
}

#[test]
fn settling_chamber_matches_its_closed_form_per_bin_and_by_mass() {
    for (name, set) in [
        ("originals", vec![]),
        (
            "scg α = 2",
            vec!["coarse_grain.alpha=2", "coarse_grain.law=scg"],
        ),
        (
            "sample α = 2",
            vec!["coarse_grain.alpha=2", "coarse_grain.law=sample"],
        ),
    ] {
        let o = run(&set);
        let (share, lo, hi) = o.by_mass;
        let (binned, exact) = o.expected;
        eprintln!(
            "{name}: collected by mass {:.2} % [{:.2}, {:.2}]; theory over the bins {:.2} %, \
             ∫η·q₃ {:.2} %; fed {}",
            100.0 * share,
            100.0 * lo,
            100.0 * hi,
            100.0 * binned,
            100.0 * exact,
            o.bins.iter().map(|b| b.2).sum::<u64>()
        );
        assert!(
            lo <= binned && binned <= hi,
            "{name}: {binned} outside [{lo}, {hi}]"
        );
        // each bin within 3.3 binomial standard deviations (99.9 %)
        for (i, &(_, k, n, e)) in o.bins.iter().enumerate() {
            if n == 0 {
                continue;
            }
            let sd = (e * (1.0 - e) / n as f64).sqrt().max(0.5 / n as f64);
            let p = k as f64 / n as f64;
            assert!((p - e).abs() <= 3.3 * sd, "{name} bin {i}: {k}/{n} vs {e}");
        }
        // binning (number-weighted η in each bin instead of mass-weighted) moves the
        // estimate by less than a point here
        assert!((binned - exact).abs() < 0.01, "{binned} vs {exact}");
    }
}

#[test]
fn fed_sizes_follow_the_distribution_and_sit_in_their_bins() {
    for set in [vec![], vec!["coarse_grain.alpha=2"]] {
        let scene = scene(&set);
        let mut sim = scene.build(false);
        sim.run(500, |_| true).unwrap(); // 0.5 s: feeding; nothing has reached the exit yet
        let mut q = sim
            .world
            .query::<(&GroupId, &CoarseGrain, &scg::core::components::Diameter)>();
        let mut per_bin = vec![0u64; scene.groups.len()];
        for (g, cg, d) in q.iter(&sim.world) {
            let grp = &scene.groups[g.0 as usize];
            let (lo, hi) = grp.size.as_ref().unwrap().range();
            let d0 = cg.original_diameter;
            assert!(d0 >= lo && d0 <= hi, "{d0} outside [{lo}, {hi}]");
            assert!(
                (d.0 - grp.alpha * d0).abs() <= 1e-15 * d.0,
                "simulated d = α·d₀"
            );
            per_bin[g.0 as usize] += 1;
        }
        let fates = scg::cli::fates::fates(&scene, &mut sim);
        let fed: Vec<u64> = fates.iter().map(|f| f.fed).collect();
        let n: u64 = fed.iter().sum();
        // the rate from mass_rate: 4e-8 kg/s over the mean particle (α³ originals)
        let dist = &scene.groups[0].size.as_ref().unwrap().distribution;
        let alpha: f64 = scene.groups[0].alpha;
        let per_particle = 1000.0 * std::f64::consts::PI / 6.0 * alpha.powi(3) * dist.mean_d3();
        let want = (4.0e-8 / per_particle * 0.5).floor() as u64;
        assert!(n.abs_diff(want) <= 1, "fed {n}, want {want}");
        // counts per bin against the number shares: χ² with 11 degrees of freedom below
        // its 99.9 % point, 31.3 (bins expecting fewer than 5 pooled into the last)
        let (mut chi2, mut pooled_n, mut pooled_e) = (0.0, 0.0, 0.0);
        for (g, k) in scene.groups.iter().zip(&fed) {
            let (lo, hi) = g.size.as_ref().unwrap().range();
            let e = n as f64 * dist.share(lo, hi, Basis::Number);
            if e < 5.0 {
                pooled_n += *k as f64;
                pooled_e += e;
            } else {
                chi2 += (*k as f64 - e).powi(2) / e;
            }
        }
        if pooled_e > 0.0 {
            chi2 += (pooled_n - pooled_e).powi(2) / pooled_e;
        }
        eprintln!("α {alpha}: {n} fed, χ² {chi2:.1}");
        assert!(chi2 < 31.3, "χ² {chi2}");
        for ((f, k), inside) in fates.iter().zip(&fed).zip(&per_bin) {
            // the ones not on the floor yet are in the domain, in their bin's group
            assert_eq!(f.airborne, *inside);
            assert_eq!(f.accounted(), *k);
        }
    }
}

#[test]
fn same_seed_same_sizes_and_a_checkpoint_keeps_the_stream() {
    let scene = scene(&[]);
    let steps = scene.steps();
    let mut whole = scene.build(false);
    whole.run(steps, |_| true).unwrap();
    let mut a = scene.build(false);
    a.run(400, |_| true).unwrap();
    let c = a.checkpoint();
    let mut b = scene.build(false);
    b.restore(&c).unwrap();
    b.run(steps - 400, |_| true).unwrap();
    let fw = scg::cli::fates::fates(&scene, &mut whole);
    let fb = scg::cli::fates::fates(&scene, &mut b);
    assert_eq!(fw, fb);
    assert!(fw.iter().map(|f| f.fed).sum::<u64>() > 10_000);
}

#[test]
fn bad_size_tables_are_refused_with_their_key() {
    let cases: &[(&[&str], &str)] = &[
        (&["groups.0.diameter=1e-5"], "groups[0].diameter"),
        (&["groups.0.size.basis=\"volume\""], "basis"),
        (&["groups.0.size.distribution=\"gamma\""], "distribution"),
        (&["groups.0.size.median=1e-5"], "groups[0].size.median"),
        (&["groups.0.size.bins=0"], "groups[0].size.bins"),
        (&["groups.0.size.bins=[5e-6, 1e-5]"], "groups[0].size.bins"),
        (&["groups.0.size.min=9e-5"], "groups[0].size.max"),
        (&["groups.0.size.spread=-1"], "groups[0].size.spread"),
        (&["feeders.0.group=\"other\""], "groups[0].size"), // no feeder feeds it
    ];
    for (set, key) in cases {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/settling.toml");
        let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
        let e = scg::scene::load(&path, &set)
            .err()
            .unwrap_or_else(|| panic!("{set:?} accepted"));
        let msg = e.to_string();
        assert!(
            msg.contains(key) && msg.contains("settling.toml"),
            "{set:?}: {msg}"
        );
    }
}
