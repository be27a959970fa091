//! Turbulent dispersion alone, side by side with OpenFOAM: `cases/duct.toml`, a 2 m duct
//! with uniform air (1 m/s) and uniform turbulence (k = 0.01 m²/s², ε = 0.1 m²/s³) whose
//! particles end on the `ring` wall around the `core` outlet only if the dispersion moved
//! them off their straight line. OpenFOAM's counts (`cases/duct/openfoam-v1912.json`) are
//! those of `bash cases/cyclone/vs-openfoam.sh --scene cases/duct.toml --split "1 2 1"`:
//! uncoupledKinematicParcelFoam with stochasticDispersionRAS on a frozen kEpsilon model,
//! the same feed, drag, walls and time step.
//!
//! Run: `cargo test --release --test dispersion_duct`.

use std::path::Path;

fn scene(sets: &[&str], without_dispersion: bool) -> scg::scene::Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/duct.toml");
    let mut text = std::fs::read_to_string(path).unwrap();
    if without_dispersion {
        text = drop_dispersion(&text);
    }
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let dir = Path::new(path).parent().unwrap();
    scg::scene::parse_in(&text, path, dir, "duct", &sets).unwrap_or_else(|e| panic!("{e}"))
}

/// The scene text without its `[dispersion]` table (it stands before the first
/// `[[groups]]`).
fn drop_dispersion(text: &str) -> String {
    let at = text.find("[dispersion]").unwrap();
    let end = at + text[at..].find("[[groups]]").unwrap();
    format!("{}{}", &text[..at], &text[end..])
}

/// (group, entered, escaped through `core`, stuck on `ring`, stuck elsewhere, airborne).
fn run(sc: &scg::scene::Scene) -> Vec<(String, u64, u64, u64, u64, u64)> {
    let mut sim = sc.build(false);
    sim.run(sc.steps(), |_| true).unwrap();
    let fates = scg::cli::fates::fates(sc, &mut sim);
    println!("{}", scg::cli::fates::render(&fates));
    fates
        .iter()
        .map(|f| {
            assert_eq!(f.accounted(), f.entered(), "{}", f.group);
            let on = |name: &str, stuck: bool| {
                f.patches
                    .iter()
                    .filter(|p| p.0 == name)
                    .map(|p| if stuck { p.3 } else { p.2 })
                    .sum::<u64>()
            };
            let stuck_all: u64 = f.patches.iter().map(|p| p.3).sum();
            (
                f.group.clone(),
                f.entered(),
                on("core", false),
                on("ring", true),
                stuck_all - on("ring", true),
                f.airborne + f.lost,
            )
        })
        .collect()
}

/// Sanity first: without dispersion the air carries every particle straight through the
/// duct and out of the core, none reaches a wall.
#[test]
fn without_dispersion_every_particle_leaves_through_the_core() {
    let sc = scene(&["feed_scale=0.1"], true);
    assert!(sc.dispersion.is_none());
    for (g, entered, core, ring, other, left) in run(&sc) {
        assert!(entered >= 190, "{g}: {entered}");
        assert_eq!((core, ring, other, left), (entered, 0, 0, 0), "{g}");
    }
}

/// SplitMix64, for the reference below (a stream of its own, not scg's).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn gauss(&mut self) -> f64 {
        let (u, v) = (1.0 - self.next(), self.next());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// The eddy-interaction model for exact tracers, eddy by eddy (no time step): a start
/// uniform over the 80 mm inlet, one lifetime T = k/ε without a fluctuation, then eddies of
/// |N|·√(2k/3) along a uniform direction for T each (OpenFOAM's convention); the fraction
/// that reaches x = 2 m outside the core (|y|, |z| < 0.04 m).
fn tracer_reference(n: usize) -> f64 {
    let (k, t, u, l, h) = (0.01_f64, 0.1, 1.0, 2.0, 0.04);
    let sigma = (2.0 * k / 3.0).sqrt();
    let mut rng = Rng(2026);
    let mut ring = 0;
    for _ in 0..n {
        let (mut y, mut z) = (h * (2.0 * rng.next() - 1.0), h * (2.0 * rng.next() - 1.0));
        let mut x = u * t;
        while x < l {
            let theta = std::f64::consts::TAU * rng.next();
            let c = 2.0 * rng.next() - 1.0;
            let s = (1.0 - c * c).sqrt();
            let g = rng.gauss().abs() * sigma;
            let (ux, uy, uz) = (u + g * s * theta.cos(), g * s * theta.sin(), g * c);
            let dt = if x + ux * t >= l { (l - x) / ux } else { t };
            x += ux * dt;
            y += uy * dt;
            z += uz * dt;
            if dt < t {
                break;
            }
        }
        ring += usize::from(y.abs() > h || z.abs() > h);
    }
    ring as f64 / n as f64
}

