//! Grade efficiency of a cyclone per size class, its cut size, and residence-time
//! distances, in the `grade.json` field names shared with `cases/cyclone/vs-openfoam.sh`.
//!
//! A particle fed at the inlet ends one of four ways: **collected** in the scene's
//! collecting zone (the dust outlet at the bottom of the cone: `[[zones]] collects =
//! true`), **escaped** through the vortex finder (the `outlet` patch), **lost** back out
//! through the inlet, or **held**: still inside at the end, undecided. The grade
//! efficiency of a class is collected/fed, with escaped/fed and the undecided share beside
//! it; the two bound the efficiency a longer run would give (collected/fed ≤ η ≤
//! 1 − escaped/fed). A run without a collecting zone (and another code's `grade.json`
//! without `collected` counts) has only the upper bound: its efficiency is 1 − escaped/fed.

use serde::{Deserialize, Serialize};

use crate::analysis::{d50, mean, wasserstein1};

/// One size class: counts of simulated particles and the residence times of the escaped.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassGrade {
    /// Group name.
    #[serde(default)]
    pub group: String,
    /// Original diameter, m.
    pub diameter: f64,
    /// Original density, kg/m³ (NaN when a `grade.json` leaves it out).
    #[serde(default = "nan", with = "nan_as_null")]
    pub density: f64,
    /// Particles fed.
    #[serde(default)]
    pub fed: u64,
    /// Escaped through the outlet.
    #[serde(default)]
    pub escaped: u64,
    /// Still inside at the end.
    #[serde(default)]
    pub held: u64,
    /// Lost through the inlet (or elsewhere).
    #[serde(default)]
    pub lost: u64,
    /// Collected in a collecting zone (`None`: the run had none, or the file says none).
    #[serde(default)]
    pub collected: Option<u64>,
    /// Grade efficiency: collected / fed where the run collects, else 1 − escaped / fed
    /// (NaN, written null, when none was fed).
    #[serde(default = "nan", with = "nan_as_null")]
    pub efficiency: f64,
    /// Feed-to-escape times of the escaped particles, s, sorted.
    #[serde(default)]
    pub residence_times: Vec<f64>,
}

fn nan() -> f64 {
    f64::NAN
}

/// NaN ↔ JSON null (JSON has no NaN); binary formats (postcard, between MPI ranks) keep
/// the f64 bits as they are.
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        if x.is_finite() || !s.is_human_readable() {
            s.serialize_f64(*x)
        } else {
            s.serialize_none()
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        if d.is_human_readable() {
            Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
        } else {
            f64::deserialize(d)
        }
    }
}

impl ClassGrade {
    /// A class from its counts; `residence_times` in any order.
    pub fn new(
        group: &str,
        diameter: f64,
        density: f64,
        counts: [u64; 4],
        mut residence_times: Vec<f64>,
    ) -> Self {
        let [fed, escaped, held, lost] = counts;
        residence_times.sort_by(f64::total_cmp);
        ClassGrade {
            group: group.to_string(),
            diameter,
            density,
            fed,
            escaped,
            held,
            lost,
            collected: None,
            efficiency: efficiency(fed, escaped),
            residence_times,
        }
    }

    /// The class with `n` particles collected: its efficiency becomes collected / fed.
    pub fn with_collected(mut self, n: u64) -> Self {
        self.collected = Some(n);
        self.efficiency = share(n, self.fed);
        self
    }

    /// The efficiency again from the counts (collected / fed, or 1 − escaped / fed).
    pub fn recompute(&mut self) {
        self.efficiency = match self.collected {
            Some(n) => share(n, self.fed),
            None => efficiency(self.fed, self.escaped),
        };
    }

    /// Share of the fed that escaped.
    pub fn escaped_share(&self) -> f64 {
        share(self.escaped, self.fed)
    }

    /// Wilson's 95 % interval of the efficiency.
    pub fn efficiency95(&self) -> (f64, f64) {
        match self.collected {
            Some(n) => wilson95(n, self.fed),
            None => wilson95(self.fed.saturating_sub(self.escaped), self.fed),
        }
    }

    /// Share of the fed still inside at the end.
    pub fn held_share(&self) -> f64 {
        share(self.held, self.fed)
    }

    /// Share of the fed lost through the inlet.
    pub fn lost_share(&self) -> f64 {
        share(self.lost, self.fed)
    }

    /// Mean residence time of the escaped, s (NaN when none escaped).
    pub fn mean_residence(&self) -> f64 {
        mean(&self.residence_times)
    }
}

fn share(n: u64, of: u64) -> f64 {
    if of == 0 {
        f64::NAN
    } else {
        n as f64 / of as f64
    }
}

