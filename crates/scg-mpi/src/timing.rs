//! The shares of a decomposed run's step time, from the per-rank times of its report.

/// Times (ns) per rank in the gathered report words: compute, ghost exchange, migration,
/// recording (gather) and rebalance.
pub const TIMES: usize = 5;

/// Fields per rank in the gathered report words: the [`TIMES`] times, particles migrated
/// in, particles held at the end.
pub const FIELDS: usize = TIMES + 2;

/// Shares of compute, ghost exchange, migration, recording (gather) and rebalance in the
/// time of all ranks together, from the report words (`FIELDS` per rank); all 0 when
/// nothing was timed. Migration includes the per-step collective and the wait for the
/// slowest rank.
pub fn time_shares(per_rank: &[u64]) -> [f64; TIMES] {
    let mut sum = [0u64; TIMES];
    for c in per_rank.chunks_exact(FIELDS) {
        for (s, t) in sum.iter_mut().zip(c) {
            *s += t;
        }
    }
    let total: u64 = sum.iter().sum();
    if total == 0 {
        return [0.0; TIMES];
    }
    sum.map(|s| s as f64 / total as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_sum_over_ranks() {
        // Rank 0: 6 compute, 1 ghosts, 2 migration; rank 1: 4 compute, 1 ghosts,
        // 4 migration, 2 gather.
        let words = [6, 1, 2, 0, 0, 11, 100, 4, 1, 4, 2, 0, 9, 90];
        let s = time_shares(&words);
        assert_eq!(s, [0.5, 0.1, 0.3, 0.1, 0.0]);
        assert_eq!(time_shares(&[0; 14]), [0.0; 5]);
        assert_eq!(time_shares(&[]), [0.0; 5]);
    }
}