/// The fraction on the ring per class against OpenFOAM's (binomial: |diff| within three
/// standard deviations of the two counts' sampling), and the tracers' against the
/// eddy-by-eddy reference (0.364). docs/dispersion.md's duct table is this run: the test
/// checks every number of it (the crossing-trajectory lifetime and inertia shorten the
/// 200 µm's spread alike in both codes).
#[test]
fn dispersion_agrees_with_openfoam_and_the_eddy_reference() {
    let sc = scene(&[], false);
    assert!(sc.dispersion.is_some());
    let ours = run(&sc);
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/duct/openfoam-v1912.json"
    );
    let foam: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let classes = foam["classes"].as_array().unwrap();
    assert_eq!(classes.len(), ours.len());
    let reference = tracer_reference(100_000);
    assert!((reference - 0.364).abs() < 0.006, "reference {reference}");
    // docs/dispersion.md quotes this comparison: its table must say what this run gives.
    let docs = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/dispersion.md"))
        .unwrap();
    let table: Vec<Vec<String>> = docs
        .lines()
        .skip_while(|l| !l.starts_with("| class (1000 kg/m³) |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| l.split('|').map(|c| c.trim().to_string()).collect())
        .collect();
    assert_eq!(table.len(), ours.len(), "docs/dispersion.md's duct table");
    for (k, (c, (g, entered, core, ring, other, left))) in classes.iter().zip(&ours).enumerate() {
        assert_eq!(c["group"].as_str().unwrap(), g);
        assert_eq!(
            (*other, *left > 20),
            (0, false),
            "{g}: {other} stuck elsewhere, {left} left"
        );
        assert_eq!(core + ring + other + left, *entered);
        let n1 = *entered as f64;
        let p1 = *ring as f64 / n1;
        let n2 = c["fed"].as_f64().unwrap();
        let p2 = c["stuck"].as_f64().unwrap() / n2; // all on the ring (its log: back, sides 0)
        let p = (p1 * n1 + p2 * n2) / (n1 + n2);
        let sigma = (p * (1.0 - p) * (1.0 / n1 + 1.0 / n2)).sqrt();
        println!("{g}: scg {p1:.4}, OpenFOAM {p2:.4}, σ {sigma:.4}");
        let diff = 100.0 * (p1 - p2);
        let cells = [
            format!("{p2:.4}"),
            format!("{p1:.4}"),
            format!(
                "{}{:.2}{}",
                if diff < 0.0 { "−" } else { "+" },
                diff.abs(),
                if k == 0 { " pp" } else { "" }
            ),
            format!("{:.2}", 100.0 * sigma),
        ];
        assert_eq!(
            table[k][3..7],
            cells,
            "docs/dispersion.md, duct table row {g}: rewrite it with these"
        );
        assert!(
            (p1 - p2).abs() < 3.0 * sigma,
            "{g}: scg {p1} vs OpenFOAM {p2} (σ {sigma})"
        );
        assert!(p1 > 0.1, "{g}: the dispersion spread them ({p1})");
        if g == "tracer" {
            let s = (reference * (1.0 - reference) / n1).sqrt();
            assert!(
                (p1 - reference).abs() < 3.0 * s,
                "tracer {p1} vs reference {reference}"
            );
        }
    }
    // Inertia and the crossing-trajectory lifetime: the 200 µm spread least.
    assert!(ours[3].3 * 3 < ours[0].3 * 2, "{ours:?}");
}

/// Recordings carry each particle's |u′| (MCAP point field `fluctuation`; the Rerun
/// component is checked in crates/scg-record/tests/rrd.rs) when the scene has dispersion,
/// and `scg replay --verify` checks it bit for bit; without dispersion the points are as
/// before (72 bytes, no such field). Its
/// mean square over the tracers in an eddy is the model's ⟨|u′|²⟩ = 2k/3.
#[test]
fn recordings_carry_the_fluctuation() {
    let dir = tempfile::tempdir().unwrap();
    let scg = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_scg"))
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            out.status.success(),
            "{args:?}: {text}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        text
    };
    let out = dir.path().to_str().unwrap();
    scg(&[
        "run",
        "cases/duct.toml",
        "--out",
        out,
        "--set",
        "duration=0.4",
    ]);
    let mcap = dir.path().join("duct.mcap");
    let rec = scg::record::read_mcap(&mcap).unwrap();
    let last = rec.frames.last().unwrap();
    assert_eq!(last.fluctuation.len(), last.len());
    assert!(last.len() > 1000, "{}", last.len());
    // The tracers (group 0): an inertial particle's eddy ends sooner the larger its slip,
    // hence the larger its |u′|, so a snapshot of them under-samples the large ones.
    let tracers = last.group.iter().filter(|g| **g == 0).count();
    let on: Vec<f64> = (0..last.len())
        .filter(|&i| last.group[i] == 0 && last.fluctuation[i] > 0.0)
        .map(|i| last.fluctuation[i])
        .collect();
    // fed 0..0.4 s, an eddy after 0.1 s: about three quarters carry one
    assert!(on.len() * 2 > tracers, "{} of {tracers}", on.len());
    let mean_sq = on.iter().map(|u| u * u).sum::<f64>() / on.len() as f64;
    let k = 0.01;
    let rel = mean_sq / (2.0 * k / 3.0) - 1.0;
    // ±3 standard errors (|N|² has variance 2)
    assert!(
        rel.abs() < 3.0 * (2.0 / on.len() as f64).sqrt(),
        "⟨|u′|²⟩ {mean_sq}"
    );
    assert!(rec.frames[0].fluctuation.iter().all(|u| *u == 0.0));
    let v = scg(&["replay", mcap.to_str().unwrap(), "--verify"]);
    assert!(v.contains("bit-identical"), "{v}");
    let rrd = std::fs::read(dir.path().join("duct.rrd")).unwrap();
    assert!(
        rrd.windows(11).any(|w| w == b"fluctuation"),
        "no fluctuation in the .rrd"
    );

    // Without dispersion: no fluctuation anywhere.
    let plain = dir.path().join("plain.toml");
    let text = drop_dispersion(&std::fs::read_to_string("cases/duct.toml").unwrap())
        .replace("\"duct/case\"", "\"CASE\"");
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/duct/case");
    std::fs::write(&plain, text.replace("CASE", case)).unwrap();
    let out2 = dir.path().join("plain");
    scg(&[
        "run",
        plain.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
        "--set",
        "duration=0.2",
    ]);
    let rec = scg::record::read_mcap(&out2.join("duct.mcap")).unwrap();
    assert!(rec.frames.iter().all(|f| f.fluctuation.is_empty()));
}
