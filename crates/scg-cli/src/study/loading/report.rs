//! The loading study's table (Markdown), CSV and `summary.json`, from one flat [`Record`]
//! per method and loading (what the tables show, JSON-safe: a missing number is `null`,
//! never NaN, so `--from DIR --markdown` prints the same table from the summary).

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use super::Row;

/// What the tables show of one method at one loading.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Multiple of the scene's feed rate.
    pub loading: f64,
    /// Method name (`original`, `scg2`, …).
    pub method: String,
    /// Law name (`original` at α = 1, `scg`, `sample`, …).
    pub law: String,
    /// α.
    pub alpha: f64,
    /// Mean simulated particles.
    pub particles: f64,
    /// Wall time of the run, s.
    pub wall_s: f64,
    /// Particle-steps.
    pub particle_steps: u64,
    /// Particle–particle contacts started.
    pub pair_contacts: u64,
    /// Particle–wall contacts started.
    pub wall_contacts: u64,
    /// Contacts per particle per simulated second, 1/s.
    pub contact_rate: Option<f64>,
    /// The class whose W1 stands farthest above its noise.
    pub worst_class: Option<String>,
    /// Its W1 / vessel radius.
    pub w1: Option<f64>,
    /// Its 95 % bootstrap interval (a bound `None` where not finite).
    pub w1_95: Option<(Option<f64>, Option<f64>)>,
    /// Its sampling-noise W1 (permutation test's 95 % quantile) / vessel radius.
    pub w1_noise95: Option<f64>,
    /// Every class's W1 within its noise.
    pub w1_agrees: Option<bool>,
    /// Cut size, m.
    pub d50: Option<f64>,
    /// Its 95 % bootstrap interval, m (a bound `None` where open).
    pub d50_95: Option<(Option<f64>, Option<f64>)>,
    /// d50 within the two intervals of the originals' (None when either is missing).
    pub d50_agrees: Option<bool>,
    /// Agrees with the originals within the intervals (None: the originals themselves,
    /// or a failed run).
    pub agrees: Option<bool>,
    /// Why the run failed, if it did.
    pub failure: Option<String>,
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

impl Record {
    /// The record of a row.
    pub fn of(r: &Row) -> Record {
        let o = &r.outcome;
        let c = o.classes.as_ref();
        let original = r.law().is_none();
        // the class farthest beyond its noise (largest W1/noise)
        let worst = c.and_then(|c| {
            (0..c.w1.len())
                .filter(|&i| c.w1[i].is_finite() && c.w1_noise95[i] > 0.0)
                .max_by(|&a, &b| {
                    (c.w1[a] / c.w1_noise95[a]).total_cmp(&(c.w1[b] / c.w1_noise95[b]))
                })
        });
        let pick = |f: &dyn Fn(&crate::cost::ClassErrors, usize) -> f64| -> Option<f64> {
            if original {
                return None;
            }
            c.zip(worst).and_then(|(c, i)| finite(f(c, i)))
        };
        let w1_agrees = (!original).then(|| c.is_some_and(|c| c.w1_agrees()));
        let d50_agrees = c.and_then(|c| c.d50_agrees);
        Record {
            loading: r.loading,
            method: r.method.clone(),
            law: o.point.law_name().to_string(),
            alpha: o.point.alpha,
            particles: o.particles(),
            wall_s: o.wall_s,
            particle_steps: o.particle_steps,
            pair_contacts: o.pair_contacts,
            wall_contacts: o.wall_contacts,
            contact_rate: finite(o.contact_rate()),
            worst_class: if original {
                None
            } else {
                c.zip(worst).map(|(c, i)| c.names[i].clone())
            },
            w1: pick(&|c, i| c.w1[i]),
            w1_95: (!original)
                .then(|| {
                    c.zip(worst)
                        .map(|(c, i)| (finite(c.w1_95[i].0), finite(c.w1_95[i].1)))
                })
                .flatten(),
            w1_noise95: pick(&|c, i| c.w1_noise95[i]),
            w1_agrees,
            d50: c.and_then(|c| c.d50),
            d50_95: c
                .and_then(|c| c.d50_95)
                .map(|(lo, hi)| (finite(lo), finite(hi))),
            d50_agrees,
            agrees: if original || o.failure.is_some() || c.is_none() {
                None
            } else {
                Some(w1_agrees == Some(true) && d50_agrees != Some(false))
            },
            failure: o.failure.clone(),
        }
    }

