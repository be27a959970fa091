//! `mpirun -np N scg run CASE`: one simulation decomposed over N ranks.
//!
//! Every rank builds the whole scene, keeps the particles of its slab
//! ([`crate::decomp::Slabs`]) and runs the ordinary step on them with its thread team.
//! After each step the particles that left the slab migrate with their whole state (the
//! checkpoint's [`scg_core::checkpoint::ParticleRecord`]: ω, force and torque, wall
//! history, mesh cell). Every rank runs every feeder from the scene's seed, so the fed
//! particles, their ids and the random streams are the same on all ranks; each rank keeps
//! the fed particles of its slab and drops the others. Every `record_every` steps rank 0
//! gathers the particles, sorts them by id and writes the one `.rrd` and `.mcap` (and the
//! VTK/CSV frames asked for); drained and collision counts are summed over the ranks. When
//! the counts drift apart (the fullest rank over [`REBALANCE_TOLERANCE`] × the mean, checked
//! every step, at most every [`REBALANCE_MIN_STEPS`] steps), the slabs are cut again at the quantiles of all positions.
//!
//! The slabs run along the longest extent of the initial particles, or along the axis
//! `SCG_MPI_AXIS` names (`x`, `y` or `z`). `SCG_MPI_DECOMP=ids` shares the particles by a
//! hash of their id instead: nothing migrates and nothing needs rebalancing, the better
//! choice for scenes without particle contacts (docs/scaling.md). With contacts, every
//! rank receives ghost copies of the other slabs' particles near its own before each
//! step ([`crate::ghosts`]); contacts are refused with `SCG_MPI_DECOMP=ids`.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use scg_cli::EXIT_BAD_INPUT;
use scg_cli::run::{RunArgs, ensure_writable, extra_sinks};
use std::io::Write;

use scg_core::checkpoint::ParticleRecord;
use scg_core::components::ParticleId;
use scg_core::frame::{FrameSink, RunMeta};
use scg_core::stages::contacts::ContactState;
use scg_core::stages::contacts::ghosts::Due;
use scg_core::stages::feeder::SpawnOwner;
use scg_core::stages::recording::{FrameRow, RecordingParams, frame_from_rows};
use scg_core::state::Tally;
use scg_core::{SimError, Simulation};
use serde::{Deserialize, Serialize};

use crate::comm::{Comm, decode, encode};
use crate::decomp::{Owners, Slabs, longest_axis, merge_tally, needs_rebalance};
use crate::ghosts::Halo;

mod checkpoints;
use checkpoints::Ckpt;

/// The slabs are cut again when the fullest rank holds more than this many times the
/// mean count.
pub const REBALANCE_TOLERANCE: f64 = 1.2;

/// Steps at least between two rebalances (each gathers every position on every rank).
pub const REBALANCE_MIN_STEPS: u64 = 100;

/// Steps between the migrations of a run without particle contacts (slabs): nothing
/// there depends on which rank holds a particle, so a migration only keeps the slabs'
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

/// What a rank sends to rank 0 for a frame.
#[derive(Serialize, Deserialize)]
struct FramePart {
    rows: Vec<FrameRow>,
    drained: Vec<u64>,
    collisions: Vec<u64>,
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

/// Whether every rank is fine (`ok` on this one); a collective.
fn all_ok(comm: &Comm, ok: bool) -> bool {
    comm.all_gather_u64(&[u64::from(!ok)])
        .iter()
        .all(|&f| f == 0)
}

struct Ranked<'c> {
    comm: &'c Comm,
    sim: Simulation,
    owners: Owners,
    migrated: u64,
    rebalances: u64,
    /// Fed particles spawned here up to the last rebuild.
    kept_at_rebuild: u64,
}

