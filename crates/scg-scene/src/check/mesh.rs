//! `scg check` on a mesh flow: 2-D and wedge cases, initial particles and feeder
//! regions outside the mesh.

use super::*;

/// Feeder-region points sampled per feeder to test them against a mesh flow.
const FEEDER_SAMPLES: usize = 1000;

/// Warnings of a mesh flow: initial particles outside the mesh (they are lost at the first
/// step) and feeder regions reaching outside it (sampled: [`FEEDER_SAMPLES`] points each,
/// seeded, so the report is deterministic).
pub(super) fn mesh_flow_findings(scene: &Scene) -> Vec<Finding> {
    use rand::SeedableRng;
    let Some(m) = &scene.mesh_flow else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mesh = m.flow.mesh();
    let empty: Vec<&str> = mesh
        .patches
        .iter()
        .filter(|p| p.kind == "empty")
        .map(|p| p.name.as_str())
        .collect();
    if !empty.is_empty() {
        out.push(Finding {
            level: Level::Note,
            message: format!(
                "a 2-D case: patch(es) {} are `empty` (the direction the case does not resolve); particles reflect specularly there, so their motion stays in the slab, and the fates are of the slab's depth",
                empty.join(", ")
            ),
        });
    }
    if let Some(w) = m.flow.wall_cells() {
        let (cells, faces) = w.counts();
        let law = w.law();
        let message = match w.y_plus_range() {
            Some((lo, mid, hi)) => {
                let level = if lo < 30.0 {
                    "; below y⁺ = 30 the first cell is in the buffer layer or the viscous sublayer, where the log law is approximate"
                } else {
                    ""
                };
                format!(
                    "wall function: the log law (κ = {}, E = {}, C_μ = {}) below the centres of {cells} wall-adjacent cells ({faces} wall faces); y⁺ of the centres {lo:.1}..{hi:.1} (median {mid:.1}){level}",
                    law.kappa, law.e, law.c_mu
                )
            }
            None => "wall function: no face on a wall patch, it changes nothing".into(),
        };
        out.push(Finding {
            level: Level::Note,
            message,
        });
    }
    if mesh.patches.iter().any(|p| p.kind == "wedge") {
        out.push(Finding {
            level: Level::Warning,
            message: "an axisymmetric (wedge) case: particles reflect at the wedge faces instead of moving round the axis; their azimuthal motion is not represented".into(),
        });
    }
    let particles = scene.initial_particles();
    let outside: Vec<&scg_core::ParticleSpec> = particles
        .iter()
        .filter(|p| m.flow.find_cell(p.position).is_none())
        .collect();
    if let Some(first) = outside.first() {
        out.push(Finding {
            level: Level::Warning,
            message: format!(
                "{} of {} initial particles start outside the flow mesh (first: group `{}` at {:?} m); they are removed as lost at the first step",
                outside.len(),
                particles.len(),
                scene.groups[first.group as usize].name,
                first.position.to_array()
            ),
        });
    }
    for (i, f) in scene.feeders.iter().enumerate() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(i as u64);
        let region = match &f.source {
            FeedSource::Region(r) => r,
            FeedSource::Patch(p) => {
                // the centres, one simulated radius inward, must be inside the mesh
                let g = &scene.groups[f.group];
                // (a size distribution's largest particles)
                let r = 0.5 * coarse_grain(g.law, g.alpha, g.max_diameter(), g.density).diameter;
                let n = (0..FEEDER_SAMPLES)
                    .filter(|_| m.flow.find_cell(p.sample(&mut rng, r).centre).is_none())
                    .count();
                if n > 0 {
                    out.push(Finding {
                        level: Level::Warning,
                        message: format!(
                            "feeders[{i}]: {n} of {FEEDER_SAMPLES} sampled starts on patch `{}` (one radius, {r:.4e} m, inward) lie outside the flow mesh; particles fed there are removed as lost",
                            p.name
                        ),
                    });
                }
                continue;
            }
        };
        let n = (0..FEEDER_SAMPLES)
            .filter(|_| m.flow.find_cell(region.sample(&mut rng)).is_none())
            .count();
        if n > 0 {
            out.push(Finding {
                level: Level::Warning,
                message: format!(
                    "feeders[{i}]: {n} of {FEEDER_SAMPLES} sampled points of the feed region lie outside the flow mesh; particles fed there are removed as lost"
                ),
            });
        }
    }
    out
}

