//! What a mesh move reads at a particle's start before it moves: the fused dispersion's
//! step, the carrier velocity the last landing kept, and whether it is kept at all.

use glam::DVec3;

use crate::components::*;
use crate::physics::carrier::{Carrier, Place, Scheme};
use crate::physics::mesh_flow::MeshFlow;
use crate::stages::carrier::{CarrierModifier, DisperseStep};
use crate::state::Motion;

/// The fused dispersion of row `i` ([`DispersionInMove`](super::super::carrier::DispersionInMove)): its fluctuation for this step
/// from the state [`disperse`](super::super::carrier::disperse) reads — the mean carrier velocity
/// where the last landing kept it (not for an unsteady flow, `series`), else sampled in
/// `base` at the row's cell.
#[inline(always)]
#[allow(clippy::type_complexity)]
pub(super) fn disperse_row<B: Carrier>(
    step: Option<DisperseStep>,
    base: &B,
    series: bool,
    i: usize,
    (xs, vs, hs, us, ids): (
        &[Position],
        &[Velocity],
        &[CellHint],
        &[FlowAtCentre],
        &[ParticleId],
    ),
    (offs, eddies): (&mut Option<&mut [CarrierOffset]>, &mut Option<&mut [Eddy]>),
) {
    let (Some(ds), Some(o), Some(e)) = (step, offs.as_deref_mut(), eddies.as_deref_mut()) else {
        return;
    };
    let (x, cell) = (xs[i].0, hs[i].0);
    let mean = || {
        us[i]
            .at(x)
            .filter(|_| !series)
            .unwrap_or_else(|| Carrier::at(base, Place::cell(cell), x).0)
    };
    ds.apply(ids[i].0, cell, x, vs[i].0, mean, &mut e[i], &mut o[i]);
}

/// The carrier's velocity at the start `x` of a step as the last landing kept it
/// (`None` where it did not, or kept it of another pair of snapshots, `stale`): an
/// unsteady flow's two snapshots blended at the step's weight (`later`'s) as
/// [`Blend`](crate::physics::mesh_flow::series::Blend) blends them, plus the particle's
/// offset `off` when the carrier has one; the same bits as locating x again.
#[inline(always)]
pub(super) fn kept_start(
    k: &FlowAtCentre,
    x: DVec3,
    later: Option<(&MeshFlow, f64)>,
    stale: bool,
    off: Option<DVec3>,
) -> Option<DVec3> {
    if stale {
        return None;
    }
    let u = match later {
        None => k.at(x)?,
        Some((_, w)) => {
            let (a, b) = k.pair_at(x)?;
            crate::physics::mesh_flow::series::blend(a, b, w)
        }
    };
    Some(off.map_or(u, |o| u + o))
}

/// True when a step reads the fluid velocity at its start ([`Scheme::reads_start`]) or the
/// dispersion reads the mean velocity at the centre
/// ([`Model::reads_mean`](crate::physics::dispersion::Model::reads_mean)), so that
/// [`FlowAtCentre`] is kept. The landing finds the value anyway; keeping it costs a store.
pub(super) fn keeps_start(m: &Motion, carrier: Option<&CarrierModifier>) -> bool {
    let mean_at_centre = carrier
        .and_then(CarrierModifier::dispersion)
        .is_some_and(|d| d.model.reads_mean());
    mean_at_centre
        || Scheme {
            dt: 0.0,
            law: m.drag,
            integrator: m.integrator,
            fluid: Scheme::NO_FLUID,
            forces: None,
        }
        .reads_start()
}