impl Ranked<'_> {
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

    /// Take out the particles that left this rank's slab, by owner.
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

    /// Move the particles that left this rank's slab to their owners (a collective).
    fn migrate(&mut self) -> Result<(), String> {
        let out = self.leaving();
        self.deliver(&out)
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

    /// A rebuild (a collective): migrate the particles that left their slab, cut the
    /// slabs again when the counts drifted apart (at most every
    /// [`REBALANCE_MIN_STEPS`]), and give every rank its new ghost set.
    fn rebuild(
        &mut self,
        halo: Option<&mut Halo>,
        times: &mut Times,
        last: &mut u64,
    ) -> Result<(), String> {
        let t = Instant::now();
        self.migrate()?;
        let held = self.sim.particle_count() as u64;
        let counts = self.comm.all_gather_u64(&[held]);
        times.migrate += t.elapsed();
        let n = self.sim.step_count();
        if n >= *last + REBALANCE_MIN_STEPS && needs_rebalance(&counts, REBALANCE_TOLERANCE) {
            *last = n;
            let t = Instant::now();
            self.rebalance()?;
            times.rebalance += t.elapsed();
        }
        if let Some(halo) = halo {
            let t = Instant::now();
            halo.regather(self.comm, &mut self.sim, &self.owners);
            times.ghosts += t.elapsed();
        }
        self.kept_at_rebuild = self.kept();
        Ok(())
    }

    /// Cut the slabs again at the quantiles of all positions and migrate.
    fn rebalance(&mut self) -> Result<(), String> {
        let Owners::Slabs(slabs) = &self.owners else {
            return Ok(());
        };
        let (axis, period) = (slabs.axis, slabs.period);
        let mine: Vec<f64> = self
            .sim
            .frame_rows()
            .iter()
            .map(|r| r.position[axis])
            .collect();
        let all: Vec<f64> = self
            .comm
            .all_gather_bytes(&encode(&mine))
            .iter()
            .flat_map(|b| decode::<Vec<f64>>(b))
            .collect();
        self.owners = Owners::Slabs(Slabs::balanced(axis, self.comm.size(), &all, period));
        self.own_feeds();
        self.rebalances += 1;
        self.migrate()
    }

    /// The frame to write here: this rank's own part of it (`per_rank`), or the whole
    /// frame gathered on rank 0 (`None` on the others).
    fn frame(
        &mut self,
        params: &RecordingParams,
        per_rank: bool,
    ) -> Option<scg_core::frame::Frame> {
        if !per_rank {
            return self.gather_frame(params);
        }
        let tally = self.sim.world.resource::<Tally>().clone();
        Some(frame_from_rows(
            self.sim.step_count(),
            self.sim.time(),
            params,
            &tally,
            self.sim.frame_rows(),
        ))
    }

    /// Gather the particles on rank 0; the frame there (`None` on the other ranks).
    fn gather_frame(&mut self, params: &RecordingParams) -> Option<scg_core::frame::Frame> {
        let tally = self.sim.world.resource::<Tally>().clone();
        let part = FramePart {
            rows: self.sim.frame_rows(),
            drained: tally.drained.clone(),
            collisions: tally.collisions.clone(),
        };
        let parts = self.comm.gather_bytes(&encode(&part))?;
        let mut rows = Vec::new();
        let mut tallies = Vec::new();
        for b in &parts {
            let p: FramePart = decode(b);
            rows.extend(p.rows);
            let mut t = tally.clone();
            t.drained = p.drained;
            t.collisions = p.collisions;
            tallies.push(t);
        }
        let merged = merge_tally(&tallies).unwrap_or(tally);
        Some(frame_from_rows(
            self.sim.step_count(),
            self.sim.time(),
            params,
            &merged,
            rows,
        ))
    }
}

