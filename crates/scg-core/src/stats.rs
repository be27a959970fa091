//! Names of the scalars a frame carries ([`crate::frame::Frame::stats`]): written by the
//! recording stage and read back by analysis, through one type so the two cannot drift.

/// One recorded scalar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stat<'a> {
    /// Particles of a group present at the frame.
    Count(&'a str),
    /// Particles of a group drained through the outlet so far.
    Drained(&'a str),
    /// Contacts of a group's particles started so far.
    Collisions(&'a str),
    /// Mean particle speed, m/s.
    MeanSpeed,
    /// Translational kinetic energy of all particles, J.
    KineticEnergy,
}

impl<'a> Stat<'a> {
    /// The key in [`crate::frame::Frame::stats`] (`count/<group>`, `mean_speed`, …; a `/`
    /// nests in the Rerun entity tree).
    pub fn key(&self) -> String {
        match self {
            Stat::Count(g) => format!("count/{g}"),
            Stat::Drained(g) => format!("drained/{g}"),
            Stat::Collisions(g) => format!("collisions/{g}"),
            Stat::MeanSpeed => "mean_speed".into(),
            Stat::KineticEnergy => "kinetic_energy".into(),
        }
    }

    /// The stat a key names, if any.
    pub fn parse(key: &'a str) -> Option<Self> {
        if let Some((family, group)) = key.split_once('/') {
            return match family {
                "count" => Some(Stat::Count(group)),
                "drained" => Some(Stat::Drained(group)),
                "collisions" => Some(Stat::Collisions(group)),
                _ => None,
            };
        }
        match key {
            "mean_speed" => Some(Stat::MeanSpeed),
            "kinetic_energy" => Some(Stat::KineticEnergy),
            _ => None,
        }
    }

    /// The value of this stat in `stats` (a frame's list), if recorded.
    pub fn find(&self, stats: &[(String, f64)]) -> Option<f64> {
        let key = self.key();
        stats.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_round_trip() {
        for s in [
            Stat::Count("fine"),
            Stat::Drained("a/b"),
            Stat::Collisions("x"),
            Stat::MeanSpeed,
            Stat::KineticEnergy,
        ] {
            let k = s.key();
            assert_eq!(Stat::parse(&k), Some(s), "{k}");
        }
        assert_eq!(Stat::parse("bogus"), None);
        assert_eq!(Stat::parse("speed/x"), None);
        let stats = vec![("count/fine".to_string(), 3.0)];
        assert_eq!(Stat::Count("fine").find(&stats), Some(3.0));
        assert_eq!(Stat::Drained("fine").find(&stats), None);
    }
}