/// An unsteady field (`[flow] series`): its window, spacing and seam (a note), and
/// warnings where the snapshot spacing exceeds a group's response time τ or the field's
/// median cell crossing time (the changes between two snapshots are then not resolved
/// for those particles, or for the flow's own structures).
pub(super) fn series_findings(scene: &Scene, groups: &[GroupReport]) -> Vec<Finding> {
    let Some(m) = &scene.mesh_flow else {
        return Vec::new();
    };
    let Some(s) = &m.series else {
        return Vec::new();
    };
    let c = &s.spec.clock;
    let (lo, hi) = c.spacing();
    let mut note = format!(
        "unsteady field: {} snapshots ({} … {}), CFD t = {} … {} s as simulation t = 0 … {} s, spacing {lo:.4e} … {hi:.4e} s, linear in time between two; in memory: the pair around t, the first (it holds the mesh) and the next, read ahead",
        c.len(),
        s.dirs
            .first()
            .map_or(String::new(), |d| d.display().to_string()),
        s.dirs
            .last()
            .map_or(String::new(), |d| d.display().to_string()),
        s.start(),
        s.start() + c.span(),
        c.span()
    );
    // what the snapshots' tracker tables hold: the first's records, then per later
    // snapshot its values on them (three at a time: the pair and the one read ahead)
    if let (Some(first), Some(later)) = (m.flow.table(), s.spec.second.flow.table()) {
        note.push_str(&format!(
            "; tracker tables {:.3} MB for the first snapshot and {:.3} MB for each later one held (and {:.3} MB shared by them)",
            first.bytes() as f64 / 1e6,
            later.bytes() as f64 / 1e6,
            later.shared_bytes() as f64 / 1e6
        ));
    }
    // snapshots once read stay in memory while they fit (stages::flow_series::keep_bytes)
    let each = s.spec.second.flow.bytes();
    let budget = scg_core::stages::flow_series::keep_bytes();
    let all = m.flow.bytes() + each * (c.len() - 1);
    note.push_str(&format!(
        "; snapshots once read are kept while they fit in {:.0} MB (SCG_SERIES_KEEP_MB): {} ({:.1} MB for all {}, {:.1} MB each after the first)",
        budget as f64 / f64::from(1 << 20),
        if all <= budget {
            "this window is read once"
        } else {
            "this window does not fit, it is read again at every pass"
        },
        all as f64 / 1e6,
        c.len(),
        each as f64 / 1e6
    ));
    if let (Some(p), Some(jump)) = (c.period(), s.seam) {
        note.push_str(&format!(
            "; cycle = true: the window repeats every {p:.6e} s, the field running from the last snapshot back to the first over {:.4e} s (the mean spacing); across that seam the field changes by {:.3} % (rms over the cells, of the first snapshot's rms)",
            c.seam(),
            100.0 * jump
        ));
    }
    let mut out = vec![Finding {
        level: Level::Note,
        message: note,
    }];
    if let Some(g) = groups
        .iter()
        .filter(|g| g.tau.is_finite() && g.tau > 0.0)
        .min_by(|a, b| a.tau.total_cmp(&b.tau))
        && hi > g.tau
    {
        out.push(Finding {
            level: Level::Warning,
            message: format!(
                "the snapshots are up to {hi:.4e} s apart, longer than the response time τ = {:.4e} s of group `{}`: those particles follow changes of the flow between two snapshots that the series does not hold (linear in time there)",
                g.tau, g.name
            ),
        });
    }
    let geom = m.flow.geometry();
    let mut crossing: Vec<f64> = geom
        .cell_volumes
        .iter()
        .zip(m.flow.cell_values())
        .filter(|(v, u)| **v > 0.0 && u.length() > 0.0)
        .map(|(v, u)| v.cbrt() / u.length())
        .collect();
    if !crossing.is_empty() {
        let mid = crossing.len() / 2;
        let median = *crossing
            .select_nth_unstable_by(mid, |a, b| a.total_cmp(b))
            .1;
        if hi > median {
            out.push(Finding {
                level: Level::Warning,
                message: format!(
                    "the snapshots are up to {hi:.4e} s apart, longer than the field's median cell crossing time {median:.4e} s (cell size / speed): the flow's structures move more than a cell between two snapshots, which linear interpolation in time smears"
                ),
            });
        }
    }
    out
}
