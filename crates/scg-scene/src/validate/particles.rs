//! The particles: `[[groups]]` (placements and their regions) and `[[feeders]]`.

use scg_core::physics::scaling::CoarseGrainLaw;

use super::Ctx;
use crate::error::SceneError;
use std::sync::Arc;

use scg_core::physics::inlet::PatchSampler;

use crate::model::{FeedSource, Feeder, Group, Placement, Region, SceneMeshFlow};
use crate::raw::{RawFeedVelocity, RawFeeder, RawGroup, RawRegion, RawRegionKind};

/// Default group colours, by group index.
pub(super) const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// `groups[i]`; `fed`: a feeder feeds it (then it may start empty).
pub(super) fn group(g: &RawGroup, i: usize, cx: &Ctx, fed: bool) -> Result<Group, SceneError> {
    let k = |s: &str| format!("groups[{i}].{s}");
    if g.name.is_empty()
        || !g
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-".contains(c))
    {
        return Err(cx.err(
            &k("name"),
            "must be non-empty and use only letters, digits, `_` and `-`",
        ));
    }
    let diameter = cx.positive(&k("diameter"), cx.need(&k("diameter"), &g.diameter)?)?;
    let density = cx.positive(&k("density"), g.density)?;
    let alpha = cx.positive(&k("alpha"), g.alpha.unwrap_or(1.0))?;
    let law = g.law.map_or(CoarseGrainLaw::Scg, CoarseGrainLaw::from);
    let color = match g.color {
        None => PALETTE[i % PALETTE.len()],
        Some(c) => {
            if c.iter().any(|v| !(0..=255).contains(v)) {
                return Err(cx.err(&k("color"), "components must lie in 0..=255"));
            }
            [c[0] as u8, c[1] as u8, c[2] as u8]
        }
    };
    let velocity = cx.vec3(&k("velocity"), g.velocity.unwrap_or([0.0; 3]))?;
    let placement = match (&g.positions, &g.region) {
        (Some(_), Some(_)) => {
            return Err(cx.err(
                &k("region"),
                "give either `positions` or `count` + `region`, not both",
            ));
        }
        (Some(ps), None) => {
            if g.count.is_some() {
                return Err(cx.err(
                    &k("count"),
                    "`count` goes with `region`, not with `positions`",
                ));
            }
            if ps.is_empty() {
                return Err(cx.err(&k("positions"), "must list at least one position"));
            }
            let positions = ps
                .iter()
                .map(|p| cx.vec3(&k("positions"), *p))
                .collect::<Result<Vec<_>, _>>()?;
            let velocities = match &g.velocities {
                None => vec![velocity; positions.len()],
                Some(vs) => {
                    if vs.len() != positions.len() {
                        return Err(cx.err(
                            &k("velocities"),
                            format!("has {} entries for {} positions", vs.len(), positions.len()),
                        ));
                    }
                    vs.iter()
                        .map(|v| cx.vec3(&k("velocities"), *v))
                        .collect::<Result<Vec<_>, _>>()?
                }
            };
            Placement::Explicit {
                positions,
                velocities,
            }
        }
        (None, Some(r)) => {
            let count = cx.need(&k("count"), &g.count)?;
            if !(0..=50_000_000).contains(&count) {
                return Err(cx.err(
                    &k("count"),
                    format!("must lie in 0..=50000000, got {count}"),
                ));
            }
            Placement::Random {
                count: count as usize,
                region: region(r, &k("region"), cx)?,
                velocity,
            }
        }
        // A group that a feeder feeds may start empty.
        (None, None) if fed && g.count.is_none() => Placement::Explicit {
            positions: Vec::new(),
            velocities: Vec::new(),
        },
        (None, None) => {
            return Err(cx.err(
                &k("positions"),
                "a group needs `positions` or `count` + `region` (or a feeder)",
            ));
        }
    };
    Ok(Group {
        name: g.name.clone(),
        diameter,
        density,
        alpha,
        law,
        color,
        placement,
        size: None,
    })
}

/// A region at `key` (a group's or a feeder's).
pub(super) fn region(r: &RawRegion, key: &str, cx: &Ctx) -> Result<Region, SceneError> {
    let k = |s: &str| format!("{key}.{s}");
    match r.kind {
        RawRegionKind::Box => {
            let min = cx.vec3(&k("min"), cx.need(&k("min"), &r.min)?)?;
            let max = cx.vec3(&k("max"), cx.need(&k("max"), &r.max)?)?;
            if !(min.cmple(max).all()) {
                return Err(cx.err(&k("max"), "every component of max must be ≥ min"));
            }
            Ok(Region::Box { min, max })
        }
        RawRegionKind::Cylinder => {
            let radius_min = cx.non_negative(&k("radius_min"), r.radius_min.unwrap_or(0.0))?;
            let radius_max =
                cx.positive(&k("radius_max"), cx.need(&k("radius_max"), &r.radius_max)?)?;
            if radius_min > radius_max {
                return Err(cx.err(&k("radius_min"), "must be ≤ radius_max"));
            }
            let [h0, h1] = r.height.unwrap_or([0.0, 0.0]);
            let (h0, h1) = (cx.finite(&k("height"), h0)?, cx.finite(&k("height"), h1)?);
            if h0 > h1 {
                return Err(cx.err(&k("height"), "must be [from, to] with from ≤ to"));
            }
            Ok(Region::Cylinder {
                center: cx.vec3(&k("center"), r.center.unwrap_or([0.0; 3]))?,
                axis: cx.unit(&k("axis"), r.axis.unwrap_or([0.0, 0.0, 1.0]))?,
                radius_min,
                radius_max,
                height: (h0, h1),
            })
        }
    }
}

