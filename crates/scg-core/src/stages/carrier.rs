//! Carrier modifiers: the stage that writes each particle's [`CarrierOffset`], the
//! velocity every integration scheme adds to the fluid velocity the particle sees
//! ([`crate::physics::carrier`]). Added only when the scene declares a modifier; its
//! system runs at the start of the integration stage, before the particles move.
//!
//! Two modifiers: a constant offset (a uniform wind on top of the flow, and the seam's
//! own test), and turbulent dispersion ([`Dispersion`]: the fluctuation of
//! [`crate::physics::dispersion`], one per particle, drawn from the particle's own
//! counter-based random stream keyed by (seed, id, step), so the run is bit-identical for
//! any thread count, rank count or restart).

use bevy_ecs::prelude::*;
use glam::DVec3;

use super::flow_series::FlowSeries;
use super::mesh_flow::MeshFlowState;
use super::table::{bypass, columns, columns_mut};
use crate::components::{
    CarrierOffset, CellHint, Eddy, FlowAtCentre, ParticleId, Position, Velocity,
};
use crate::exec::par::for_each_piece;
use crate::physics::carrier::{Carrier, Place};
use crate::physics::dispersion::{self, Model, State, Turbulence};
use crate::physics::flow::FlowField;
use crate::physics::random::Draws;
use crate::state::SimClock;
use crate::step::{StepBuilder, StepSet, StepSystem};

/// Turbulent dispersion: a model and the turbulence it reads.
#[derive(Clone, Debug, PartialEq)]
pub struct Dispersion {
    /// The model.
    pub model: Model,
    /// k and ε (uniform, a profile, or the mesh's cell values).
    pub turbulence: Turbulence,
    /// The run's seed (each particle's stream is keyed by it, its id and the step).
    pub seed: u64,
    /// 1 for every direction the flow solves, 0 for the normal of a 2-D case's `empty`
    /// patches (OpenFOAM's `constrainDirection`).
    pub mask: DVec3,
    /// Run as a pass of its own even where the mesh move could run it
    /// ([`DispersionInMove`]): the same bits, slower; for checking the fused move.
    pub own_pass: bool,
}

/// A carrier modifier (resource).
#[derive(Resource, Clone, Debug, PartialEq)]
pub enum CarrierModifier {
    /// The same velocity added everywhere, m/s.
    ConstantOffset(DVec3),
    /// Turbulent dispersion.
    Dispersion(Dispersion),
}

impl CarrierModifier {
    /// Scene and plan name.
    pub fn name(&self) -> &'static str {
        match self {
            CarrierModifier::ConstantOffset(_) => "carrier:constant_offset",
            CarrierModifier::Dispersion(d) => match d.model {
                Model::StochasticRas => "dispersion:stochastic_ras",
                Model::Langevin { .. } => "dispersion:langevin",
            },
        }
    }

    /// The mesh move's plan name when it runs this modifier's dispersion
    /// ([`DispersionInMove`]).
    pub fn in_move_name(&self) -> &'static str {
        match self.dispersion().map(|d| d.model) {
            Some(Model::StochasticRas) => "mesh_flow + dispersion:stochastic_ras",
            Some(Model::Langevin { .. }) => "mesh_flow + dispersion:langevin",
            None => "mesh_flow",
        }
    }

    /// The dispersion, if this modifier is one.
    pub fn dispersion(&self) -> Option<&Dispersion> {
        match self {
            CarrierModifier::Dispersion(d) => Some(d),
            CarrierModifier::ConstantOffset(_) => None,
        }
    }
}

/// The dispersion runs inside the mesh move's sweep (resource; [`plugin`] with `fuse`):
/// each particle's fluctuation is advanced just before it moves, from the same inputs
/// [`disperse`] reads, so the same bits without a pass of its own over the table.
#[derive(Resource, Clone, Copy, Debug, PartialEq, Eq)]
pub struct DispersionInMove;

/// Add the modifier's system (the integration stage's first) and its resource. `fuse`:
/// the particles move through a mesh flow and nothing between this stage and the move
/// reads the offsets, so a dispersion model runs inside the move ([`DispersionInMove`]).
pub fn plugin(world: &mut World, b: &mut StepBuilder, m: CarrierModifier, fuse: bool) {
    let name = m.name();
    let dispersion = m.dispersion().is_some();
    let fuse = fuse && !m.dispersion().is_some_and(|d| d.own_pass);
    world.insert_resource(m);
    if dispersion && fuse {
        world.insert_resource(DispersionInMove);
    } else if dispersion {
        b.add(
            StepSet::Integration,
            name,
            StepSystem::ModifyCarrier,
            disperse,
        );
    } else {
        b.add(
            StepSet::Integration,
            name,
            StepSystem::ModifyCarrier,
            modify_carrier,
        );
    }
}

