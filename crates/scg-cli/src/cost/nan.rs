//! NaN as a missing number, both ways: JSON has no NaN (it writes `null`), and postcard
//! (the points' transport between MPI ranks) must read what it wrote, so every field that
//! may be NaN is written as an `Option` and read back with NaN for `None`.

fn o(x: f64) -> Option<f64> {
    (!x.is_nan()).then_some(x)
}

fn v(x: Option<f64>) -> f64 {
    x.unwrap_or(f64::NAN)
}

pub mod num {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        super::o(*x).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Option::<f64>::deserialize(d).map(super::v)
    }
}

pub mod nums {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(x: &[f64], s: S) -> Result<S::Ok, S::Error> {
        x.iter()
            .map(|x| super::o(*x))
            .collect::<Vec<_>>()
            .serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Vec::<Option<f64>>::deserialize(d).map(|x| x.into_iter().map(super::v).collect())
    }
}

pub mod pairs {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(x: &[(f64, f64)], s: S) -> Result<S::Ok, S::Error> {
        x.iter()
            .map(|(a, b)| (super::o(*a), super::o(*b)))
            .collect::<Vec<_>>()
            .serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<(f64, f64)>, D::Error> {
        Vec::<(Option<f64>, Option<f64>)>::deserialize(d).map(|x| {
            x.into_iter()
                .map(|(a, b)| (super::v(a), super::v(b)))
                .collect()
        })
    }
}

pub mod opt_pair {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(x: &Option<(f64, f64)>, s: S) -> Result<S::Ok, S::Error> {
        x.map(|(a, b)| (super::o(a), super::o(b))).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<(f64, f64)>, D::Error> {
        Option::<(Option<f64>, Option<f64>)>::deserialize(d)
            .map(|x| x.map(|(a, b)| (super::v(a), super::v(b))))
    }
}

#[cfg(test)]
mod tests {
    use super::super::run::ClassErrors;

    /// NaNs survive postcard (MPI) and JSON (summary files) both ways.
    #[test]
    fn nan_round_trips() {
        let c = ClassErrors {
            names: vec!["a".into(), "b".into()],
            w1: vec![0.5, f64::NAN],
            d50: None,
            d50_error: f64::NAN,
            w1_95: vec![(0.1, f64::NAN), (f64::NAN, 2.0)],
            w1_noise95: vec![f64::NAN, 1.0],
            d50_95: Some((1e-4, f64::NAN)),
            d50_agrees: None,
        };
        let same = |d: &ClassErrors| {
            let bits = |v: &[f64]| {
                v.iter()
                    .map(|x| if x.is_nan() { u64::MAX } else { x.to_bits() })
                    .collect::<Vec<_>>()
            };
            bits(&d.w1) == bits(&c.w1)
                && d.d50_error.is_nan()
                && bits(&d.w1_noise95) == bits(&c.w1_noise95)
                && d.w1_95[0].0 == 0.1
                && d.w1_95[0].1.is_nan()
                && d.w1_95[1].0.is_nan()
                && d.d50_95.is_some_and(|(a, b)| a == 1e-4 && b.is_nan())
        };
        let p: ClassErrors = postcard::from_bytes(&postcard::to_stdvec(&c).unwrap()).unwrap();
        assert!(same(&p));
        let j: ClassErrors = serde_json::from_str(&serde_json::to_string(&c).unwrap()).unwrap();
        assert!(same(&j));
    }
}