    /// Kinetic theory's collision frequency of this method's particle from the originals'
    /// `f0` at the same loading: f ∝ n·d²·|Δv| with n/α³ particles, so f0/α for SCG
    /// (diameter α·d, the same velocities), f0/α³ for sampling, f0 for the originals.
    pub fn predicted_rate(&self, f0: f64) -> f64 {
        let a = self.alpha;
        match self.law.as_str() {
            "original" => f0,
            "sample" => f0 / (a * a * a),
            _ => f0 / a,
        }
    }
}

/// The originals' record at `loading`.
fn original(records: &[Record], loading: f64) -> Option<&Record> {
    records
        .iter()
        .find(|r| r.loading == loading && r.law == "original")
}

/// The loadings in run order.
pub fn loadings(records: &[Record]) -> Vec<f64> {
    let mut l: Vec<f64> = Vec::new();
    for r in records {
        if !l.contains(&r.loading) {
            l.push(r.loading);
        }
    }
    l
}

fn um(x: Option<f64>) -> String {
    x.map_or("…".into(), |x| format!("{:.1}", x * 1e6))
}

fn opt(x: Option<f64>, f: impl Fn(f64) -> String) -> String {
    x.map_or("—".into(), f)
}

/// What the sweep says, loading by loading: which methods agree with the originals, and
/// the first loading where sampling departs.
pub fn verdicts(records: &[Record]) -> Vec<String> {
    let mut v = Vec::new();
    for l in loadings(records) {
        let here = records.iter().filter(|r| r.loading == l);
        let (ok, off): (Vec<&Record>, Vec<&Record>) = here
            .filter(|r| r.agrees.is_some())
            .partition(|r| r.agrees == Some(true));
        let names = |x: &[&Record]| {
            if x.is_empty() {
                "none".to_string()
            } else {
                x.iter()
                    .map(|r| r.method.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        };
        v.push(format!(
            "×{l}: agree with the originals within the intervals: {}; differ: {}",
            names(&ok),
            names(&off)
        ));
    }
    let first = loadings(records).into_iter().find(|l| {
        records
            .iter()
            .any(|r| r.loading == *l && r.law == "sample" && r.agrees == Some(false))
    });
    v.push(match first {
        Some(l) => {
            let scg = records
                .iter()
                .filter(|r| r.loading == l && r.law == "scg")
                .map(|r| {
                    format!(
                        "{} {}",
                        r.method,
                        if r.agrees == Some(true) {
                            "holds"
                        } else {
                            "departs too"
                        }
                    )
                })
                .collect::<Vec<_>>()
                .join(", ");
            format!(
                "sampling first departs from the originals beyond its interval at ×{l}; there \
                 SCG: {scg}"
            )
        }
        None => "sampling agrees with the originals within its intervals at every loading run: \
                 at these loadings SCG buys nothing sampling does not"
            .into(),
    });
    v
}

/// The Markdown table of the sweep, with the verdicts.
pub fn markdown(records: &[Record], duration: f64) -> String {
    let mut m = String::new();
    let _ = writeln!(
        m,
        "`cases/classifier.toml` (Stokes drag, Hertz contacts between particles and with the \
         walls) fed at multiples of its feed rate, {duration} s simulated each, the radial \
         distributions over the second half. Every method runs the same feed of original \
         powder: `scgα` coarse-grained particles (α³ fewer), `sampleα` originals, α³ fewer \
         (the control: no model error, only fewer particles). **contacts/s**: \
         particle–particle contacts per particle per second; **theory**: kinetic theory's \
         rate from the originals' (f ∝ n·d²: f₀/α for SCG, f₀/α³ for sampling). **W1/R**: \
         the W1 of the radial distribution to the originals' (/ vessel radius) of the class \
         that stands farthest above its noise, beside that noise: the W1 sampling alone \
         reaches in 5 % of cases (permutation test over particles); d50 with its 95 % \
         bootstrap interval (… = open). ✓ = agrees with the originals within the intervals \
         (every class's W1 within the noise, d50 within the intervals).\n"
    );
    let _ = writeln!(
        m,
        "| loading | method | particles | wall [s] | speed-up | pair contacts | contacts/s | theory | W1/R (class) | noise | d50 [µm] | agrees |"
    );
    let _ = writeln!(m, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in records {
        let o = original(records, r.loading);
        let f0 = o.and_then(|o| o.contact_rate);
        let speedup = o.map_or(f64::NAN, |o| o.wall_s / r.wall_s.max(1e-12));
        let is_orig = r.law == "original";
        let _ = writeln!(
            m,
            "| ×{} | {} | {:.0} | {:.1} | {:.1}× | {} | {} | {} | {} | {} | {} | {} |",
            r.loading,
            r.method,
            r.particles,
            r.wall_s,
            speedup,
            r.pair_contacts,
            opt(r.contact_rate, |x| format!("{x:.1}")),
            if is_orig {
                "—".into()
            } else {
                opt(f0, |f| format!("{:.1}", r.predicted_rate(f)))
            },
            match (&r.worst_class, r.w1) {
                (Some(c), Some(w)) => format!("{w:.4} ({c})"),
                _ => "—".into(),
            },
            opt(r.w1_noise95, |x| format!("{x:.4}")),
            match (r.d50, r.d50_95) {
                (Some(d), Some((lo, hi))) => format!("{} [{}, {}]", um(Some(d)), um(lo), um(hi)),
                _ => "—".into(),
            },
            match (&r.failure, r.agrees) {
                (Some(f), _) => format!("failed: {f}"),
                (None, Some(true)) => "✓".into(),
                (None, Some(false)) => "✗".into(),
                (None, None) => "reference".into(),
            }
        );
    }
    let _ = writeln!(m);
    for v in verdicts(records) {
        let _ = writeln!(m, "- {v}");
    }
    m
}

/// One line per record.
pub fn csv(records: &[Record]) -> String {
    let mut out = String::from(
        "loading,method,law,alpha,particles_mean,wall_s,particle_steps,pair_contacts,\
         wall_contacts,contacts_per_particle_s,theory_per_particle_s,w1_worst,w1_worst_class,\
         w1_worst_lo,w1_worst_hi,w1_worst_noise95,w1_agrees,d50_m,d50_lo_m,d50_hi_m,\
         d50_agrees,agrees,failure\n",
    );
    let num = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:e}"));
    let flag = |x: Option<bool>| x.map_or(String::new(), |x| x.to_string());
    for r in records {
        let f0 = original(records, r.loading).and_then(|o| o.contact_rate);
        let _ = writeln!(
            out,
            "{},{},{},{},{:.3},{:.6},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.loading,
            r.method,
            r.law,
            r.alpha,
            r.particles,
            r.wall_s,
            r.particle_steps,
            r.pair_contacts,
            r.wall_contacts,
            num(r.contact_rate),
            num(f0.map(|f| r.predicted_rate(f))),
            num(r.w1),
            r.worst_class.clone().unwrap_or_default(),
            num(r.w1_95.and_then(|x| x.0)),
            num(r.w1_95.and_then(|x| x.1)),
            num(r.w1_noise95),
            flag(r.w1_agrees),
            num(r.d50),
            num(r.d50_95.and_then(|x| x.0)),
            num(r.d50_95.and_then(|x| x.1)),
            flag(r.d50_agrees),
            flag(r.agrees),
            r.failure.clone().unwrap_or_default().replace(',', ";")
        );
    }
    out
}

/// `summary.json`: the records, the verdicts, and every point's full measurements.
pub fn summary(rows: &[Row], duration: f64) -> serde_json::Value {
    let records: Vec<Record> = rows.iter().map(Record::of).collect();
    serde_json::json!({
        "scene": "cases/classifier.toml",
        "duration_s": duration,
        "definitions": {
            "loading": "multiple of the scene's feed rate (feed_scale)",
            "contact_rate": "2 × particle–particle contacts started / (particle-steps × dt): contacts per particle per simulated second",
            "theory": "kinetic theory from the originals' rate f0: f0/α for scg (n/α³, diameter α·d), f0/α³ for sample (n/α³, diameter d)",
            "w1_noise95": "the W1 two runs of these particle counts reach from sampling alone in 5 % of cases (permutation test over particles)",
            "agrees": "every class's W1 ≤ its noise95 and d50 within the two 95 % intervals"
        },
        "verdicts": verdicts(&records),
        "records": records,
        "points": rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cost::{ClassErrors, Outcome, Point};
    use scg_core::physics::integrate::Integrator;
    use scg_core::physics::scaling::CoarseGrainLaw;

    fn row(loading: f64, method: &str, law: Option<CoarseGrainLaw>, alpha: f64) -> Row {
        let point = Point {
            law,
            alpha,
            dt_mult: 1,
            integrator: Integrator::Exponential,
            stiffness: 1.0,
        };
        Row {
            loading,
            method: method.into(),
            outcome: Outcome {
                point,
                dt: 1e-6,
                wall_s: 10.0 / alpha.powi(3),
                steps: 1000,
                particle_steps: (1000.0 * 800.0 / alpha.powi(3)) as u64,
                alone_wall_s: None,
                error: f64::NAN,
                sets: Default::default(),
                failure: None,
                classes: Some(ClassErrors {
                    names: vec!["a".into(), "b".into()],
                    w1: vec![0.01, 0.02],
                    d50: Some(150e-6),
                    d50_error: f64::NAN,
                    w1_95: vec![(0.005, 0.015), (0.01, 0.03)],
                    w1_noise95: vec![0.02, 0.03],
                    d50_95: Some((140e-6, f64::NAN)),
                    d50_agrees: law.map(|_| true),
                }),
                pair_contacts: (400.0 / alpha.powi(4)) as u64,
                wall_contacts: 0,
            },
        }
    }

    #[test]
    fn kinetic_theory_verdicts_and_the_summary_round_trip() {
        let o = Record::of(&row(1.0, "original", None, 1.0));
        let f0 = o.contact_rate.unwrap();
        // 2 × 400 contacts over 800 particles × 1000 steps × 1 µs: 1000 /s
        assert!((f0 - 1000.0).abs() < 1e-9, "{f0}");
        let s = Record::of(&row(1.0, "scg2", Some(CoarseGrainLaw::Scg), 2.0));
        let p = Record::of(&row(1.0, "sample2", Some(CoarseGrainLaw::Sample), 2.0));
        assert!((s.predicted_rate(f0) - 500.0).abs() < 1e-9);
        assert!((p.predicted_rate(f0) - 125.0).abs() < 1e-9);
        assert_eq!((o.agrees, s.agrees), (None, Some(true)));
        // the class farthest beyond its noise: b (0.02/0.03) over a (0.01/0.02)
        assert_eq!(s.worst_class.as_deref(), Some("b"));
        // sampling departs at ×16: its class b beyond the noise
        let mut p16 = row(16.0, "sample2", Some(CoarseGrainLaw::Sample), 2.0);
        if let Some(c) = &mut p16.outcome.classes {
            c.w1[1] = 0.05;
        }
        let rows = vec![
            row(1.0, "original", None, 1.0),
            row(1.0, "scg2", Some(CoarseGrainLaw::Scg), 2.0),
            row(1.0, "sample2", Some(CoarseGrainLaw::Sample), 2.0),
            row(16.0, "original", None, 1.0),
            row(16.0, "scg2", Some(CoarseGrainLaw::Scg), 2.0),
            p16,
        ];
        let records: Vec<Record> = rows.iter().map(Record::of).collect();
        assert_eq!(records[5].agrees, Some(false));
        let v = verdicts(&records);
        assert_eq!(v.len(), 3);
        assert!(v[1].contains("differ: sample2"), "{v:?}");
        assert!(
            v[2].contains("departs from the originals beyond its interval at ×16")
                && v[2].contains("scg2 holds"),
            "{v:?}"
        );
        let md = markdown(&records, 0.1);
        assert!(md.contains("| ×16 | sample2 |") && md.contains("✗"), "{md}");
        assert!(md.contains("150.0 [140.0, …]"), "{md}");
        let csv = csv(&records);
        assert_eq!(csv.lines().count(), 7);
        let n = csv.lines().next().unwrap().split(',').count();
        assert!(csv.lines().all(|l| l.split(',').count() == n), "{csv}");
        // summary.json (NaNs in the points) reads back to the same table
        let text = serde_json::to_string(&summary(&rows, 0.1)).unwrap();
        let back: Vec<Record> = serde_json::from_value(
            serde_json::from_str::<serde_json::Value>(&text).unwrap()["records"].clone(),
        )
        .unwrap();
        assert_eq!(markdown(&back, 0.1), md);
    }
}
