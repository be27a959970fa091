//! The report of a decomposed run: how the particles are shared, rates, shares of the
//! step time, per rank.

use scg_core::stages::contacts::ContactState;

use super::{Decomposed, Outcome};
use crate::decomp::{Owners, Shape};

impl Decomposed<'_> {
    /// How the particles are shared, in words ("in slabs along x", "in 4 boxes by
    /// recursive bisection (cuts along x, y)", "by id"), with why when the shape was
    /// chosen ([`super::Decomposition::Auto`]).
    pub fn describe(&self) -> String {
        match &self.owners {
            Owners::Ids(_) => "by id (no migration)".to_string(),
            Owners::Regions(r) if self.shape == Shape::Auto => {
                let (than, other) = match r.slab_axis() {
                    Some(_) => ("no more", "by bisection"),
                    None => ("fewer", "in slabs"),
                };
                format!(
                    "{} (auto: {than} ghost copies within {:.3e} m than {other})",
                    r.describe(),
                    self.halo_reach()
                )
            }
            Owners::Regions(r) => r.describe(),
        }
    }

    /// The run's report lines on rank 0 (`None` on the others; a collective): the rate,
    /// the shares of the step time, per rank the times, migrations and particles held,
    /// and with contacts the ghosts and list builds.
    pub fn report(&mut self, out: &Outcome) -> Option<Vec<String>> {
        let comm = self.comm;
        let ps: u64 = comm
            .all_gather_u64(&[self.sim.particle_steps()])
            .iter()
            .sum();
        let held = self.sim.particle_count() as u64;
        let t = self.times;
        let per_rank = comm.all_gather_u64(&[
            t.compute.as_nanos() as u64,
            t.ghosts.as_nanos() as u64,
            t.migrate.as_nanos() as u64,
            t.record.as_nanos() as u64,
            t.rebalance.as_nanos() as u64,
            self.migrated,
            held,
        ]);
        let (builds, build_time, pairs, touching) = self
            .sim
            .world
            .get_resource::<ContactState>()
            .map_or((0, 0, 0, 0), |c| {
                (
                    c.list.builds,
                    c.list.build_time.as_nanos() as u64,
                    c.list.pairs.len() as u64,
                    c.active as u64,
                )
            });
        let ghost_stats = comm.all_gather_u64(&[
            t.ghosts.as_nanos() as u64,
            self.halo.received,
            builds,
            build_time,
            pairs,
            touching,
        ]);
        if comm.rank() != 0 {
            return None;
        }
        let mut lines = Vec::new();
        let wall = out.wall;
        lines.push(match &out.failure {
            None => format!(
                "{} {} steps (t = {:.6} s) in {wall:.3} s on {} ranks: {:.3e} particle-steps/s, {} rebalances",
                if out.interrupted {
                    "interrupted after"
                } else {
                    "done:"
                },
                out.steps,
                self.sim.time(),
                comm.size(),
                ps as f64 / wall.max(1e-12),
                self.rebalances
            ),
            Some(e) => format!("error: run stopped at step {}: {e}", out.steps),
        });
        if self.rebalances > 0 {
            lines.push(format!("particles at the end {}", self.describe()));
        }
        let share = crate::timing::time_shares(&per_rank);
        lines.push(format!(
            "share of the step time (all ranks): compute {:.1} %, ghost exchange {:.1} %, migration {:.1} %, recording (gather) {:.1} %, rebalance {:.1} %",
            100.0 * share[0],
            100.0 * share[1],
            100.0 * share[2],
            100.0 * share[3],
            100.0 * share[4]
        ));
        lines.push(
            "time per rank (s): compute, ghost exchange, migration, recording (gather), rebalance; particles migrated in, held at the end:".into(),
        );
        for (k, c) in per_rank.chunks(crate::timing::FIELDS).enumerate() {
            let s = |ns: u64| ns as f64 * 1e-9;
            lines.push(format!(
                "  rank {k:<4} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3}   {:>9} {:>9}",
                s(c[0]),
                s(c[1]),
                s(c[2]),
                s(c[3]),
                s(c[4]),
                c[5],
                c[6]
            ));
        }
        let h = &self.halo;
        if h.exchanges > 0 {
            lines.push(format!(
                "ghosts: {} sets given (rebuilds), states forwarded on {} steps",
                h.exchanges, h.forwards
            ));
            lines.push(
                "ghost exchange per rank (s; ghosts held per step on average; neighbour-list builds, their time in s; pairs listed, in contact at the end):".into(),
            );
            for (k, c) in ghost_stats.chunks(6).enumerate() {
                lines.push(format!(
                    "  rank {k:<4} {:>9.3}   {:>9.1}   {:>9} {:>9.3}   {:>9} {:>9}",
                    c[0] as f64 * 1e-9,
                    c[1] as f64 / (h.exchanges + h.forwards).max(1) as f64,
                    c[2],
                    c[3] as f64 * 1e-9,
                    c[4],
                    c[5]
                ));
            }
        }
        Some(lines)
    }
}
