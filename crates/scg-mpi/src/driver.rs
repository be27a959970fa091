//! The decomposed driver: one simulation over the ranks of an MPI communicator, beside
//! the single-rank [`Simulation`] — what `mpirun -np N scg run CASE` runs, and what a
//! library user calls ([`Decomposed::new`], [`Decomposed::run`]).
//!
//! Every rank builds the whole scene, keeps the particles of its share (its region:
//! slabs along one axis or boxes by recursive bisection, [`crate::decomp::regions`]; or
//! shared by a hash of their id) and runs the
//! ordinary step on them with its thread team. Every rank runs every feeder from the
//! scene's seed and spawns only the particles it owns (`SpawnOwner`), so no rank scans
//! its particles for strangers after a feed.
//!
//! With particle contacts (regions) the run follows LAMMPS's pattern ([`crate::ghosts`]):
//! between two *rebuilds* the particle sets and the ghost sets are fixed; each step only
//! forwards the ghosts' x, v, ω along fixed row lists, with the step's flags (failures,
//! interrupts, whether a rank needs a rebuild) riding on those messages when every
//! rank's peers are all the others (else one small collective). A rebuild is decided
//! collectively after a step where some rank's particle moved more than half the skin
//! since its list was built or some rank's particle table changed (a particle fed,
//! drained): then the particles that left their region migrate with their whole state and
//! their touching pairs' histories, the regions are cut again if the counts drifted apart
//! (the fullest over [`REBALANCE_TOLERANCE`] × the mean, at most every
//! [`REBALANCE_MIN_STEPS`] steps), and every rank gets its new ghost set. A particle
//! strays at most half the skin beyond its region between rebuilds, which the ghost halo
//! (its radius, the largest radius and the whole skin) covers.
//!
//! Without particle contacts nothing depends on where a particle is held: the ranks meet
//! only every [`MIGRATE_EVERY`] steps (migration and the balance check) and where a
//! frame, a checkpoint or the end is due; shared by id they never migrate.
//!
//! Frames are gathered on rank 0 (sorted by id: the bits of one rank), or written by
//! every rank for its own particles ([`Options::per_rank`]; `scg_record::read_mcap`
//! merges the parts). Checkpoints are gathered and merged into one file in the
//! single-rank format ([`crate::checkpoint`]), which restarts on any number of ranks
//! ([`restore`]).

use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use scg_core::checkpoint::{Checkpoint, ParticleRecord};
use scg_core::components::ParticleId;
use scg_core::frame::FrameSink;
use scg_core::stages::contacts::ContactState;
use scg_core::stages::contacts::ghosts::{Due, RebuildCheck};
use scg_core::stages::feeder::SpawnOwner;
use scg_core::stages::recording::RecordingParams;
use scg_core::{SimError, Simulation};

use crate::comm::{Comm, decode, encode};
use crate::decomp::{Owners, Regions, Shape, longest_axis, needs_rebalance};
use crate::ghosts::Halo;

mod output;
mod report;

/// How a decomposed run shares its particles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decomposition {
    /// Slabs along an axis (0, 1, 2), or along the longest extent of the initial
    /// particles (`None`), cut at the quantiles of their coordinates; in a periodic box
    /// the slabs wrap round it.
    Slabs(Option<usize>),
    /// Boxes by recursive coordinate bisection ([`crate::decomp::regions`]).
    Bisection,
    /// With particle contacts, slabs or bisection, whichever gives fewer ghost copies
    /// (decided again at every rebalance; slabs on 2 ranks, where the two are the
    /// same); without, slabs along the longest extent.
    Auto,
    /// By a hash of the particle id: nothing migrates (refused with particle contacts).
    Ids,
}

/// Where and how often a decomposed run writes its checkpoint.
#[derive(Clone, Debug)]
pub struct CheckpointPlan {
    /// Steps between checkpoints (one is also written at the end and when interrupted).
    pub every: u64,
    /// The file.
    pub path: PathBuf,
    /// The scene's text, stored in the checkpoint.
    pub scene: String,
    /// The scene file's absolute path (its folder resolves relative paths on a restart).
    pub scene_file: String,
}

/// What [`Decomposed::run`] does besides stepping.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Record a frame every `every` steps (and the initial one) into the sink.
    pub recording: Option<RecordingParams>,
    /// Each rank writes its own particles of every frame into its own sink (else the
    /// frames are gathered on rank 0, whose sink writes them).
    pub per_rank: bool,
    /// Checkpoints.
    pub checkpoint: Option<CheckpointPlan>,
    /// Write the step, the particle count and an order-independent id digest after
    /// every step into the counts log (rank 0; a collective every step, for tests).
    pub count_every_step: bool,
}

