//! A fork–join team of worker threads for the hot parallel loops (OpenMP style).
//!
//! The caller runs tasks itself, so a team of `n` workers has `n − 1` extra threads: on
//! two cores there are never more running threads than cores. Worker `w` first runs its
//! own share of the tasks (the `w`-th contiguous block, in order), then helps the others
//! with what is left of theirs; each task index is handed out once by an atomic counter
//! per share. A worker thus runs mostly the same tasks at every step and finds their data
//! in its own core's caches (when any thread took any task, the dense contact bed gained
//! only 1.3× from the second core, the pair data migrating between cores at every step).
//! [`Team::run`] returns when every worker has finished the job. Between jobs a worker
//! spins for the block time ([`super::ExecSettings::block_time`]) before it sleeps, so that the many short
//! jobs of a step start without a wake-up (an empty job costs about 0.7 µs on two cores).
//!
//! The team never decides *what* is computed, only *where*: callers split their work into
//! tasks by data size, never by thread count, so results are the same bits for any team.
//! A job started while another runs (nested, or from another thread, as in tests) runs on
//! the calling thread alone.

use std::any::Any;
use std::sync::atomic::{AtomicPtr, AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, OnceLock};

/// The job of one [`Team::run`] call, on the caller's stack while it runs.
struct Job<'a> {
    f: &'a (dyn Fn(usize) + Sync),
    n: usize,
}

struct Shared {
    /// Incremented (Release) when a job is posted.
    epoch: AtomicUsize,
    /// The posted job (valid until every worker has reported back).
    job: AtomicPtr<Job<'static>>,
    /// Next task index of each worker's share (tasks me·n/w .. (me+1)·n/w).
    next: Vec<Padded>,
    /// Workers that have not finished the current job.
    pending: AtomicUsize,
    /// Workers asleep (waiting on `wake`).
    sleeping: AtomicUsize,
    lock: Mutex<()>,
    wake: Condvar,
    /// The first panic of a task, re-raised on the caller.
    panic: Mutex<Option<Box<dyn Any + Send>>>,
    /// Held while a job runs.
    busy: Mutex<()>,
    block_time: std::time::Duration,
}

/// A counter alone on its cache lines (two workers update neighbouring ones).
#[repr(align(128))]
struct Padded(AtomicUsize);

/// A fixed team of worker threads (see the module documentation).
pub struct Team {
    workers: usize,
    shared: &'static Shared,
}

impl Team {
    /// A team of `workers` (≥ 1, the caller included) that spin for `block_time` between
    /// jobs before sleeping.
    pub fn new(workers: usize, block_time: std::time::Duration) -> Self {
        let workers = workers.max(1);
        let shared: &'static Shared = Box::leak(Box::new(Shared {
            epoch: AtomicUsize::new(0),
            job: AtomicPtr::new(std::ptr::null_mut()),
            next: (0..workers).map(|_| Padded(AtomicUsize::new(0))).collect(),
            pending: AtomicUsize::new(0),
            sleeping: AtomicUsize::new(0),
            lock: Mutex::new(()),
            wake: Condvar::new(),
            panic: Mutex::new(None),
            busy: Mutex::new(()),
            block_time,
        }));
        for k in 1..workers {
            std::thread::Builder::new()
                .name(format!("scg-worker-{k}"))
                .spawn(move || worker(shared, k, workers))
                .expect("failed to start a worker thread");
        }
        Team { workers, shared }
    }

    /// Number of workers, the caller included.
    pub fn workers(&self) -> usize {
        self.workers
    }

    /// Run `f(k)` for every k in 0..n, each once, on all workers; returns when all are
    /// done. A panic in a task is re-raised here after every worker has stopped.
    pub fn run(&self, n: usize, f: &(dyn Fn(usize) + Sync)) {
        let serial = || (0..n).for_each(f);
        if n == 0 {
            return;
        }
        if self.workers < 2 || n < 2 {
            return serial();
        }
        let Ok(_busy) = self.shared.busy.try_lock() else {
            return serial();
        };
        let s = self.shared;
        let job = Job { f, n };
        // SAFETY (lifetime): the job outlives its use, since this function returns only
        // after every worker has reported `pending` done for this epoch, and workers read
        // the pointer only between seeing the new epoch and reporting.
        let ptr = &job as *const Job<'_> as *mut Job<'static>;
        s.job.store(ptr, Ordering::Relaxed);
        for (w, c) in s.next.iter().enumerate() {
            c.0.store(share(w, self.workers, n).start, Ordering::Relaxed);
        }
        s.pending.store(self.workers - 1, Ordering::Relaxed);
        s.epoch.fetch_add(1, Ordering::SeqCst);
        if s.sleeping.load(Ordering::SeqCst) > 0 {
            let _g = s.lock.lock().unwrap_or_else(|e| e.into_inner());
            s.wake.notify_all();
        }
        let mine = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            take_tasks(s, 0, self.workers, &job)
        }));
        let mut spins = 0u32;
        while s.pending.load(Ordering::Acquire) != 0 {
            std::hint::spin_loop();
            spins += 1;
            if spins.is_multiple_of(1024) {
                std::thread::yield_now();
            }
        }
        s.job.store(std::ptr::null_mut(), Ordering::Relaxed);
        if let Err(p) = mine {
            std::panic::resume_unwind(p);
        }
        let theirs = s.panic.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(p) = theirs {
            std::panic::resume_unwind(p);
        }
    }
}

/// Worker `me`'s share of n tasks.
fn share(me: usize, workers: usize, n: usize) -> std::ops::Range<usize> {
    me * n / workers..(me + 1) * n / workers
}

