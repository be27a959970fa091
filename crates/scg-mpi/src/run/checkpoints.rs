//! Checkpoints of a decomposed run: the options checked, a restart restored on every rank,
//! and one checkpoint written from all ranks ([`crate::checkpoint`]).

use std::path::PathBuf;

use scg_cli::EXIT_BAD_INPUT;
use scg_cli::run::{RunArgs, recording_stem, set_suffix};
use scg_core::Simulation;

use super::{Ranked, all_ok};
use crate::comm::{Comm, decode, encode};

/// The checkpoint settings of a run, and the recordings' stem.
pub(super) struct Ckpt {
    /// Steps between checkpoints (`--checkpoint-every`).
    pub every: Option<u64>,
    /// Where checkpoints go (`--checkpoint`, default `<out>/<stem>.ckpt`).
    pub path: PathBuf,
    /// The recordings' stem (`-from<step>` added on a restart).
    pub stem: String,
}

/// Check the checkpoint options (refused over ranks for what [`crate::checkpoint::refusal`]
/// names), and on a restart restore the whole checkpoint on every rank (rank 0 with the
/// logs so far, the others from zero; each keeps its slab's particles later). A
/// collective; `Err` holds the exit status, the message printed on rank 0.
pub(super) fn prepare(
    comm: &Comm,
    args: &RunArgs,
    scene: &scg_scene::Scene,
    sim: &mut Simulation,
) -> Result<Ckpt, i32> {
    let root = comm.rank() == 0;
    let wanted =
        args.restart.is_some() || args.checkpoint_every.is_some() || args.checkpoint.is_some();
    if wanted
        && comm.size() > 1
        && let Some(why) = crate::checkpoint::refusal(scene)
    {
        if root {
            eprintln!(
                "error: checkpoints over MPI ranks ({} here) do not cover {why}: run with one rank",
                comm.size()
            );
        }
        return Err(EXIT_BAD_INPUT);
    }
    let every = match scg_cli::run::checkpoint_interval(args.checkpoint_every, scene.dt) {
        Ok(e) => e,
        Err(e) => {
            if root {
                eprintln!("error: {e}");
            }
            return Err(EXIT_BAD_INPUT);
        }
    };
    if let Some(path) = &args.restart {
        let restored = scg_record::checkpoint::read_checkpoint(path).and_then(|mut c| {
            if !root {
                crate::checkpoint::strip_logs(&mut c);
            }
            sim.restore(&c)
                .map_err(|e| format!("{}: {e}", path.display()))
        });
        if let Err(e) = &restored
            && root
        {
            eprintln!("error: {e}");
        }
        if !all_ok(comm, restored.is_ok()) {
            return Err(EXIT_BAD_INPUT);
        }
        if root {
            eprintln!(
                "restarting `{}` from {} at step {} (t = {:.6} s) on {} MPI ranks",
                scene.name,
                path.display(),
                sim.step_count(),
                sim.time(),
                comm.size()
            );
        }
    }
    let base = format!("{}{}", recording_stem(scene), set_suffix(&args.set));
    let path = args
        .checkpoint
        .clone()
        .unwrap_or_else(|| args.out.join(format!("{base}.ckpt")));
    let stem = match args.restart {
        Some(_) => format!("{base}-from{}", sim.step_count()),
        None => base,
    };
    Ok(Ckpt { every, path, stem })
}

impl Ranked<'_> {
    /// Gather every rank's checkpoint on rank 0, merge them ([`crate::checkpoint::merge`])
    /// and write the one file there (a collective; `Err` only on rank 0).
    pub(super) fn write_checkpoint(
        &mut self,
        path: &std::path::Path,
        scene: &scg_scene::Scene,
    ) -> Result<(), String> {
        let parts = self.comm.gather_bytes(&encode(&self.sim.checkpoint()));
        let Some(parts) = parts else {
            return Ok(());
        };
        let mut c = crate::checkpoint::merge(parts.iter().map(|b| decode(b)).collect())
            .ok_or("no checkpoint to merge")?;
        c.scene.clone_from(&scene.source);
        c.scene_file = scene.absolute_file();
        scg_record::checkpoint::write_checkpoint(path, &c)
    }
}