/// How a run ended (the same on every rank, but the sink's error).
#[derive(Clone, Debug, Default)]
pub struct Outcome {
    /// Steps done.
    pub steps: u64,
    /// Stopped by the stop flag.
    pub interrupted: bool,
    /// The first failure over the ranks (a step, a checkpoint).
    pub failure: Option<String>,
    /// This rank's recorder failed.
    pub sink_error: Option<String>,
    /// The step of the last checkpoint written.
    pub checkpointed: Option<u64>,
    /// Wall time of the stepping loop, s.
    pub wall: f64,
}

/// Whether every rank is fine (`ok` on this one); a collective.
pub fn all_ok(comm: &Comm, ok: bool) -> bool {
    comm.all_gather_u64(&[u64::from(!ok)])
        .iter()
        .all(|&f| f == 0)
}

/// Restore checkpoint `c` (written by a decomposed run on any number of ranks, or by one
/// rank) into `sim` on every rank: the whole of it, rank 0 with the logs and counts so
/// far, the others from zero ([`crate::checkpoint::strip_logs`]); each keeps its share of
/// the particles when [`Decomposed::new`] splits them.
pub fn restore(comm: &Comm, sim: &mut Simulation, mut c: Checkpoint) -> Result<(), String> {
    if comm.rank() != 0 {
        crate::checkpoint::strip_logs(&mut c);
    }
    sim.restore(&c)
}

/// The regions are cut again when the fullest rank holds more than this many times the
/// mean count.
pub const REBALANCE_TOLERANCE: f64 = 1.2;

/// Steps at least between two rebalances (each gathers every position on every rank).
pub const REBALANCE_MIN_STEPS: u64 = 100;

/// Steps between the migrations of a run without particle contacts (regions): nothing
/// there depends on which rank holds a particle, so a migration only keeps the regions'
/// counts near the balance the rebalance check looks at, and its scan of every particle
/// (≈ 12 ns each) costs ≈ 0.1 ns per particle-step at this interval.
pub const MIGRATE_EVERY: u64 = 100;

/// The flags of a sync point: this rank's step failed.
const FAILED: u64 = 1;
/// … its recorder failed (rank 0).
const SINK_FAILED: u64 = 1 << 1;
/// … it was asked to stop (SIGINT, SIGTERM).
const STOP: u64 = 1 << 2;
/// … it needs a rebuild: a new ghost set, after a migration (contacts).
const REBUILD: u64 = 1 << 3;
/// … its particle table changed since the last rebuild: its rows cannot be forwarded.
const STALE: u64 = 1 << 4;

/// The message of a failed step.
fn step_failure(e: SimError) -> String {
    match e {
        SimError::NonFinite(n) => n.to_string(),
        e => e.to_string(),
    }
}

/// Wall time of the parts of a decomposed step, on one rank.
#[derive(Clone, Copy, Debug, Default)]
struct Times {
    compute: Duration,
    ghosts: Duration,
    migrate: Duration,
    record: Duration,
    rebalance: Duration,
}

/// One simulation decomposed over the ranks of a communicator: this rank's share of the
/// particles and what the decomposition keeps between steps.
pub struct Decomposed<'c> {
    comm: &'c Comm,
    /// This rank's simulation: the whole scene's clock, feeders and flow, its share of
    /// the particles.
    pub sim: Simulation,
    owners: Owners,
    /// Particles migrated in so far.
    pub migrated: u64,
    /// Rebalances (regions cut again) so far.
    pub rebalances: u64,
    /// Fed particles spawned here up to the last rebuild.
    kept_at_rebuild: u64,
    /// The ghosts of a run with contacts.
    halo: Halo,
    /// Particle contacts over regions (ghosts, rebuilds).
    contacts: bool,
    /// Shared by id (no migration).
    by_id: bool,
    /// How the regions are cut at a rebalance.
    shape: Shape,
    /// Whether this rank needs a rebuild (contacts; its query kept across steps).
    rebuild_check: RebuildCheck,
    /// Step of the last rebalance.
    last_rebalance: u64,
    /// Wall time of the parts of the steps, here.
    times: Times,
}

impl<'c> Decomposed<'c> {
    fn me(&self) -> usize {
        self.comm.rank()
    }

