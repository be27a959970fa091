//! The shares of a decomposed run's step time, from the per-rank times of its report.

/// Fields per rank in the gathered report words: compute, migration, recording (gather)
/// and rebalance times (ns), particles migrated in, particles held at the end.
pub const FIELDS: usize = 6;

/// Shares of compute, migration, recording (gather) and rebalance in the time of all
/// ranks together, from the report words (`FIELDS` per rank); all 0 when nothing was
/// timed. Migration includes the per-step collective and the wait for the slowest rank.
pub fn time_shares(per_rank: &[u64]) -> [f64; 4] {
    let mut sum = [0u64; 4];
    for c in per_rank.chunks_exact(FIELDS) {
        for (s, t) in sum.iter_mut().zip(c) {
            *s += t;
        }
    }
    let total: u64 = sum.iter().sum();
    if total == 0 {
        return [0.0; 4];
    }
    sum.map(|s| s as f64 / total as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_sum_over_ranks() {
        // Rank 0: 6 compute, 2 migration; rank 1: 4 compute, 6 migration, 2 gather.
        let words = [6, 2, 0, 0, 11, 100, 4, 6, 2, 0, 9, 90];
        let s = time_shares(&words);
        assert_eq!(s, [0.5, 0.4, 0.1, 0.0]);
        assert_eq!(time_shares(&[0; 12]), [0.0; 4]);
        assert_eq!(time_shares(&[]), [0.0; 4]);
    }
}