/// Run worker `me`'s share of `job` in order, then help the others with what is left of
/// theirs. Each worker mostly runs the same tasks at every job (its caches keep their
/// data); a slow one is helped at the end.
fn take_tasks(s: &Shared, me: usize, workers: usize, job: &Job<'_>) {
    for w in (me..workers).chain(0..me) {
        let end = share(w, workers, job.n).end;
        loop {
            let k = s.next[w].0.fetch_add(1, Ordering::Relaxed);
            if k >= end {
                break;
            }
            (job.f)(k);
        }
    }
}

fn worker(s: &'static Shared, me: usize, workers: usize) {
    // Epoch 0 is the team's creation: any later one is a job, even one posted before
    // this thread started.
    let mut seen = 0;
    loop {
        // Wait for the next job: spin for the block time, then sleep.
        let start = std::time::Instant::now();
        loop {
            if s.epoch.load(Ordering::Acquire) != seen {
                break;
            }
            if start.elapsed() < s.block_time {
                // Check the epoch often (a job should start within a fraction of a µs)
                // and the clock rarely.
                for _ in 0..256 {
                    if s.epoch.load(Ordering::Relaxed) != seen {
                        break;
                    }
                    std::hint::spin_loop();
                }
                continue;
            }
            let mut g = s.lock.lock().unwrap_or_else(|e| e.into_inner());
            s.sleeping.fetch_add(1, Ordering::SeqCst);
            while s.epoch.load(Ordering::SeqCst) == seen {
                g = s.wake.wait(g).unwrap_or_else(|e| e.into_inner());
            }
            s.sleeping.fetch_sub(1, Ordering::SeqCst);
            break;
        }
        seen = s.epoch.load(Ordering::Acquire);
        let ptr = s.job.load(Ordering::Relaxed);
        // SAFETY: the caller posted this job before moving the epoch (SeqCst/Acquire
        // pair) and waits for our report below before the job goes out of scope.
        let job = unsafe { &*ptr };
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            take_tasks(s, me, workers, job)
        }));
        if let Err(p) = r {
            let mut slot = s.panic.lock().unwrap_or_else(|e| e.into_inner());
            slot.get_or_insert(p);
        }
        s.pending.fetch_sub(1, Ordering::Release);
    }
}

static TEAM: OnceLock<Team> = OnceLock::new();

/// The team in force: the process-wide one, sized by [`super::settings`] when first used,
/// or inside [`super::with_settings`] the team of that size (started once and kept).
pub fn team() -> &'static Team {
    if let Some(s) = super::scoped() {
        return sized(s.team_size(), s.block_time);
    }
    TEAM.get_or_init(|| {
        let s = super::settings();
        Team::new(s.team_size(), s.block_time)
    })
}

/// The kept team of `workers` and `block_time`.
fn sized(workers: usize, block_time: std::time::Duration) -> &'static Team {
    type Teams = Vec<(usize, std::time::Duration, &'static Team)>;
    static TEAMS: Mutex<Teams> = Mutex::new(Vec::new());
    let mut teams = TEAMS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(t) = teams.iter().find(|t| t.0 == workers && t.1 == block_time) {
        return t.2;
    }
    let t: &'static Team = Box::leak(Box::new(Team::new(workers, block_time)));
    teams.push((workers, block_time, t));
    t
}

/// A pointer that may cross threads (each task touches a distinct element).
struct SendPtr<T>(*mut T);
unsafe impl<T: Send> Sync for SendPtr<T> {}
unsafe impl<T: Send> Send for SendPtr<T> {}

/// `f(k, &mut items[k])` for every k on the team, each element once.
pub fn for_each_item<T: Send>(items: &mut [T], f: impl Fn(usize, &mut T) + Sync) {
    let n = items.len();
    let base = SendPtr(items.as_mut_ptr());
    let base = &base;
    team().run(n, &move |k| {
        // SAFETY: k < n, and the team hands out each index once, so no two calls alias.
        let item = unsafe { &mut *base.0.add(k) };
        f(k, item)
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Inside `with_settings` the team has the size asked for (the machine's cores
    /// permitting), and the process's team again after it.
    #[test]
    fn scoped_settings_choose_the_team() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let one = crate::exec::ExecSettings {
            threads: 1,
            ..Default::default()
        };
        let two = crate::exec::ExecSettings { threads: 2, ..one };
        assert_eq!(crate::exec::with_settings(one, || team().workers()), 1);
        assert_eq!(
            crate::exec::with_settings(two, || team().workers()),
            2.min(cores)
        );
        assert!(crate::exec::with_settings(one, || {
            let portable = crate::exec::ExecSettings {
                portable: true,
                ..one
            };
            crate::exec::with_settings(portable, || !crate::exec::lanes())
                && crate::exec::settings().threads == 1
        }));
        assert!(crate::exec::scoped().is_none());
    }

    #[test]
    fn every_index_once() {
        for n in [0, 1, 2, 3, 17, 1000] {
            let mut hits = vec![0u32; n];
            for_each_item(&mut hits, |k, h| *h += 1 + k as u32);
            assert!(
                hits.iter().enumerate().all(|(k, &h)| h == 1 + k as u32),
                "n = {n}"
            );
        }
    }

    #[test]
    fn panics_reach_the_caller() {
        let r = std::panic::catch_unwind(|| {
            let mut v = vec![0u8; 64];
            for_each_item(&mut v, |_, x| {
                if *x == 0 {
                    panic!("task failed")
                }
            });
        });
        assert!(r.is_err());
        // The team still works afterwards.
        let mut v = vec![1u8; 64];
        for_each_item(&mut v, |_, x| *x += 1);
        assert!(v.iter().all(|&x| x == 2));
    }
}