    /// The particles held here and an order-independent digest of their ids (a sum of
    /// SplitMix64 hashes, so that a lost or duplicated particle changes it).
    fn id_digest(&mut self) -> (u64, u64) {
        let mut q = self.sim.world.query::<&ParticleId>();
        q.iter(&self.sim.world).fold((0, 0), |(n, h), id| {
            (
                n + 1,
                h.wrapping_add(crate::decomp::splitmix64(u64::from(id.0))),
            )
        })
    }

    /// Take out the particles that left this rank's region, by owner.
    fn leaving(&mut self) -> Vec<Vec<ParticleRecord>> {
        let (me, owners) = (self.me(), &self.owners);
        let leaving = self
            .sim
            .extract_particles(|id, x| owners.owner(id, x) != me);
        let mut out: Vec<Vec<ParticleRecord>> = vec![Vec::new(); self.comm.size()];
        for p in leaving {
            out[owners.owner(p.id, p.spec.position)].push(p);
        }
        out
    }

    /// Send `out[r]` to rank r and take in what the others send here (a collective).
    /// With contacts, the particles' touching pairs' histories go with them.
    fn deliver(&mut self, out: &[Vec<ParticleRecord>]) -> Result<(), String> {
        let send: Vec<Vec<u8>> = crate::ghosts::migrants(&self.sim, out)
            .iter()
            .map(encode)
            .collect();
        for part in self.comm.all_to_all_bytes(&send) {
            self.migrated += crate::ghosts::arrive(&mut self.sim, decode(&part))? as u64;
        }
        Ok(())
    }

    /// Move the particles that left this rank's region to their owners (a collective).
    fn migrate(&mut self) -> Result<(), String> {
        let out = self.leaving();
        self.deliver(&out)
    }

    /// The ghost halo the shapes are compared by ([`Shape::Auto`]), m (0 without
    /// particle contacts).
    fn halo_reach(&self) -> f64 {
        self.halo.reach_in(&self.sim).unwrap_or(0.0)
    }

    /// Make the feeders spawn only the particles this rank owns (every rank draws them
    /// all, from the same seed).
    fn own_feeds(&mut self) {
        let (owners, me) = (self.owners.clone(), self.me());
        let kept = self
            .sim
            .world
            .get_resource::<SpawnOwner>()
            .map_or(0, |o| o.kept);
        self.sim.world.insert_resource(SpawnOwner {
            keep: Arc::new(move |id, x| owners.owner(id, x) == me),
            kept,
        });
    }

    /// Fed particles spawned here so far.
    fn kept(&self) -> u64 {
        self.sim
            .world
            .get_resource::<SpawnOwner>()
            .map_or(0, |o| o.kept)
    }

    /// A rebuild (a collective): migrate the particles that left their region, cut the
    /// regions again when the counts drifted apart (at most every
    /// [`REBALANCE_MIN_STEPS`]), and give every rank its new ghost set.
    ///
    /// Every rank takes part in every collective of it even after an error here (a
    /// particle that could not be inserted), which is returned at the end.
    fn rebuild(&mut self) -> Result<(), String> {
        let t = Instant::now();
        let mut result = self.migrate();
        let held = self.sim.particle_count() as u64;
        let counts = self.comm.all_gather_u64(&[held]);
        self.times.migrate += t.elapsed();
        let n = self.sim.step_count();
        if n >= self.last_rebalance + REBALANCE_MIN_STEPS
            && needs_rebalance(&counts, REBALANCE_TOLERANCE)
        {
            self.last_rebalance = n;
            let t = Instant::now();
            let balanced = self.rebalance();
            result = result.and(balanced);
            self.times.rebalance += t.elapsed();
        }
        if self.contacts {
            let t = Instant::now();
            self.sim.sort_particles_by_id();
            self.halo.regather(self.comm, &mut self.sim, &self.owners);
            self.times.ghosts += t.elapsed();
        }
        self.kept_at_rebuild = self.kept();
        result
    }

    /// Cut the regions again at the quantiles of all positions and migrate.
    fn rebalance(&mut self) -> Result<(), String> {
        let Owners::Regions(regions) = &self.owners else {
            return Ok(());
        };
        let period = regions.period();
        let mine: Vec<[f64; 3]> = self.sim.frame_rows().iter().map(|r| r.position).collect();
        let all: Vec<glam::DVec3> = self
            .comm
            .all_gather_bytes(&encode(&mine))
            .iter()
            .flat_map(|b| decode::<Vec<[f64; 3]>>(b))
            .map(glam::DVec3::from_array)
            .collect();
        self.owners = Owners::Regions(Regions::balanced(
            self.shape,
            self.comm.size(),
            &all,
            period,
            self.halo_reach(),
        ));
        self.own_feeds();
        self.rebalances += 1;
        self.migrate()
    }
}

