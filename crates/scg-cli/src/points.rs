//! Where the independent points of `scg cost` and `scg study` run.
//!
//! A sweep or a study is a list of independent simulations (cost points, study variants):
//! each is a job `i → result`. [`map`] runs them through a [`Points`]: [`Local`] (the
//! default) runs them one after another in this process; another implementation (the
//! MPI build's, `scg_mpi`) spreads them over processes, each running its share with its
//! share of the cores, and hands every result, serialised, to the one process that writes
//! the outputs. Jobs must not depend on where they run: a result that is bit-deterministic
//! is then the same whichever process ran it.

use serde::Serialize;
use serde::de::DeserializeOwned;

/// Runs a list of independent jobs, each returning its serialised result.
pub trait Points {
    /// Run jobs `0..n` (this process calls `job` for its share, each job once over all
    /// processes). Returns every job's result in job order on the process that writes the
    /// outputs, `None` on the others. `cost[i]` is an estimate of job i's run time in any
    /// unit (to balance the shares); `cost` is empty or has `n` entries.
    fn map_bytes(
        &self,
        n: usize,
        cost: &[f64],
        job: &mut dyn FnMut(usize) -> Vec<u8>,
    ) -> Option<Vec<Vec<u8>>>;

    /// Processes the jobs are spread over (1: this one alone).
    fn processes(&self) -> usize;

    /// Whether this process receives the results (and writes the outputs).
    fn writer(&self) -> bool;
}

/// The default: every job in this process, in order.
pub struct Local;

impl Points for Local {
    fn map_bytes(
        &self,
        n: usize,
        _cost: &[f64],
        job: &mut dyn FnMut(usize) -> Vec<u8>,
    ) -> Option<Vec<Vec<u8>>> {
        Some((0..n).map(job).collect())
    }

    fn processes(&self) -> usize {
        1
    }

    fn writer(&self) -> bool {
        true
    }
}

/// Run jobs `0..n` through `points`: every result in job order on the process that writes
/// the outputs, `None` on the others. In one process ([`Points::processes`] = 1) the
/// results are not serialised; over several they travel as postcard (f64 bits exact).
pub fn map<T: Serialize + DeserializeOwned>(
    points: &dyn Points,
    n: usize,
    cost: &[f64],
    mut job: impl FnMut(usize) -> T,
) -> Option<Vec<T>> {
    debug_assert!(cost.is_empty() || cost.len() == n);
    if points.processes() <= 1 {
        return Some((0..n).map(job).collect());
    }
    let bytes = points.map_bytes(n, cost, &mut |i| {
        postcard::to_stdvec(&job(i)).expect("a job's result serialises")
    })?;
    Some(
        bytes
            .iter()
            .map(|b| postcard::from_bytes(b).expect("a job's result deserialises"))
            .collect(),
    )
}

/// The shares of `n` jobs over `ranks` processes: each job (largest estimated `cost`
/// first, ties by index) goes to the process with the least estimated load so far (ties:
/// the lowest); each share in job order. Without costs (`cost` empty) every job counts 1.
/// Deterministic: every process computes the same shares.
pub fn shares(n: usize, cost: &[f64], ranks: usize) -> Vec<Vec<usize>> {
    let ranks = ranks.max(1);
    let c = |i: usize| {
        cost.get(i)
            .copied()
            .filter(|x| x.is_finite())
            .unwrap_or(1.0)
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| c(b).total_cmp(&c(a)).then(a.cmp(&b)));
    let mut load = vec![0.0f64; ranks];
    let mut out = vec![Vec::new(); ranks];
    for i in order {
        let r = (0..ranks)
            .min_by(|&x, &y| load[x].total_cmp(&load[y]).then(x.cmp(&y)))
            .unwrap_or(0);
        load[r] += c(i);
        out[r].push(i);
    }
    for s in &mut out {
        s.sort_unstable();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_cover_every_job_once() {
        for ranks in 1..5 {
            for n in 0..9 {
                let cost: Vec<f64> = (0..n).map(|i| ((i * 7) % 5) as f64 + 0.5).collect();
                let mut all: Vec<usize> = shares(n, &cost, ranks).concat();
                all.sort_unstable();
                assert_eq!(all, (0..n).collect::<Vec<_>>(), "{n} jobs on {ranks}");
            }
        }
    }

    #[test]
    fn shares_balance_by_cost() {
        // One job as costly as the three others: it runs alone.
        let s = shares(4, &[3.0, 1.0, 1.0, 1.0], 2);
        assert_eq!(s, vec![vec![0], vec![1, 2, 3]]);
        // Without costs: alternate.
        assert_eq!(shares(5, &[], 2), vec![vec![0, 2, 4], vec![1, 3]]);
    }

    #[test]
    fn local_map_runs_in_order_without_serialising() {
        let mut seen = Vec::new();
        let r = map(&Local, 3, &[], |i| {
            seen.push(i);
            f64::NAN.to_bits() + i as u64
        });
        assert_eq!(seen, vec![0, 1, 2]);
        assert_eq!(r.unwrap()[2], f64::NAN.to_bits() + 2);
    }

    /// Two "processes" in one: the jobs of each share run, the results travel as bytes.
    struct Split;
    impl Points for Split {
        fn map_bytes(
            &self,
            n: usize,
            cost: &[f64],
            job: &mut dyn FnMut(usize) -> Vec<u8>,
        ) -> Option<Vec<Vec<u8>>> {
            let mut out = vec![Vec::new(); n];
            for share in shares(n, cost, 2).iter().rev() {
                for &i in share {
                    out[i] = job(i);
                }
            }
            Some(out)
        }
        fn processes(&self) -> usize {
            2
        }
        fn writer(&self) -> bool {
            true
        }
    }

    #[test]
    fn results_cross_processes_bit_exact() {
        let v = [f64::NAN, -0.0, 1e-300, f64::INFINITY];
        let r = map(&Split, 4, &[], |i| (v[i], format!("job {i}"))).unwrap();
        for (i, (x, s)) in r.iter().enumerate() {
            assert_eq!(x.to_bits(), v[i].to_bits());
            assert_eq!(s, &format!("job {i}"));
        }
    }
}
