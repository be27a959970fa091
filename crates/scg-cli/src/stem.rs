//! The file stem of a run's recordings and checkpoint: the scene, its coarse graining and
//! the overrides that change it.

/// File stem of a run's recordings: the scene name, followed by `-<law>-a<α>` when every
/// group is coarse-grained alike (α ≠ 1), so the coarse-grained variants of a case
/// (`--set coarse_grain.alpha=2 --set coarse_grain.law=none`) do not overwrite the
/// originals' recordings or each other's.
pub fn recording_stem(scene: &scg_scene::Scene) -> String {
    let first = scene.groups.first().map(|g| (g.law, g.alpha));
    match first {
        Some((law, alpha))
            if alpha != 1.0
                && scene
                    .groups
                    .iter()
                    .all(|g| (g.law, g.alpha) == (law, alpha)) =>
        {
            format!("{}-{}-a{}", scene.name, law.name(), alpha)
        }
        _ => scene.name.clone(),
    }
}

/// The part of a run's file stem that its `--set` overrides add, so that a run with other
/// physics does not overwrite another's recordings: `-key=value` for each override, in
/// order, characters other than letters, digits and `._=+-` written `_`; a suffix longer
/// than 64 characters becomes `-set` and a hash of the overrides. Left out: `duration` (a
/// longer or shorter run of the same physics replaces its recording, and restarts
/// lengthen runs with it) and `coarse_grain.alpha` / `coarse_grain.law`, which
/// [`recording_stem`] names already.
pub fn set_suffix(sets: &[String]) -> String {
    let mut s = String::new();
    for kv in sets {
        let key = kv.split('=').next().unwrap_or("").trim();
        if matches!(key, "duration" | "coarse_grain.alpha" | "coarse_grain.law") {
            continue;
        }
        s.push('-');
        s.extend(kv.trim().chars().map(|c| {
            if c.is_ascii_alphanumeric() || "._=+-".contains(c) {
                c
            } else {
                '_'
            }
        }));
    }
    if s.len() > 64 {
        // FNV-1a: stable across runs and versions
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in sets.join("\n").bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
        s = format!("-set{h:016x}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_that_change_the_physics_name_the_recording() {
        let s = |v: &[&str]| set_suffix(&v.iter().map(|x| x.to_string()).collect::<Vec<_>>());
        assert_eq!(s(&[]), "");
        assert_eq!(s(&["duration=0.5"]), "");
        assert_eq!(s(&["coarse_grain.alpha=2", "coarse_grain.law=none"]), "");
        assert_eq!(s(&["drag.law=stokes"]), "-drag.law=stokes");
        assert_eq!(
            s(&[
                "drag.law=stokes",
                "duration=1",
                "groups.0.velocity=[1, 2, 3]"
            ]),
            "-drag.law=stokes-groups.0.velocity=_1__2__3_"
        );
        let long: Vec<String> = (0..20).map(|i| format!("groups.{i}.alpha=2")).collect();
        let a = set_suffix(&long);
        assert!(a.starts_with("-set") && a.len() == 20, "{a}");
        assert_ne!(a, set_suffix(&long[1..]));
    }
}