impl<'c> Decomposed<'c> {
    /// Split `sim` (built from `scene` on every rank, or restored) over the ranks of
    /// `comm` as `how` says: each rank keeps its share of the particles. A collective.
    /// Errors (the same on every rank): particle contacts shared by id.
    pub fn new(
        comm: &'c Comm,
        mut sim: Simulation,
        scene: &scg_scene::Scene,
        how: Decomposition,
    ) -> Result<Self, String> {
        let contacts = sim.world.get_resource::<ContactState>().is_some();
        if how == Decomposition::Ids && contacts {
            return Err(format!(
                "{}: particle contacts over MPI ranks need regions (SCG_MPI_DECOMP=ids shares them by id): run with one rank or without SCG_MPI_DECOMP=ids",
                scene.file
            ));
        }
        let xs: Vec<glam::DVec3> = (sim.frame_rows().iter())
            .map(|r| glam::DVec3::from_array(r.position))
            .collect();
        // Slabs keep the axis of the initial particles' longest extent.
        let shape = match how {
            Decomposition::Slabs(Some(a)) => Shape::Slabs(a.min(2)),
            Decomposition::Slabs(None) | Decomposition::Ids => {
                Shape::Slabs(longest_axis(xs.iter().copied()))
            }
            Decomposition::Auto if !contacts => Shape::Slabs(longest_axis(xs.iter().copied())),
            Decomposition::Auto => Shape::Auto,
            Decomposition::Bisection => Shape::Bisection,
        };
        // Periodic contacts: the regions tile the box.
        let period = (sim.world.get_resource::<ContactState>())
            .and_then(|c| c.params.periodic)
            .map_or([None; 3], |b| b.lengths.to_array().map(Some));
        let halo = Halo::new(scene);
        let halo_reach = halo.reach_in(&sim).unwrap_or(0.0);
        let owners = match how {
            Decomposition::Ids => Owners::Ids(comm.size()),
            _ => Owners::Regions(Regions::balanced(
                shape,
                comm.size(),
                &xs,
                period,
                halo_reach,
            )),
        };
        let me = comm.rank();
        // (With contacts the first rebuild, before the first step, puts the rows of the
        // particles kept in id order: `Simulation::sort_particles_by_id`.)
        drop(sim.extract_particles(|id, x| owners.owner(id, x) != me));
        let last_rebalance = sim.step_count();
        let rebuild_check = RebuildCheck::new(&mut sim.world);
        let mut d = Decomposed {
            comm,
            sim,
            owners,
            migrated: 0,
            rebalances: 0,
            kept_at_rebuild: 0,
            halo,
            contacts: contacts && how != Decomposition::Ids,
            by_id: how == Decomposition::Ids,
            shape,
            rebuild_check,
            last_rebalance,
            times: Times::default(),
        };
        d.own_feeds();
        Ok(d)
    }

