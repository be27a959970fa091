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

    /// The dispersion, if this modifier is one.
    pub fn dispersion(&self) -> Option<&Dispersion> {
        match self {
            CarrierModifier::Dispersion(d) => Some(d),
            CarrierModifier::ConstantOffset(_) => None,
        }
    }
}

/// Add the modifier's system (the integration stage's first) and its resource.
pub fn plugin(world: &mut World, b: &mut StepBuilder, m: CarrierModifier) {
    let name = m.name();
    let dispersion = m.dispersion().is_some();
    world.insert_resource(m);
    if dispersion {
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
    let (dt, step) = (clock.dt, clock.step);
    let mesh = mesh.as_ref().map(|m| &*m.spec.flow);
    // an unsteady flow: its two snapshots' velocity and turbulence at the step's mid time
    // (the value the last landing kept is of one snapshot: not read)
    let series = series.as_deref();
    let blend = series.map(FlowSeries::blend);
    let known = known.filter(|_| series.is_none());
    let mean = |cell: u32, x: DVec3| match (blend, mesh) {
        (Some(b), _) => Carrier::at(&b, Place::cell(cell), x).0,
        (None, Some(mf)) => Carrier::at(mf, Place::cell(cell), x).0,
        (None, None) => flow.velocity(x),
    };
    let turbulence = |cell: u32, x: DVec3| {
        series
            .and_then(|s| s.turbulence(cell))
            .unwrap_or_else(|| d.turbulence.at(cell, x))
    };
    let cols = (ids, xs, vs, cells, known, bypass(eddies), bypass(offs));
    for_each_piece(cols, |(ids, xs, vs, cells, known, eddies, offs)| {
        for i in 0..ids.len() {
            let cell = cells.map_or(0, |c| c[i].0);
            let x = xs[i].0;
            let t = turbulence(cell, x);
            let mut s = State {
                u: offs[i].0,
                age: eddies[i].age,
                sigma: eddies[i].sigma,
            };
            let mut draws = Draws::new(d.seed, ids[i].0, step);
            match d.model {
                Model::StochasticRas => {
                    // the mean velocity the last step's landing found here, when kept
                    // (the same value bit for bit), else sampled
                    let u = known
                        .and_then(|k| k[i].at(x))
                        .unwrap_or_else(|| mean(cell, x));
                    dispersion::stochastic_ras(dt, &t, vs[i].0, u, d.mask, &mut s, &mut draws);
                }
                Model::Langevin { c0 } => {
                    dispersion::langevin(dt, &t, c0, d.mask, &mut s, &mut draws);
                }
            }
            offs[i].0 = s.u;
            eddies[i] = Eddy {
                age: s.age,
                sigma: s.sigma,
            };
        }
    });
}