/// Run `scg run` over the ranks of `comm`; returns the exit status (the same on every
/// rank).
pub fn run(comm: &Comm, args: RunArgs) -> i32 {
    let root = comm.rank() == 0;
    let (scene, report) = match scg_cli::run::load_checked(&args, root) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let record = !args.no_record;
    if args.plan {
        if root {
            let sim = scene.build(record);
            println!(
                "schedule of scene `{}` ({} systems, on each of {} MPI ranks):",
                scene.name,
                sim.plan().systems.len(),
                comm.size()
            );
            print!("{}", sim.plan().render());
        }
        return 0;
    }
    // What the one-rank run reports at its end from logs a rank holds only its share of:
    // refused rather than reported from rank 0's share.
    let per_rank = [
        ("--summary-json", args.summary_json.is_some()),
        ("--fates-csv", args.fates_csv.is_some()),
        ("--erosion-csv", args.erosion_csv.is_some()),
        ("--erosion-vtk", args.erosion_vtk.is_some()),
        ("[erosion]", scene.erosion.is_some()),
    ];
    if comm.size() > 1
        && let Some((what, _)) = per_rank.iter().find(|(_, on)| *on)
    {
        if root {
            eprintln!(
                "error: {what} is not yet gathered over MPI ranks ({} here): run with one rank",
                comm.size()
            );
        }
        return EXIT_BAD_INPUT;
    }
    // Written per rank, a frame is never whole anywhere: the formats that need it are
    // made from the set afterwards.
    let per_rank = args.per_rank && comm.size() > 1 && record;
    if per_rank && (args.vtk.is_some() || args.frames_csv.is_some()) {
        if root {
            eprintln!(
                "error: --per-rank writes no whole frame, so no --vtk or --frames-csv during the run: make them from the recording with `scg replay <stem>.mcap --vtk DIR` (or --frames-csv DIR)"
            );
        }
        return EXIT_BAD_INPUT;
    }
    // The recording stage is the driver's (gathered on rank 0, or each rank's own part
    // with --per-rank), not the schedule's.
    let mut sim = scene.build(false);
    let Ckpt {
        every,
        path: checkpoint_path,
        stem,
    } = match checkpoints::prepare(comm, &args, &scene, &mut sim) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let by_id = std::env::var("SCG_MPI_DECOMP").as_deref() == Ok("ids");
    if by_id && sim.world.get_resource::<ContactState>().is_some() {
        if root {
            eprintln!(
                "error: {}: particle contacts over MPI ranks need slabs (SCG_MPI_DECOMP=ids shares them by id): run with one rank or without SCG_MPI_DECOMP=ids",
                scene.file,
            );
        }
        return EXIT_BAD_INPUT;
    }

    // Sinks on rank 0; every rank learns whether they could be made.
    let mut sinks: Option<Box<dyn FrameSink>> = None;
    let mut paths = Vec::new();
    let mut made = Ok(());
    if per_rank {
        made = make_part_sink(&scene, &args, &report, &stem, comm, &mut paths)
            .map(|s| sinks = Some(s));
        if let Err((e, _)) = &made {
            eprintln!("error: rank {}: {e}", comm.rank());
        }
    } else if root && record {
        made = make_sinks(&scene, &args, &report, &stem, &mut paths).map(|s| sinks = Some(s));
        if let Err((e, _)) = &made {
            eprintln!("error: {e}");
        }
    }
    if !all_ok(comm, made.is_ok()) {
        // The ranks that failed know why; the others stop with the same status.
        let code = match &made {
            Err((_, c)) => *c as u64,
            Ok(()) => 0,
        };
        return comm.all_gather_u64(&[code]).into_iter().max().unwrap_or(1) as i32;
    }

    // Initial slabs: equal shares of the initial particles along their longest extent.
    let rows = sim.frame_rows();
    let axis = match std::env::var("SCG_MPI_AXIS").as_deref() {
        Ok("x") => 0,
        Ok("y") => 1,
        Ok("z") => 2,
        _ => longest_axis(rows.iter().map(|r| glam::DVec3::from_array(r.position))),
    };
    let coords: Vec<f64> = rows.iter().map(|r| r.position[axis]).collect();
    // Periodic contacts: the slabs wrap round the box along their axis.
    let period = sim
        .world
        .get_resource::<ContactState>()
        .and_then(|c| c.params.periodic)
        .map(|b| b.lengths[axis]);
    let owners = if by_id {
        Owners::Ids(comm.size())
    } else {
        Owners::Slabs(Slabs::balanced(axis, comm.size(), &coords, period))
    };
    let me = comm.rank();
    drop(sim.extract_particles(|id, x| owners.owner(id, x) != me));
    let mut r = Ranked {
        comm,
        sim,
        owners,
        migrated: 0,
        rebalances: 0,
        kept_at_rebuild: 0,
    };
    r.own_feeds();

    let params = RecordingParams {
        every: scene.record_every.max(1),
        groups: scene.sim_config(true).groups,
    };
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register(sig, Arc::clone(&stop));
    }
    let steps = scene.steps();
    if root {
        let n0 = scene.groups.iter().map(|g| g.count()).sum::<usize>();
        eprintln!(
            "running `{}` on {} MPI ranks × {} threads: {} particles, {} steps of {:.3e} s, particles {}",
            scene.name,
            comm.size(),
            scg_core::exec::settings().team_size(),
            n0,
            steps,
            scene.dt,
            if by_id {
                "by id (no migration)".to_string()
            } else {
                format!("in slabs along {}", ["x", "y", "z"][axis])
            }
        );
    }
    let mut times = Times::default();
    let mut sink_err: Option<String> = None;
    let mut failure: Option<String> = None;
    let t0 = Instant::now();
    let mut write = |frame: Option<scg_core::frame::Frame>,
                     sinks: &mut Option<Box<dyn FrameSink>>| {
        if let (Some(f), Some(s)) = (frame, sinks.as_mut())
            && sink_err.is_none()
            && let Err(e) = s.write_frame(&f)
        {
            sink_err = Some(e);
        }
        sink_err.is_none()
    };
    if record {
        let f = r.frame(&params, per_rank);
        write(f, &mut sinks);
    }
    // `SCG_MPI_COUNTS=FILE`: rank 0 writes the step, the particle count and an
    // order-independent digest of the ids after every step (tests: no particle lost or
    // duplicated; a collective every step, only then).
    let count_every_step = std::env::var_os("SCG_MPI_COUNTS").is_some();
    let mut counts_log = match std::env::var_os("SCG_MPI_COUNTS") {
        Some(p) if root => match std::fs::File::create(&p) {
            Ok(f) => Some(std::io::BufWriter::new(f)),
            Err(e) => {
                eprintln!("error: SCG_MPI_COUNTS {}: {e}", p.to_string_lossy());
                None
            }
        },
        _ => None,
    };
    // Contacts over slabs: ghost particles, a new set at every rebuild, forwarded states
    // between (a flag exchange every step). Without, a sync point only every
    // MIGRATE_EVERY steps and where a frame, a checkpoint or the end is due.
    let mut halo = crate::ghosts::Halo::new(&scene);
    let contacts = !by_id && r.sim.world.get_resource::<ContactState>().is_some();
    let start = r.sim.step_count();
    let mut interrupted = false;
    let mut last_rebalance = start;
    let mut sink_failed = false;
    let mut checkpointed: Option<u64> = None;
    let mut n = start;
    loop {
        let frame_due = record && n > start && n.is_multiple_of(params.every);
        let ckpt_due = every.is_some_and(|e| n > start && (n.is_multiple_of(e) || n >= steps));
        let migrate_due = !by_id && (n - start).is_multiple_of(MIGRATE_EVERY);
        let sync =
            contacts || count_every_step || frame_due || ckpt_due || migrate_due || n >= steps;
        if !sync {
            let t = Instant::now();
            if failure.is_none()
                && let Err(e) = r.sim.step()
            {
                failure = Some(step_failure(e));
            }
            times.compute += t.elapsed();
            n += 1;
            continue;
        }
        // The sync point after step n: every rank's flags (failures, interrupts, whether
        // its ghosts' owners need a rebuild); with contacts they travel with the
        // forwarded ghost states when the peers are all the ranks.
        let t = Instant::now();
        let mut flags = (u64::from(failure.is_some()) * FAILED)
            | (u64::from(sink_failed) * SINK_FAILED)
            | (u64::from(stop.load(Ordering::Relaxed)) * STOP);
        if contacts {
            match scg_core::stages::contacts::ghosts::rebuild_due_here(&mut r.sim.world) {
                Due::Table => flags |= REBUILD | STALE,
                Due::Moved => flags |= REBUILD,
                Due::No => {}
            }
            if r.kept() != r.kept_at_rebuild || n == start {
                flags |= REBUILD | STALE;
            }
        }
        let any = if contacts && halo.reaches_all() {
            let any = halo.forward(comm, &mut r.sim, flags, STALE);
            times.ghosts += t.elapsed();
            any
        } else {
            let any = comm.all_gather_u64(&[flags]).iter().fold(0, |a, f| a | f);
            times.migrate += t.elapsed();
            if contacts && any & REBUILD == 0 {
                let t = Instant::now();
                halo.forward(comm, &mut r.sim, 0, STALE);
                times.ghosts += t.elapsed();
            }
            any
        };
        if count_every_step {
            let (held, ids) = r.id_digest();
            let all = comm.all_gather_u64(&[held, ids]);
            if let Some(log) = counts_log.as_mut()
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
        if frame_due {
            let t = Instant::now();
            let f = r.frame(&params, per_rank);
            sink_failed |= !write(f, &mut sinks);
            times.record += t.elapsed();
        }
        // A checkpoint at every multiple of the interval, at the end and when interrupted
        // (a collective: every rank's share gathered and merged on rank 0).
        if every.is_some() && (ckpt_due || (any & STOP != 0 && n > start)) {
            let t = Instant::now();
            let saved = r.write_checkpoint(&checkpoint_path, &scene);
            times.record += t.elapsed();
            if let Err(e) = &saved {
                failure = Some(e.clone());
            }
            if !all_ok(comm, saved.is_ok()) {
                failure.get_or_insert_with(|| "a checkpoint failed on rank 0".into());
                break;
            }
            checkpointed = Some(n);
        }
        if any & STOP != 0 {
            interrupted = true;
            break;
        }
        if n >= steps {
            break;
        }
        if (contacts && any & REBUILD != 0) || (!contacts && migrate_due) {
            let ghosts = if contacts { Some(&mut halo) } else { None };
            if let Err(e) = r.rebuild(ghosts, &mut times, &mut last_rebalance) {
                failure = Some(e);
            }
        }
        let t = Instant::now();
        if failure.is_none()
            && let Err(e) = r.sim.step()
        {
            failure = Some(step_failure(e));
        }
        times.compute += t.elapsed();
        n += 1;
    }
    let wall = t0.elapsed().as_secs_f64();
    if let Some(mut log) = counts_log.take() {
        let _ = log.flush();
    }

    // Reports, on rank 0.
    let fails: Vec<Option<String>> = comm
        .all_gather_bytes(&encode(&failure))
        .iter()
        .map(|b| decode(b))
        .collect();
    let first_failure = fails.iter().flatten().next().cloned();
    let steps_done = r.sim.step_count();
    let ps: u64 = comm.all_gather_u64(&[r.sim.particle_steps()]).iter().sum();
    let per_rank = comm.all_gather_u64(&[
        times.compute.as_nanos() as u64,
        times.ghosts.as_nanos() as u64,
        times.migrate.as_nanos() as u64,
        times.record.as_nanos() as u64,
        times.rebalance.as_nanos() as u64,
        r.migrated,
        r.sim.frame_rows().len() as u64,
    ]);
    let (builds, build_time) = r
        .sim
        .world
        .get_resource::<ContactState>()
        .map_or((0, 0), |c| {
            (c.list.builds, c.list.build_time.as_nanos() as u64)
        });
    let ghost_stats = comm.all_gather_u64(&[
        times.ghosts.as_nanos() as u64,
        halo.received,
        builds,
        build_time,
    ]);
    let fin = sinks.as_mut().map_or(Ok(()), |s| s.finish());
    let mut code = 0;
    if root {
        match &first_failure {
            None => eprintln!(
                "{} {steps_done} steps (t = {:.6} s) in {wall:.3} s on {} ranks: {:.3e} particle-steps/s, {} slab rebalances",
                if interrupted {
                    "interrupted after"
                } else {
                    "done:"
                },
                r.sim.time(),
                comm.size(),
                ps as f64 / wall.max(1e-12),
                r.rebalances
            ),
            Some(e) => eprintln!("error: run stopped at step {steps_done}: {e}"),
        }
        let share = crate::timing::time_shares(&per_rank);
        eprintln!(
            "share of the step time (all ranks): compute {:.1} %, ghost exchange {:.1} %, migration {:.1} %, recording (gather) {:.1} %, rebalance {:.1} %",
            100.0 * share[0],
            100.0 * share[1],
            100.0 * share[2],
            100.0 * share[3],
            100.0 * share[4]
        );
        eprintln!(
            "time per rank (s): compute, ghost exchange, migration, recording (gather), rebalance; particles migrated in, held at the end:"
        );
        for (k, c) in per_rank.chunks(crate::timing::FIELDS).enumerate() {
            let s = |ns: u64| ns as f64 * 1e-9;
            eprintln!(
                "  rank {k:<4} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3}   {:>9} {:>9}",
                s(c[0]),
                s(c[1]),
                s(c[2]),
                s(c[3]),
                s(c[4]),
                c[5],
                c[6]
            );
        }
        if halo.exchanges > 0 {
            eprintln!(
                "ghosts: {} sets given (rebuilds), states forwarded on {} steps",
                halo.exchanges, halo.forwards
            );
            eprintln!(
                "ghost exchange per rank (s; ghosts held per step on average; neighbour-list builds, their time in s):"
            );
            for (k, c) in ghost_stats.chunks(4).enumerate() {
                eprintln!(
                    "  rank {k:<4} {:>9.3}   {:>9.1}   {:>9} {:>9.3}",
                    c[0] as f64 * 1e-9,
                    c[1] as f64 / (halo.exchanges + halo.forwards) as f64,
                    c[2],
                    c[3] as f64 * 1e-9
                );
            }
        }
        for p in &paths {
            eprintln!("wrote {}", p.display());
        }
        if let Some(n) = checkpointed {
            eprintln!("checkpoint {} at step {n}", checkpoint_path.display());
        }
        if let Some(e) = &sink_err {
            eprintln!("error: recorder failed: {e}");
        }
        if let Err(e) = &fin {
            eprintln!("error: {e}");
        }
    }
    if first_failure.is_some() || sink_err.is_some() || fin.is_err() {
        code = 1;
    }
    let any_code = comm.all_gather_u64(&[code]).into_iter().max().unwrap_or(0);
    if any_code != 0 {
        return any_code as i32;
    }
    if interrupted { 130 } else { 0 }
}

