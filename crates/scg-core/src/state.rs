//! Resources shared by several stages: the clock (the only `dt`), the run's health, the
//! per-group tally, the next particle id, and the largest step displacement.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use bevy_ecs::prelude::*;

/// Simulation clock (resource): t = step·dt, never the wall clock. `dt` lives here and
/// nowhere else; every stage reads it from the clock.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct SimClock {
    /// Steps completed.
    pub step: u64,
    /// Time step, s.
    pub dt: f64,
    /// Particle-steps done so far (Σ over steps of the particles moved).
    pub particle_steps: u64,
}

impl SimClock {
    /// A clock at step 0.
    pub fn new(dt: f64) -> Self {
        SimClock {
            step: 0,
            dt,
            particle_steps: 0,
        }
    }

    /// Simulation time, s.
    pub fn time(&self) -> f64 {
        self.step as f64 * self.dt
    }
}

/// A non-finite value found by the guard.
#[derive(Clone, Debug, PartialEq)]
pub struct NonFinite {
    /// Step at which it appeared.
    pub step: u64,
    /// Particle id.
    pub particle: u32,
    /// Field name (`position`, `velocity`).
    pub field: &'static str,
    /// The value.
    pub value: [f64; 3],
}

impl std::fmt::Display for NonFinite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "non-finite {} {:?} of particle {} at step {}",
            self.field, self.value, self.particle, self.step
        )
    }
}

/// Health of the run (resource). Integration kernels raise `suspect` cheaply; the guard
/// then scans and records the first offending particle (lowest id) in `failure`.
#[derive(Resource, Default)]
pub struct Health {
    suspect: AtomicBool,
    /// The failure that stops the run, if any.
    pub failure: Option<NonFinite>,
}

impl Health {
    /// Called by kernels when they produce a non-finite value.
    #[inline]
    pub fn raise(&self) {
        self.suspect.store(true, Ordering::Relaxed);
    }

    /// Whether a kernel raised the flag since the last call (clears it).
    pub fn take_suspect(&self) -> bool {
        self.suspect.swap(false, Ordering::Relaxed)
    }
}

/// The shortest contact the run has met (resource): the duration of every contact at the
/// approach speed with which it started (Hertz), measured by the contact stages, so a run
/// can tell how many steps resolve its contacts. Only the minimum is kept, as the bits of a
/// positive f64 (ordered like the numbers), so the result does not depend on the thread
/// count.
///
/// It also counts the contacts, and those that lasted fewer than
/// [`ContactResolution::MIN_STEPS`] steps.
#[derive(Resource, Debug)]
pub struct ContactResolution {
    dt: f64,
    shortest: [AtomicU64; 2],
    /// Per kind (wall, pair): contacts started, and of those the under-resolved ones.
    counts: [[AtomicU64; 2]; 2],
}

/// What [`ContactResolution`] measured for one kind of contact.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactCount {
    /// Shortest contact, s (`None`: no contact yet).
    pub shortest: Option<f64>,
    /// Contacts started.
    pub contacts: u64,
    /// Contacts that lasted fewer than [`ContactResolution::MIN_STEPS`] steps.
    pub under_resolved: u64,
}

impl ContactResolution {
    /// Steps per contact below which a contact is under-resolved.
    pub const MIN_STEPS: f64 = 20.0;

    /// An empty record for time step `dt` (s).
    pub fn new(dt: f64) -> Self {
        ContactResolution {
            dt,
            shortest: [
                AtomicU64::new(f64::INFINITY.to_bits()),
                AtomicU64::new(f64::INFINITY.to_bits()),
            ],
            counts: Default::default(),
        }
    }

