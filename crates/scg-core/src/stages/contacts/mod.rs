//! Particle–particle contacts: neighbour-list upkeep ([`list`]), forces summed in fixed
//! slots ([`slots`]) and kicks ([`kicks`]).
//!
//! * [`list::maintain_neighbour_list`] (StepSet::NeighbourSearch) checks that the particle
//!   table still holds the particles the arrays index and rebuilds the Verlet list when
//!   needed, carrying each touching pair's history over by ids;
//! * [`slots::particle_contact_forces`] (StepSet::Forces) computes each pair's force once
//!   with [`crate::physics::contact::pair::pair_kernel`] (or, on AVX2 CPUs, four pairs at
//!   a time with [`crate::physics::contact::lanes`], the same bits) and adds it to its two
//!   particles (+F on i, −F exactly on j) in the slot of the pair;
//! * [`kicks::apply_contact_kicks`] (first of StepSet::Integration) adds the slots' sums
//!   per particle in slot order and kicks v and ω (after a dense step it zeroes the sums
//!   as it reads them, so the next force stage has nothing left to clear).
//!
//! The result is bit-identical whatever the thread count.
//!
//! In a run decomposed over processes (`scg-mpi`), [`ghosts`] adds read-only rows for
//! the particles other processes own near this one's: they take part in the list and
//! the pair forces, never in the kicks.

pub mod ghosts;
pub mod kicks;
pub mod list;
pub mod slots;

use bevy_ecs::prelude::*;

use crate::checkpoint::records::{Checkpoint, Part, Persist, Persistence};
use crate::components::{Diameter, GroupId, Mass, ParticleId};
use glam::DVec3;

use crate::physics::contact::pair::{PairArrays, PairParams};
use crate::physics::contact::tangential::TangentialStiffness;
use crate::physics::contact::{Material, NormalLaw, TangentialLaw};
use crate::physics::neighbour::NeighbourList;
use crate::physics::periodic::PeriodicBox;
use crate::state::StepDisplacement;
use crate::step::{StepBuilder, StepSet, StepSystem};
use slots::Slot;

/// Particle–particle contact settings (part of [`crate::SimConfig`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactConfig {
    /// Normal law.
    pub law: NormalLaw,
    /// Particle material (E, ν, e, μ_s).
    pub material: Material,
    /// Verlet skin, m.
    pub skin: f64,
    /// Orthogonal periodic box lengths, m (`None` = open).
    pub periodic: Option<DVec3>,
    /// Rolling friction coefficient μ_r (0 = off).
    pub rolling_friction: f64,
    /// Tangential stiffness rule.
    pub tangential_stiffness: TangentialStiffness,
}

impl ContactConfig {
    /// The tangential law these settings give.
    pub fn tangential(&self) -> TangentialLaw {
        TangentialLaw {
            stiffness: self.tangential_stiffness,
            ..TangentialLaw::new(self.law, self.material.friction, self.rolling_friction)
        }
    }

    /// The constants of the pair law.
    pub fn pair_params(&self) -> PairParams {
        let (e_eff, g_eff) = (
            self.material.effective_modulus(),
            self.material.effective_shear_modulus(),
        );
        PairParams {
            law: self.law,
            tangential: self.tangential(),
            e_eff,
            g_eff,
            periodic: self.periodic.map(PeriodicBox::new),
            mindlin_c: (6.0 * g_eff / e_eff).sqrt(),
        }
    }
}

/// The contact arrays indexed by the particle table's rows (followed by the ghost rows in
/// a decomposed run, see [`ghosts`]), the neighbour list and the pair states (resource).
#[derive(Resource, Debug)]
pub struct ContactState {
    /// The pair law.
    pub params: PairParams,
    /// Particle ids, by row (the key of every per-particle array here): the `local`
    /// rows of the particle table, then the ghost rows.
    pub ids: Vec<u32>,
    /// Rows of the particle table at the start of `ids` etc.
    local: usize,
    /// Ghost rows set by a decomposed run's driver for the coming step (empty otherwise).
    ghosts: ghosts::Ghosts,
    /// A ghost set was given since the last neighbour stage: rebuild the list.
    rebuild_due: bool,
    /// Pair histories brought by particles that moved here, for the next rebuild.
    arrived: Vec<ghosts::PairHistory>,
    /// Groups, by row.
    pub group: Vec<u32>,
    /// Radii, m, by row.
    pub radius: Vec<f64>,
    /// Masses, kg, by row.
    pub mass: Vec<f64>,
    /// dt/m by local row ([`crate::physics::integrate::linear_kick_factor`]), s/kg.
    kick_v: Vec<f64>,
    /// dt/I by local row ([`crate::physics::integrate::angular_kick_factor`]), s/(kg·m²).
    kick_w: Vec<f64>,
    /// Verlet list.
    pub list: NeighbourList,
    /// Pair states aligned with `list.pairs`.
    pub pairs: PairArrays,
    /// Force accumulation slots over the pair list (laid out at each rebuild).
    slots: Vec<Slot>,
    /// Whether this step's slots record the particles they touch (few contacts) or
    /// every particle is summed (dense packings).
    sparse: bool,
    /// Scratch of the sparse kick: rows already kicked this step.
    marked: Vec<bool>,
    /// Particle–particle contacts in touch after the last step.
    pub active: usize,
}

