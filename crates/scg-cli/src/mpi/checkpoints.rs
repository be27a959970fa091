//! Checkpoints of a decomposed run from the command line: the options checked, a restart
//! restored on every rank ([`scg_mpi::driver::restore`]).

use std::path::PathBuf;

use scg_core::Simulation;
use scg_mpi::comm::Comm;
use scg_mpi::driver::all_ok;

use crate::EXIT_BAD_INPUT;
use crate::run::{RunArgs, recording_stem, set_suffix};

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
/// logs so far, the others from zero; each keeps its region's particles later). A
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
        && let Some(why) = scg_mpi::checkpoint::refusal(scene)
    {
        if root {
            eprintln!(
                "error: checkpoints over MPI ranks ({} here) do not cover {why}: run with one rank",
                comm.size()
            );
        }
        return Err(EXIT_BAD_INPUT);
    }
    let every = match crate::run::checkpoint_interval(args.checkpoint_every, scene.dt) {
        Ok(e) => e,
        Err(e) => {
            if root {
                eprintln!("error: {e}");
            }
            return Err(EXIT_BAD_INPUT);
        }
    };
    if let Some(path) = &args.restart {
        let restored = scg_record::checkpoint::read_checkpoint(path).and_then(|c| {
            scg_mpi::driver::restore(comm, sim, c).map_err(|e| format!("{}: {e}", path.display()))
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