/// `feeders[i]`, feeding one of `groups` (from a patch of `mesh`, the scene's mesh flow,
/// when it names one). How many it feeds over the run is checked with the whole scene's
/// particles, once `dt` is known.
pub(super) fn feeder(
    f: &RawFeeder,
    i: usize,
    groups: &[Group],
    mesh: Option<&SceneMeshFlow>,
    cx: &Ctx,
) -> Result<Feeder, SceneError> {
    let k = |s: &str| format!("feeders[{i}].{s}");
    // a size distribution's feeder names the `[[groups]]` entry and feeds its first bin's
    // group and the next ones
    let group = groups
        .iter()
        .position(|g| {
            g.size
                .as_ref()
                .map_or(g.name == f.group, |s| s.parent == f.group && s.index == 0)
        })
        .ok_or_else(|| cx.err(&k("group"), format!("no group named `{}`", f.group)))?;
    let g = &groups[group];
    let volume = g.fed_volume();
    let rate = match (f.rate, f.volume_rate, f.mass_rate) {
        (Some(r), None, None) => cx.non_negative(&k("rate"), r)?,
        (None, Some(v), None) => cx.non_negative(&k("volume_rate"), v)? / volume,
        (None, None, Some(m)) => cx.non_negative(&k("mass_rate"), m)? / (g.density * volume),
        (None, None, None) => {
            return Err(cx.err(
                &k("rate"),
                "a feeder needs `rate` (simulated particles/s), `volume_rate` (m³/s) or \
                 `mass_rate` (kg/s of the original powder)",
            ));
        }
        _ => {
            let key = if f.mass_rate.is_some() {
                "mass_rate"
            } else {
                "volume_rate"
            };
            return Err(cx.err(&k(key), "give one of `rate`, `volume_rate` and `mass_rate`"));
        }
    };
    let start = cx.non_negative(&k("start"), f.start.unwrap_or(0.0))?;
    let stop = cx.finite(&k("stop"), f.stop.unwrap_or(f64::MAX))?;
    if stop < start {
        return Err(cx.err(&k("stop"), "must be ≥ start"));
    }
    let source = match (&f.region, &f.patch) {
        (Some(_), Some(_)) => {
            return Err(cx.err(&k("patch"), "give `region` or `patch`, not both"));
        }
        (None, None) => {
            // the key is missing: point at the feeder
            let mut e = cx.err(&k("region"), "a feeder needs `region` or `patch`");
            e.line = e
                .line
                .or_else(|| crate::error::locate(cx.text, &format!("feeders[{i}]")));
            return Err(e);
        }
        (Some(r), None) => FeedSource::Region(region(r, &k("region"), cx)?),
        (None, Some(name)) => FeedSource::Patch(Arc::new(patch(name, &k("patch"), mesh, cx)?)),
    };
    let (velocity, field_velocity) = match &f.velocity {
        None => (glam::DVec3::ZERO, false),
        Some(RawFeedVelocity::Given(v)) => (cx.vec3(&k("velocity"), *v)?, false),
        Some(RawFeedVelocity::Word(w)) if w == "field" => {
            if f.patch.is_none() {
                return Err(cx.err(
                    &k("velocity"),
                    "`velocity = \"field\"` goes with `patch` (a feeder on a mesh-flow patch)",
                ));
            }
            (glam::DVec3::ZERO, true)
        }
        Some(RawFeedVelocity::Word(w)) => {
            return Err(cx.err(
                &k("velocity"),
                format!("expected [x, y, z] in m/s or \"field\", got \"{w}\""),
            ));
        }
    };
    let by_flux = match f.weight.as_deref() {
        None | Some("area") => false,
        Some("flux") if f.patch.is_some() => true,
        Some("flux") => {
            return Err(cx.err(
                &k("weight"),
                "`weight = \"flux\"` goes with `patch` (the flux of a mesh-flow patch)",
            ));
        }
        Some(w) => {
            return Err(cx.err(
                &k("weight"),
                format!("expected \"area\" or \"flux\", got \"{w}\""),
            ));
        }
    };
    Ok(Feeder {
        by_flux,
        group,
        rate,
        source,
        velocity,
        field_velocity,
        swirl: cx.finite(&k("swirl"), f.swirl.unwrap_or(0.0))?,
        window: (start, stop),
        interval: cx.non_negative(&k("interval"), f.interval.unwrap_or(0.0))?,
    })
}

/// The sampler of the mesh-flow patch `name` (at `key`).
fn patch(
    name: &str,
    key: &str,
    mesh: Option<&SceneMeshFlow>,
    cx: &Ctx,
) -> Result<PatchSampler, SceneError> {
    let Some(m) = mesh else {
        return Err(cx.err(
            key,
            "feeding from a patch needs a flow on a mesh (flow.kind = \"openfoam\" or \"vtk\")",
        ));
    };
    let mesh = m.flow.mesh();
    let Some(p) = mesh.patches.iter().position(|p| p.name == name) else {
        let known: Vec<&str> = mesh.patches.iter().map(|p| p.name.as_str()).collect();
        return Err(cx.err(
            key,
            format!(
                "unknown patch `{name}` in {}; the mesh has: {}",
                m.source,
                known.join(", ")
            ),
        ));
    };
    if m.flow.roles()[p] == scg_core::physics::mesh_flow::PatchRole::Wall {
        return Err(cx.err(
            key,
            format!(
                "patch `{name}` is a wall (flow.patches.walls): feed from an inlet patch, \
                 where the flow enters"
            ),
        ));
    }
    PatchSampler::new(mesh, m.flow.geometry(), p).map_err(|e| cx.err(key, e))
}
