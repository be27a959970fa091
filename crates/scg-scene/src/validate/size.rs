//! `groups[i].size`: a size distribution, fed in report bins (one group per bin).

use std::sync::Arc;

use scg_core::physics::scaling::CoarseGrainLaw;
use scg_core::physics::size_distribution::{Basis, Shape, SizeDistribution, log_edges};

use super::Ctx;
use super::particles::PALETTE;
use crate::error::SceneError;
use crate::model::{Group, Placement, SizeBin};
use crate::raw::{RawBasis, RawBins, RawGroup, RawSize, RawSizeKind};

/// Report bins when `bins` is not given.
const DEFAULT_BINS: i64 = 10;

/// The groups of `groups[i]` with a `size` (one per report bin; `first` is the index the
/// first takes among all groups), which a feeder must feed.
pub(super) fn size_groups(
    g: &RawGroup,
    size: &RawSize,
    i: usize,
    first: usize,
    cx: &Ctx,
    fed: bool,
) -> Result<Vec<Group>, SceneError> {
    let k = |s: &str| format!("groups[{i}].{s}");
    let ks = |s: &str| format!("groups[{i}].size.{s}");
    if g.diameter.is_some() {
        return Err(cx.err(
            &k("diameter"),
            "give `diameter` (one size) or `size`, not both",
        ));
    }
    for (key, given) in [
        ("positions", g.positions.is_some()),
        ("count", g.count.is_some()),
        ("region", g.region.is_some()),
    ] {
        if given {
            return Err(cx.err(
                &k(key),
                "a group with a size distribution is fed by [[feeders]]; particles placed \
                 at the start take one `diameter` (a group of their own)",
            ));
        }
    }
    if !fed {
        return Err(cx.err(
            &k("size"),
            format!(
                "no feeder feeds `{}`: a size distribution is fed by [[feeders]]",
                g.name
            ),
        ));
    }
    let density = cx.positive(&k("density"), g.density)?;
    let alpha = cx.positive(&k("alpha"), g.alpha.unwrap_or(1.0))?;
    let law = g.law.map_or(CoarseGrainLaw::Scg, CoarseGrainLaw::from);
    let basis = match size.basis {
        RawBasis::Number => Basis::Number,
        RawBasis::Mass => Basis::Mass,
    };
    let need = |key: &str, v: Option<f64>| -> Result<f64, SceneError> {
        cx.positive(&ks(key), cx.need(&ks(key), &v)?)
    };
    let only = |kind: &str, keys: &[(&str, bool)]| -> Result<(), SceneError> {
        match keys.iter().find(|(_, given)| *given) {
            Some((key, _)) => Err(cx.err(&ks(key), format!("does not belong to `{kind}`"))),
            None => Ok(()),
        }
    };
    let (shape, min, max) = match size.distribution {
        RawSizeKind::RosinRammler => {
            only(
                "rosin_rammler",
                &[
                    ("median", size.median.is_some()),
                    ("sigma_g", size.sigma_g.is_some()),
                    ("table", size.table.is_some()),
                ],
            )?;
            let shape = Shape::RosinRammler {
                d63: need("d63", size.d63)?,
                spread: need("spread", size.spread)?,
            };
            (shape, need("min", size.min)?, need("max", size.max)?)
        }
        RawSizeKind::LogNormal => {
            only(
                "log_normal",
                &[
                    ("d63", size.d63.is_some()),
                    ("spread", size.spread.is_some()),
                    ("table", size.table.is_some()),
                ],
            )?;
            let sigma_g = need("sigma_g", size.sigma_g)?;
            if sigma_g <= 1.0 {
                return Err(cx.err(&ks("sigma_g"), format!("must be > 1, got {sigma_g}")));
            }
            let shape = Shape::LogNormal {
                median: need("median", size.median)?,
                sigma_g,
            };
            (shape, need("min", size.min)?, need("max", size.max)?)
        }
        RawSizeKind::Table => {
            only(
                "table",
                &[
                    ("d63", size.d63.is_some()),
                    ("spread", size.spread.is_some()),
                    ("median", size.median.is_some()),
                    ("sigma_g", size.sigma_g.is_some()),
                ],
            )?;
            let t = cx.need(&ks("table"), &size.table)?;
            let d: Vec<f64> = t.iter().map(|p| p[0]).collect();
            let q: Vec<f64> = t.iter().map(|p| p[1]).collect();
            let (lo, hi) = (
                d.first().copied().unwrap_or(0.0),
                d.last().copied().unwrap_or(0.0),
            );
            let min = match size.min {
                None => lo,
                Some(v) => cx.positive(&ks("min"), v)?,
            };
            let max = match size.max {
                None => hi,
                Some(v) => cx.positive(&ks("max"), v)?,
            };
            (Shape::Table { d, q }, min, max)
        }
    };
    if min >= max {
        return Err(cx.err(
            &ks("max"),
            format!("must be > min ({min:e} m), got {max:e}"),
        ));
    }
    let edges = match &size.bins {
        None => log_edges(min, max, DEFAULT_BINS as usize),
        Some(RawBins::Count(n)) => {
            if !(1..=200).contains(n) {
                return Err(cx.err(&ks("bins"), format!("must lie in 1..=200, got {n}")));
            }
            log_edges(min, max, *n as usize)
        }
        Some(RawBins::Edges(e)) => {
            if e.len() < 2
                || e.windows(2)
                    .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
            {
                return Err(cx.err(
                    &ks("bins"),
                    "edges must be at least two increasing sizes, m",
                ));
            }
            if e[0] != min || e[e.len() - 1] != max {
                return Err(cx.err(
                    &ks("bins"),
                    format!("edges must run from min ({min:e} m) to max ({max:e} m)"),
                ));
            }
            e.clone()
        }
    };
    let dist = SizeDistribution::new(shape, basis, min, max, &edges)
        .map_err(|e| cx.err(&ks("distribution"), e))?;
    let dist = Arc::new(dist);
    let bins = edges.len() - 1;
    let width = bins.to_string().len();
    Ok((0..bins)
        .map(|b| {
            let (lo, hi) = (edges[b], edges[b + 1]);
            Group {
                name: format!("{}-{:0width$}", g.name, b + 1),
                diameter: dist.mean_d3_in(lo, hi).cbrt(),
                density,
                alpha,
                law,
                color: PALETTE[(first + b) % PALETTE.len()],
                placement: Placement::Explicit {
                    positions: Vec::new(),
                    velocities: Vec::new(),
                },
                size: Some(SizeBin {
                    parent: g.name.clone(),
                    distribution: dist.clone(),
                    edges: edges.clone(),
                    index: b,
                }),
            }
        })
        .collect())
}