impl ContactState {
    /// Empty arrays for the contact settings `cfg`.
    pub fn new(cfg: &ContactConfig) -> Self {
        let params = cfg.pair_params();
        ContactState {
            list: NeighbourList::new(cfg.skin, params.periodic),
            params,
            ids: Vec::new(),
            local: 0,
            ghosts: ghosts::Ghosts::default(),
            rebuild_due: false,
            arrived: Vec::new(),
            group: Vec::new(),
            radius: Vec::new(),
            mass: Vec::new(),
            kick_v: Vec::new(),
            kick_w: Vec::new(),
            pairs: PairArrays::default(),
            slots: Vec::new(),
            sparse: false,
            marked: Vec::new(),
            active: 0,
        }
    }

    /// One line on the neighbour list for run reports: builds (their time and the last
    /// one's grid), exact displacement checks, candidate pairs and pairs in contact.
    pub fn summary(&self) -> String {
        use crate::physics::neighbour::GridKind;
        let grid = match self.list.grid {
            GridKind::None => "",
            GridKind::Dense => ", the last on a dense grid",
            GridKind::Coarse => ", the last on a coarse grid",
            GridKind::Hashed => ", the last on hashed cells",
        };
        format!(
            "{} builds ({:.3} s{grid}), {} exact displacement checks, {} candidate pairs in {} force slots, {} in contact",
            self.list.builds,
            self.list.build_time.as_secs_f64(),
            self.list.checks,
            self.list.pairs.len(),
            self.slots.len(),
            self.active
        )
    }

    /// Number of force accumulation slots (fixed by the pair list, not the threads).
    pub fn slot_count(&self) -> usize {
        self.slots.len()
    }
}

/// The contacts' part of a checkpoint: the arrays that carry over between steps and the
/// last step's displacement bound.
struct ContactsPart;

impl Persist for ContactsPart {
    fn part(&self) -> Option<Part> {
        Some(Part::Contacts)
    }

    fn save(&self, world: &World, c: &mut Checkpoint) {
        c.contacts = Some(world.resource::<ContactState>().record());
        c.displacement = world.resource::<StepDisplacement>().raw();
    }

    fn restore(&self, w: &mut World, c: &Checkpoint) -> Result<(), String> {
        let Some(rec) = &c.contacts else {
            return Err(Part::Contacts.mismatch());
        };
        w.resource::<StepDisplacement>().restore(c.displacement);
        let mut q = w.query::<(&ParticleId, &GroupId, &Diameter, &Mass)>();
        let rows: Vec<(ParticleId, GroupId, Diameter, Mass)> =
            q.iter(w).map(|(a, b, d, m)| (*a, *b, *d, *m)).collect();
        let ids: Vec<ParticleId> = rows.iter().map(|r| r.0).collect();
        let groups: Vec<GroupId> = rows.iter().map(|r| r.1).collect();
        let ds: Vec<Diameter> = rows.iter().map(|r| r.2).collect();
        let ms: Vec<Mass> = rows.iter().map(|r| r.3).collect();
        w.resource_mut::<ContactState>()
            .restore(rec, &ids, &groups, &ds, &ms, c.dt)
    }
}

/// Insert the contact resources and add the systems (called only when the scene declares
/// contacts).
pub fn plugin(world: &mut World, b: &mut StepBuilder, cfg: &ContactConfig) {
    world.insert_resource(StepDisplacement::default());
    world.insert_resource(ContactState::new(cfg));
    Persistence::register(world, ContactsPart);
    use StepSystem::*;
    b.add(
        StepSet::NeighbourSearch,
        "contacts",
        MaintainNeighbourList,
        list::maintain_neighbour_list,
    );
    b.add(
        StepSet::Forces,
        "contacts",
        ParticleContactForces,
        slots::particle_contact_forces,
    );
    b.add(
        StepSet::Integration,
        "contacts",
        ApplyContactKicks,
        kicks::apply_contact_kicks,
    );
}