/// The recorder of this rank's part of a recording written per rank
/// (`<stem>.rank<k>.mcap`); rank 0 also writes the index `<stem>.mcap` naming the parts.
/// `Err` holds the message and the exit status.
fn make_part_sink(
    scene: &scg_scene::Scene,
    args: &RunArgs,
    report: &scg_scene::check::Report,
    stem: &str,
    comm: &Comm,
    paths: &mut Vec<std::path::PathBuf>,
) -> Result<Box<dyn FrameSink>, (String, i32)> {
    ensure_writable(&args.out).map_err(|e| (e, EXIT_BAD_INPUT))?;
    let meta = scene.run_meta(report.messages());
    let io = |e: scg_record::RecordError| (e.to_string(), 1);
    let part = |k: usize| format!("{stem}.rank{k}.mcap");
    if comm.rank() == 0 {
        let index = args.out.join(format!("{stem}.mcap"));
        let meta = RunMeta {
            parts: (0..comm.size()).map(part).collect(),
            ..meta.clone()
        };
        scg_record::McapSink::create(&index, &meta)
            .and_then(|mut s| s.close())
            .map_err(io)?;
        paths.push(index);
    }
    let path = args.out.join(part(comm.rank()));
    let sink = scg_record::McapSink::create(&path, &meta).map_err(io)?;
    if comm.rank() == 0 {
        paths.push(
            args.out
                .join(format!("{stem}.rank*.mcap ({} parts)", comm.size())),
        );
    }
    Ok(Box::new(scg_record::Background::spawn(vec![Box::new(
        sink,
    )])))
}