    #[inline]
    fn note(&self, kind: usize, tc: f64) {
        if tc > 0.0 && tc.is_finite() {
            self.shortest[kind].fetch_min(tc.to_bits(), Ordering::Relaxed);
            self.counts[kind][0].fetch_add(1, Ordering::Relaxed);
            if tc < Self::MIN_STEPS * self.dt {
                self.counts[kind][1].fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    /// A particle–wall contact of duration `tc` (s) started.
    #[inline]
    pub fn note_wall(&self, tc: f64) {
        self.note(0, tc);
    }

    /// A particle–particle contact of duration `tc` (s) started.
    #[inline]
    pub fn note_pair(&self, tc: f64) {
        self.note(1, tc);
    }

    fn count(&self, kind: usize) -> ContactCount {
        let t = f64::from_bits(self.shortest[kind].load(Ordering::Relaxed));
        ContactCount {
            shortest: t.is_finite().then_some(t),
            contacts: self.counts[kind][0].load(Ordering::Relaxed),
            under_resolved: self.counts[kind][1].load(Ordering::Relaxed),
        }
    }

    /// Particle–wall contacts so far.
    pub fn wall(&self) -> ContactCount {
        self.count(0)
    }

    /// Particle–particle contacts so far.
    pub fn pair(&self) -> ContactCount {
        self.count(1)
    }

    /// Set the record (restoring a checkpoint).
    pub fn restore(&self, wall: ContactCount, pair: ContactCount) {
        for (k, c) in [wall, pair].into_iter().enumerate() {
            let t = c.shortest.unwrap_or(f64::INFINITY);
            self.shortest[k].store(t.to_bits(), Ordering::Relaxed);
            self.counts[k][0].store(c.contacts, Ordering::Relaxed);
            self.counts[k][1].store(c.under_resolved, Ordering::Relaxed);
        }
    }
}

/// Per-group counters kept by the feeder, outlet and contact stages (resource).
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct Tally {
    /// Particles drained through an outlet, per group.
    pub drained: Vec<u64>,
    /// Particles fed, per group.
    pub fed: Vec<u64>,
    /// Contacts that started, per group (a particle–particle contact counts for both).
    pub collisions: Vec<u64>,
}

impl Tally {
    /// Zero counters for `groups` groups.
    pub fn new(groups: usize) -> Self {
        Tally {
            drained: vec![0; groups],
            fed: vec![0; groups],
            collisions: vec![0; groups],
        }
    }
}

/// Next free particle id (resource): ids are unique over a run and never reused.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq)]
pub struct NextParticleId(pub u32);

impl NextParticleId {
    /// Take the next id.
    pub fn take(&mut self) -> u32 {
        let id = self.0;
        self.0 += 1;
        id
    }
}

/// The largest distance any particle moved in the last integration step (resource,
/// present when the scene has contacts). Every integrator records into it; the neighbour
/// stage takes it to bound displacements without a pass over all particles.
#[derive(Resource, Debug, Default)]
pub struct StepDisplacement {
    /// Bits of the largest squared step displacement, m² (non-negative floats order
    /// like their bits).
    max2_bits: AtomicU64,
    /// Set by an integrator that recorded every particle this step.
    reported: AtomicBool,
}

impl StepDisplacement {
    /// Record a squared displacement, m².
    #[inline]
    pub fn record(&self, d2: f64) {
        let b = d2.to_bits();
        if b > self.max2_bits.load(Ordering::Relaxed) {
            self.max2_bits.fetch_max(b, Ordering::Relaxed);
        }
    }

    /// Mark the step as fully recorded.
    pub fn mark_reported(&self) {
        self.reported.store(true, Ordering::Relaxed);
    }

    /// The raw state (bits of the largest squared displacement, reported), for checkpoints.
    pub fn raw(&self) -> (u64, bool) {
        (
            self.max2_bits.load(Ordering::Relaxed),
            self.reported.load(Ordering::Relaxed),
        )
    }

    /// Set the raw state (restoring a checkpoint).
    pub fn restore(&self, (bits, reported): (u64, bool)) {
        self.max2_bits.store(bits, Ordering::Relaxed);
        self.reported.store(reported, Ordering::Relaxed);
    }

    /// The largest displacement of the step, m, if an integrator reported one; resets.
    pub fn take(&self) -> Option<f64> {
        let reported = self.reported.swap(false, Ordering::Relaxed);
        let bits = self.max2_bits.swap(0, Ordering::Relaxed);
        reported.then(|| f64::from_bits(bits).sqrt())
    }
}

/// How particles move (resource): the integrator and the drag law (`None` without fluid
/// drag); see [`crate::sim::SimConfig`] for the meaning.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// Integrator.
    pub integrator: crate::physics::integrate::Integrator,
    /// Drag law, `None` without fluid drag.
    pub drag: Option<crate::physics::drag::DragLaw>,
    /// The opt-in forces evaluated each step, if any (they take every particle through
    /// the carrier seam's [`crate::physics::carrier::advance`]).
    pub forces: Option<crate::physics::forces::StepForces>,
}
