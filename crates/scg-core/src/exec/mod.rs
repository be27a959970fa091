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
    /// Force the portable (scalar) paths where the CPU would run four lanes (AVX2): the
    /// same bits, for tests and the CI leg that checks them (`SCG_PORTABLE=1`).
    pub portable: bool,
}

impl Default for ExecSettings {
    fn default() -> Self {
        ExecSettings {
            threads: 0,
            parallel_min: par::PARALLEL_THRESHOLD,
            block_time: Duration::from_micros(1000),
            portable: false,
        }
    }
}

impl ExecSettings {
    /// The defaults, changed by `SCG_THREADS`, `SCG_PARALLEL_MIN` and `SCG_BLOCKTIME_US`
    /// where they are set to a number, and `SCG_PORTABLE=1`.
    pub fn from_env() -> Self {
        let var = |name: &str| -> Option<u64> { std::env::var(name).ok()?.parse().ok() };
        let d = ExecSettings::default();
        ExecSettings {
            threads: var("SCG_THREADS").map_or(d.threads, |n| n as usize),
            parallel_min: var("SCG_PARALLEL_MIN").map_or(d.parallel_min, |n| n as usize),
            block_time: var("SCG_BLOCKTIME_US").map_or(d.block_time, Duration::from_micros),
            portable: var("SCG_PORTABLE") == Some(1),
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

thread_local! {
    /// Settings in force on this thread inside [`with_settings`].
    static SCOPED: std::cell::Cell<Option<&'static ExecSettings>> =
        const { std::cell::Cell::new(None) };
}

/// The settings in force: those of the enclosing [`with_settings`] on this thread, else
/// the process's ([`ExecSettings::from_env`] when [`configure`] was never called).
pub fn settings() -> &'static ExecSettings {
    scoped().unwrap_or_else(|| SETTINGS.get_or_init(ExecSettings::from_env))
}

/// The settings of the enclosing [`with_settings`] on this thread, if any.
pub(crate) fn scoped() -> Option<&'static ExecSettings> {
    SCOPED.with(|s| s.get())
}

/// Run `f` on this thread with `settings` in force (team size, parallel threshold,
/// portable kernels), whatever the process was configured with: how tests compare thread
/// counts and kernels in one process. The team of each size is started once and kept.
pub fn with_settings<R>(settings: ExecSettings, f: impl FnOnce() -> R) -> R {
    static KNOWN: std::sync::Mutex<Vec<&'static ExecSettings>> = std::sync::Mutex::new(Vec::new());
    let interned = {
        let mut known = KNOWN.lock().unwrap_or_else(|e| e.into_inner());
        match known.iter().find(|k| ***k == settings) {
            Some(k) => *k,
            None => {
                let k: &'static ExecSettings = Box::leak(Box::new(settings));
                known.push(k);
                k
            }
        }
    };
    struct Restore(Option<&'static ExecSettings>);
    impl Drop for Restore {
        fn drop(&mut self) {
            SCOPED.with(|s| s.set(self.0));
        }
    }
    let _restore = Restore(SCOPED.with(|s| s.replace(Some(interned))));
    f()
}

/// True when the four-lane (AVX2) paths run: the CPU has AVX2 and the settings do not
/// force the portable paths ([`ExecSettings::portable`]). Every four-lane dispatch asks
/// this, once per call; the lanes give the portable paths' bits either way.
#[inline]
pub fn lanes() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        static AVX2: OnceLock<bool> = OnceLock::new();
        !settings().portable && *AVX2.get_or_init(|| std::arch::is_x86_feature_detected!("avx2"))
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
