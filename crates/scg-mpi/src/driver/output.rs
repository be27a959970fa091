//! What a decomposed run writes: frames (gathered on rank 0, or each rank's own part)
//! and the one checkpoint merged from every rank's.

use scg_core::checkpoint::Checkpoint;
use scg_core::stages::recording::{FrameRow, RecordingParams, frame_from_rows};
use scg_core::state::Tally;
use serde::{Deserialize, Serialize};

use super::{CheckpointPlan, Decomposed};
use crate::comm::{decode, encode};
use crate::decomp::merge_tally;

/// What a rank sends to rank 0 for a frame.
#[derive(Serialize, Deserialize)]
struct FramePart {
    rows: Vec<FrameRow>,
    drained: Vec<u64>,
    collisions: Vec<u64>,
}

impl Decomposed<'_> {
    /// The frame to write here: this rank's own part of it (`per_rank`), or the whole
    /// frame gathered on rank 0 (`None` on the others).
    pub(super) fn frame(
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
    /// Every rank's checkpoint gathered and merged on rank 0
    /// ([`crate::checkpoint::merge`]): the whole run's state as one rank would hold it
    /// (a collective; `None` on the other ranks). It holds every particle, on one node.
    pub fn gather_whole(&mut self) -> Option<Checkpoint> {
        let parts = self.comm.gather_bytes(&encode(&self.sim.checkpoint()))?;
        crate::checkpoint::merge(parts.iter().map(|b| decode(b)).collect())
    }

    /// Gather every rank's checkpoint on rank 0, merge them ([`Self::gather_whole`])
    /// and write the one file there (a collective; `Err` only on rank 0).
    pub(super) fn write_checkpoint(&mut self, plan: &CheckpointPlan) -> Result<(), String> {
        // Rank 0 merges at least its own; the others have nothing to write.
        let Some(mut c) = self.gather_whole() else {
            return Ok(());
        };
        c.scene.clone_from(&plan.scene);
        c.scene_file.clone_from(&plan.scene_file);
        scg_record::checkpoint::write_checkpoint(&plan.path, &c)
    }
}