/// Grade efficiency 1 − escaped / fed (NaN when nothing was fed).
pub fn efficiency(fed: u64, escaped: u64) -> f64 {
    if fed == 0 {
        f64::NAN
    } else {
        1.0 - escaped as f64 / fed as f64
    }
}

/// The cut size: where the grade efficiency first rises through 0.5 with size,
/// interpolated linearly in diameter between the classes (in increasing diameter);
/// `None` when it never does. Empty classes (NaN) are skipped.
pub fn cut_size(classes: &[ClassGrade]) -> Option<f64> {
    let escaped: Vec<(f64, f64)> = classes
        .iter()
        .map(|c| (c.diameter, 1.0 - c.efficiency))
        .collect();
    d50(&escaped)
}

pub use crate::analysis::interval::wilson95;

/// W1 distance between the residence times of `v` and those of `reference` (escaped
/// particles of one class), over the reference's mean residence time; NaN when either has
/// none.
pub fn residence_w1(reference: &ClassGrade, v: &ClassGrade) -> f64 {
    wasserstein1(&reference.residence_times, &v.residence_times) / reference.mean_residence()
}

/// The 95 % bootstrap interval of [`cut_size`] (each class's count redrawn binomially:
/// [`crate::analysis::interval::d50_interval`]); `None` where the curve does not cross 0.5,
/// a NaN bound where it is open.
pub fn cut_size95(classes: &[ClassGrade]) -> Option<(f64, f64)> {
    use crate::analysis::interval::{ClassCount, RESAMPLES, d50_interval};
    let counts: Vec<ClassCount> = classes
        .iter()
        .map(|c| ClassCount {
            diameter: c.diameter,
            // the share the curve falls through: 1 − η of the fed
            k: ((1.0 - c.efficiency) * c.fed as f64).round().max(0.0) as u64,
            n: c.fed,
        })
        .collect();
    d50_interval(&counts, RESAMPLES, 0x5c6_c7c)
}

/// Another code's grade curve (`grade.json` of `cases/cyclone/vs-openfoam.sh`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExternalGrade {
    /// Name of the code (`"openfoam"`).
    pub code: String,
    /// Per class.
    pub classes: Vec<ClassGrade>,
    /// Its cut size, m, if it gave one.
    #[serde(default)]
    pub d50: Option<f64>,
    /// Its tracking speed, particle-steps per second, if it gave one.
    #[serde(default)]
    pub particle_steps_per_s: Option<f64>,
}

impl ExternalGrade {
    /// Read `path`; the efficiency of each class is recomputed from its counts when they
    /// are there (fed > 0), so that both codes use the same definition (collected / fed
    /// where the class has `collected`, else 1 − escaped / fed).
    pub fn read(path: &std::path::Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut g: ExternalGrade =
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        for c in &mut g.classes {
            if c.fed > 0 {
                c.recompute();
            }
            c.residence_times.sort_by(f64::total_cmp);
        }
        Ok(g)
    }