/// Write every particle's offset for this step.
pub fn modify_carrier(m: Res<CarrierModifier>, mut q: Query<&mut CarrierOffset>) {
    let Some(offs) = columns_mut(&mut q) else {
        return;
    };
    if let CarrierModifier::ConstantOffset(du) = *m {
        for_each_piece(bypass(offs), |offs| {
            for o in offs {
                o.0 = du;
            }
        });
    }
}

/// Advance every particle's turbulent fluctuation by one step: the model reads the
/// turbulence at the particle (its mesh cell on a mesh), its velocity and the mean carrier
/// velocity there, and draws from the particle's stream for this step.
#[allow(clippy::type_complexity)]
pub fn disperse(
    m: Res<CarrierModifier>,
    clock: Res<SimClock>,
    flow: Res<FlowField>,
    mesh: Option<Res<MeshFlowState>>,
    ids: Query<(
        &ParticleId,
        &Position,
        &Velocity,
        Option<&CellHint>,
        Option<&FlowAtCentre>,
    )>,
    mut state: Query<(&mut Eddy, &mut CarrierOffset)>,
    series: Option<Res<FlowSeries>>,
) {
    let Some(d) = m.dispersion() else { return };
    let (Some((ids, xs, vs, cells, known)), Some((eddies, offs))) =
        (columns(&ids), columns_mut(&mut state))
    else {
        return;
    };
    let mesh = mesh.as_ref().map(|m| &*m.spec.flow);
    let series = series.as_deref();
    let blend = series.map(FlowSeries::blend);
    // an unsteady flow: the value the last landing kept is of one snapshot: not read
    let known = known.filter(|_| series.is_none());
    let mean = |cell: u32, x: DVec3| match (blend, mesh) {
        (Some(b), _) => Carrier::at(&b, Place::cell(cell), x).0,
        (None, Some(mf)) => Carrier::at(mf, Place::cell(cell), x).0,
        (None, None) => flow.velocity(x),
    };
    let step = DisperseStep::new(d, &clock, series);
    let cols = (ids, xs, vs, cells, known, bypass(eddies), bypass(offs));
    for_each_piece(cols, |(ids, xs, vs, cells, known, eddies, offs)| {
        for i in 0..ids.len() {
            let cell = cells.map_or(0, |c| c[i].0);
            let x = xs[i].0;
            // the mean velocity the last step's landing found here, when kept (the same
            // value bit for bit), else sampled
            let u = || {
                known
                    .and_then(|k| k[i].at(x))
                    .unwrap_or_else(|| mean(cell, x))
            };
            step.apply(ids[i].0, cell, x, vs[i].0, u, &mut eddies[i], &mut offs[i]);
        }
    });
}

/// One step of turbulent dispersion for one particle at a time: what [`disperse`] runs
/// over the particle table and the mesh move runs inside its own sweep
/// ([`DispersionInMove`]), the same operations so the same bits.
#[derive(Clone, Copy)]
pub(crate) struct DisperseStep<'a> {
    d: &'a Dispersion,
    dt: f64,
    step: u64,
    /// An unsteady flow: its turbulence at the step's mid time.
    series: Option<&'a FlowSeries>,
}

impl<'a> DisperseStep<'a> {
    pub(crate) fn new(d: &'a Dispersion, clock: &SimClock, series: Option<&'a FlowSeries>) -> Self {
        DisperseStep {
            d,
            dt: clock.dt,
            step: clock.step,
            series,
        }
    }

    /// Advance the fluctuation of particle `id` in mesh cell `cell` (0 off a mesh) at `x`
    /// with velocity `v`; `mean` gives the mean carrier velocity there (read only by
    /// `stochastic_ras` and Csanady's correction). The turbulence is the series' at the step's mid time, else the
    /// model's own; the draws come from the particle's stream for this step.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn apply(
        &self,
        id: u32,
        cell: u32,
        x: DVec3,
        v: DVec3,
        mean: impl FnOnce() -> DVec3,
        eddy: &mut Eddy,
        off: &mut CarrierOffset,
    ) {
        let d = self.d;
        let t = self
            .series
            .and_then(|s| s.turbulence(cell))
            .unwrap_or_else(|| d.turbulence.at(cell, x));
        let mut s = State {
            u: off.0,
            age: eddy.age,
            sigma: eddy.sigma,
        };
        let mut draws = Draws::new(d.seed, id, self.step);
        match d.model {
            Model::StochasticRas => {
                dispersion::stochastic_ras(self.dt, &t, v, mean(), d.mask, &mut s, &mut draws);
            }
            Model::Langevin { c0, csanady } => {
                let crossing = csanady.map(|beta| dispersion::Crossing {
                    beta,
                    slip: v - mean() - s.u,
                });
                dispersion::langevin(self.dt, &t, c0, crossing, d.mask, &mut s, &mut draws);
            }
        }
        off.0 = s.u;
        *eddy = Eddy {
            age: s.age,
            sigma: s.sigma,
        };
    }
}
