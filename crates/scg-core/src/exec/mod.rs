//! Where the work runs: the fork–join [`team`] of worker threads and the parallel loops
//! over particle columns built on it ([`par`]). Nothing here decides *what* is computed,
//! so results are the same bits for any thread count.
//!
//! The settings ([`ExecSettings`]) are read once, by the command line (or a test), and
//! handed to [`configure`] before the first parallel loop; without that call the defaults
//! apply (every core, [`par::PARALLEL_THRESHOLD`], a block time of 1 ms).

pub mod par;
pub mod team;

use std::sync::OnceLock;
use std::time::Duration;

/// How the parallel loops run. Results never depend on these.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExecSettings {
    /// Threads of the team, the caller included (0 = one per core).
    pub threads: usize,
    /// Below this many particles a per-particle pass runs on the calling thread.
    pub parallel_min: usize,
    /// How long a worker spins after a job before it sleeps (0 = sleep at once).
    pub block_time: Duration,
}

impl Default for ExecSettings {
    fn default() -> Self {
        ExecSettings {
            threads: 0,
            parallel_min: par::PARALLEL_THRESHOLD,
            block_time: Duration::from_micros(1000),
        }
    }
}

impl ExecSettings {
    /// The defaults, changed by `SCG_THREADS`, `SCG_PARALLEL_MIN` and `SCG_BLOCKTIME_US`
    /// where they are set to a number.
    pub fn from_env() -> Self {
        let var = |name: &str| -> Option<u64> { std::env::var(name).ok()?.parse().ok() };
        let d = ExecSettings::default();
        ExecSettings {
            threads: var("SCG_THREADS").map_or(d.threads, |n| n as usize),
            parallel_min: var("SCG_PARALLEL_MIN").map_or(d.parallel_min, |n| n as usize),
            block_time: var("SCG_BLOCKTIME_US").map_or(d.block_time, Duration::from_micros),
        }
    }

    /// The team size these settings give on this machine (≥ 1, at most the core count).
    pub fn team_size(&self) -> usize {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        match self.threads {
            0 => cores,
            n => n.min(cores),
        }
    }
}

static SETTINGS: OnceLock<ExecSettings> = OnceLock::new();

/// Set the execution settings for this process. Only the first call (before any parallel
/// loop ran) takes effect; returns whether this one did.
pub fn configure(settings: ExecSettings) -> bool {
    SETTINGS.set(settings).is_ok()
}

/// The settings in force ([`ExecSettings::default`] when [`configure`] was never called).
pub fn settings() -> &'static ExecSettings {
    SETTINGS.get_or_init(ExecSettings::default)
}