    /// The class of `other` with the same diameter (to 0.1 %), if any.
    pub fn matching(&self, diameter: f64) -> Option<&ClassGrade> {
        self.classes
            .iter()
            .find(|c| (c.diameter - diameter).abs() <= 1e-3 * diameter)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn class_grades_travel_between_ranks_bit_exact_and_as_json_with_null() {
        // Nothing fed: efficiency NaN; an unknown density: NaN with a payload.
        let mut c = ClassGrade::new("g", 1e-6, f64::NAN, [0, 0, 0, 0], vec![]);
        c.density = f64::from_bits(f64::NAN.to_bits() | 7);
        let bytes = postcard::to_stdvec(&c).unwrap();
        let back: ClassGrade = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(back.density.to_bits(), c.density.to_bits());
        assert_eq!(back.efficiency.to_bits(), c.efficiency.to_bits());
        assert_eq!(back.group, "g");
        let json = serde_json::to_string(&c).unwrap();
        assert!(json.contains("\"efficiency\":null"), "{json}");
        let back: ClassGrade = serde_json::from_str(&json).unwrap();
        assert!(back.efficiency.is_nan() && back.density.is_nan());
    }

    fn class(d_um: f64, fed: u64, escaped: u64, times: Vec<f64>) -> ClassGrade {
        ClassGrade::new(
            &format!("d{d_um}"),
            d_um * 1e-6,
            2000.0,
            [fed, escaped, fed - escaped, 0],
            times,
        )
    }

    #[test]
    fn efficiency_and_cut_size() {
        assert_eq!(efficiency(200, 50), 0.75);
        assert!(efficiency(0, 0).is_nan());
        // Efficiencies 0.2, 0.4, 0.8, 1.0 at 1, 2, 4, 8 µm: 0.5 is a quarter of the way
        // from 2 to 4 µm.
        let cs: Vec<ClassGrade> = [(1.0, 80), (2.0, 60), (4.0, 20), (8.0, 0)]
            .into_iter()
            .map(|(d, e)| class(d, 100, e, Vec::new()))
            .collect();
        let d = cut_size(&cs).unwrap();
        assert!((d - 2.5e-6).abs() < 1e-15, "{d}");
        assert_eq!(cs[0].held_share(), 0.2);
        // Collected 30 of 100: the efficiency is the collected share, the interval its
        // own; the escaped share stays beside it.
        let c = cs[0].clone().with_collected(30);
        assert_eq!((c.efficiency, c.escaped_share()), (0.3, 0.8));
        assert_eq!(c.efficiency95(), wilson95(30, 100));
        let mut back: ClassGrade =
            serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
        back.efficiency = 0.0;
        back.recompute();
        assert_eq!(back.efficiency, 0.3);
        assert_eq!(cs[0].lost_share(), 0.0);
        // Never through 0.5: no cut.
        assert_eq!(cut_size(&cs[2..]), None);
        // Wilson's 95 % interval: inside [0, 1], about the share, narrower with n
        let (lo, hi) = wilson95(8, 10);
        assert!(lo > 0.44 && lo < 0.5 && hi > 0.94 && hi < 0.98, "{lo} {hi}");
        assert_eq!(wilson95(0, 10).0, 0.0);
        assert!((wilson95(10, 10).1 - 1.0).abs() < 1e-12);
        let (a, b) = wilson95(800, 1000);
        assert!(a < 0.8 && b > 0.8 && b - a < 0.06, "{a} {b}");
        assert!(wilson95(0, 0).0.is_nan());
    }

    #[test]
    fn residence_w1_is_normalised_by_the_reference_mean() {
        let a = class(1.0, 10, 2, vec![3.0, 1.0]); // sorted on construction, mean 2 s
        assert_eq!(a.residence_times, vec![1.0, 3.0]);
        let b = class(1.0, 10, 2, vec![1.5, 3.5]); // shifted by 0.5 s: W1 = 0.5 s
        assert!((residence_w1(&a, &b) - 0.25).abs() < 1e-15);
        assert_eq!(residence_w1(&a, &a), 0.0);
        assert!(residence_w1(&a, &class(1.0, 10, 0, Vec::new())).is_nan());
    }

    #[test]
    fn external_grade_json_round_trip() {
        let json = r#"{"code": "openfoam", "classes": [
            {"group": "d5", "diameter": 5e-6, "density": 2000, "fed": 100, "escaped": 30,
             "held": 68, "lost": 2, "efficiency": 0.1, "residence_times": [2.0, 1.0]},
            {"group": "d8", "diameter": 8e-6, "density": 2000, "fed": 0, "escaped": 0,
             "held": 0, "lost": 0, "efficiency": null},
            {"diameter": 11e-6, "fed": 10, "escaped": 1}],
            "d50": 4.5e-6, "particle_steps_per_s": 1.0e6, "extra": "ignored"}"#;
        let dir = std::env::temp_dir().join(format!("scg-grade-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("grade.json");
        std::fs::write(&p, json).unwrap();
        let g = ExternalGrade::read(&p).unwrap();
        assert_eq!(g.code, "openfoam");
        // Recomputed from the counts (the file's 0.1 disagrees with them).
        assert!((g.classes[0].efficiency - 0.7).abs() < 1e-15);
        assert!(g.classes[1].efficiency.is_nan());
        // Only the diameter and counts: the rest defaults (density unknown).
        assert!((g.classes[2].efficiency - 0.9).abs() < 1e-15);
        assert!(g.classes[2].density.is_nan() && g.classes[2].held == 0);
        assert_eq!(g.classes[0].residence_times, vec![1.0, 2.0]);
        assert_eq!(g.d50, Some(4.5e-6));
        assert_eq!(g.matching(5.000001e-6).map(|c| c.fed), Some(100));
        assert!(g.matching(6e-6).is_none());
        // Written back, NaN becomes null and reads as NaN again.
        let back: ExternalGrade =
            serde_json::from_str(&serde_json::to_string(&g).unwrap()).unwrap();
        assert!(back.classes[1].efficiency.is_nan());
        std::fs::write(&p, "{\"code\": 3}").unwrap();
        assert!(ExternalGrade::read(&p).unwrap_err().contains("grade.json"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