/// The recorders of rank 0: one `.rrd`, one `.mcap` and the VTK/CSV frames asked for
/// (one writer thread). `Err` holds the message and the exit status.
fn make_sinks(
    scene: &scg_scene::Scene,
    args: &RunArgs,
    report: &scg_scene::check::Report,
    stem: &str,
    paths: &mut Vec<std::path::PathBuf>,
) -> Result<Box<dyn FrameSink>, (String, i32)> {
    ensure_writable(&args.out).map_err(|e| (e, EXIT_BAD_INPUT))?;
    let stem = stem.to_string();
    let meta = scene.run_meta(report.messages());
    let rrd = args.out.join(format!("{stem}.rrd"));
    let mcap = args.out.join(format!("{stem}.mcap"));
    let io = |e: scg_record::RecordError| (e.to_string(), 1);
    let mut sinks: Vec<Box<dyn FrameSink>> = vec![
        Box::new(scg_record::RrdSink::create(&rrd, &meta).map_err(io)?),
        Box::new(scg_record::McapSink::create(&mcap, &meta).map_err(io)?),
    ];
    sinks.extend(
        extra_sinks(&args.vtk, &args.frames_csv, &RunMeta { case: stem, ..meta }).map_err(io)?,
    );
    paths.push(rrd);
    paths.push(mcap);
    paths.extend(args.vtk.iter().cloned());
    paths.extend(args.frames_csv.iter().cloned());
    Ok(Box::new(scg_record::Background::spawn(sinks)))
}