    /// Step up to step `steps` (a collective). Frames go to `sink` (rank 0's, or every
    /// rank's with [`Options::per_rank`]); `stop` (set by a signal handler) stops every
    /// rank at the next sync point, after a last checkpoint; `counts` receives the
    /// per-step counts on rank 0 ([`Options::count_every_step`]).
    pub fn run(
        &mut self,
        steps: u64,
        opts: &Options,
        mut sink: Option<&mut dyn FrameSink>,
        stop: &AtomicBool,
        mut counts: Option<&mut dyn Write>,
    ) -> Outcome {
        let comm = self.comm;
        let mut out = Outcome::default();
        let mut failure: Option<String> = None;
        let mut sink_failed = false;
        // Every rank is ready (the scene built, its share kept) before the clock starts:
        // else the first rank waits at the first sync for the last, and its wall time,
        // the run's, counts the others' start-up.
        all_ok(comm, true);
        let t0 = Instant::now();
        let write = |frame: Option<scg_core::frame::Frame>,
                     sink: &mut Option<&mut dyn FrameSink>,
                     err: &mut Option<String>| {
            if let (Some(f), Some(s)) = (frame, sink.as_mut())
                && err.is_none()
                && let Err(e) = s.write_frame(&f)
            {
                *err = Some(e);
            }
            err.is_none()
        };
        let start = self.sim.step_count();
        let record = opts.recording.as_ref();
        if let Some(params) = record {
            let f = self.frame(params, opts.per_rank);
            write(f, &mut sink, &mut out.sink_error);
        }
        let every = opts.checkpoint.as_ref().map(|c| c.every.max(1));
        let mut n = start;
        loop {
            let frame_due = record.is_some_and(|p| n > start && n.is_multiple_of(p.every));
            let ckpt_due = every.is_some_and(|e| n > start && (n.is_multiple_of(e) || n >= steps));
            let migrate_due = !self.by_id && (n - start).is_multiple_of(MIGRATE_EVERY);
            let sync = self.contacts
                || opts.count_every_step
                || frame_due
                || ckpt_due
                || migrate_due
                || n >= steps;
            if !sync {
                self.step(&mut failure);
                n += 1;
                continue;
            }
            // The sync point after step n: every rank's flags (failures, interrupts,
            // whether it needs a rebuild); with contacts they travel with the forwarded
            // ghost states when the peers are all the ranks.
            let t = Instant::now();
            let mut flags = (u64::from(failure.is_some()) * FAILED)
                | (u64::from(sink_failed) * SINK_FAILED)
                | (u64::from(stop.load(Ordering::Relaxed)) * STOP);
            if self.contacts {
                match self.rebuild_check.due(&mut self.sim.world) {
                    Due::Table => flags |= REBUILD | STALE,
                    Due::Moved => flags |= REBUILD,
                    Due::No => {}
                }
                if self.kept() != self.kept_at_rebuild || n == start {
                    flags |= REBUILD | STALE;
                }
            }
            let any = if self.contacts && self.halo.reaches_all() {
                let any = self.halo.forward(comm, &mut self.sim, flags, STALE);
                self.times.ghosts += t.elapsed();
                any
            } else {
                let any = comm.all_gather_u64(&[flags]).iter().fold(0, |a, f| a | f);
                self.times.migrate += t.elapsed();
                if self.contacts && any & REBUILD == 0 {
                    let t = Instant::now();
                    self.halo.forward(comm, &mut self.sim, 0, STALE);
                    self.times.ghosts += t.elapsed();
                }
                any
            };
            if opts.count_every_step {
                let (held, ids) = self.id_digest();
                let all = comm.all_gather_u64(&[held, ids]);
                if let Some(log) = counts.as_mut()
                    && n > start
                {
                    let total: u64 = all.chunks(2).map(|c| c[0]).sum();
                    let digest = all.chunks(2).fold(0u64, |a, c| a.wrapping_add(c[1]));
                    let _ = writeln!(log, "{n} {total} {digest}");
                }
            }
            if any & (FAILED | SINK_FAILED) != 0 {
                break;
            }
            if frame_due && let Some(params) = record {
                let t = Instant::now();
                let f = self.frame(params, opts.per_rank);
                sink_failed |= !write(f, &mut sink, &mut out.sink_error);
                self.times.record += t.elapsed();
            }
            // A checkpoint at every multiple of the interval, at the end and when
            // interrupted (a collective: every rank's share gathered and merged on rank 0).
            if let Some(plan) = &opts.checkpoint
                && (ckpt_due || (any & STOP != 0 && n > start))
            {
                let t = Instant::now();
                let saved = self.write_checkpoint(plan);
                self.times.record += t.elapsed();
                if let Err(e) = &saved {
                    failure = Some(e.clone());
                }
                if !all_ok(comm, saved.is_ok()) {
                    failure.get_or_insert_with(|| "a checkpoint failed on rank 0".into());
                    break;
                }
                out.checkpointed = Some(n);
            }
            if any & STOP != 0 {
                out.interrupted = true;
                break;
            }
            if n >= steps {
                break;
            }
            if ((self.contacts && any & REBUILD != 0) || (!self.contacts && migrate_due))
                && let Err(e) = self.rebuild()
            {
                failure = Some(e);
            }
            self.step(&mut failure);
            n += 1;
        }
        out.wall = t0.elapsed().as_secs_f64();
        out.steps = self.sim.step_count();
        let fails: Vec<Option<String>> = comm
            .all_gather_bytes(&encode(&failure))
            .iter()
            .map(|b| decode(b))
            .collect();
        out.failure = fails.iter().flatten().next().cloned();
        out
    }

    /// One step here unless a step failed before (the rank then only keeps the others
    /// company up to the next sync point).
    fn step(&mut self, failure: &mut Option<String>) {
        let t = Instant::now();
        if failure.is_none()
            && let Err(e) = self.sim.step()
        {
            *failure = Some(step_failure(e));
        }
        self.times.compute += t.elapsed();
    }
}
