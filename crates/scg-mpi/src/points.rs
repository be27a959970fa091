//! The framing of the results of independent points (`scg cost`, `scg study`) gathered
//! from the ranks ([`pack`], [`unpack`]): pure, tested without MPI (the command line's
//! `RankPoints` uses it).

/// One rank's results as one buffer: per job, its index and length (u64, little-endian)
/// and its bytes.
pub fn pack(results: &[(usize, Vec<u8>)]) -> Vec<u8> {
    let mut buf = Vec::new();
    for (i, r) in results {
        buf.extend_from_slice(&(*i as u64).to_le_bytes());
        buf.extend_from_slice(&(r.len() as u64).to_le_bytes());
        buf.extend_from_slice(r);
    }
    buf
}

/// The results of [`pack`]ed buffers put in job order: `None` when a buffer is cut short,
/// a job is missing, out of range or given twice.
pub fn unpack(n: usize, parts: &[Vec<u8>]) -> Option<Vec<Vec<u8>>> {
    let mut out: Vec<Option<Vec<u8>>> = vec![None; n];
    for p in parts {
        let mut at = 0;
        let word = |at: usize| -> Option<usize> {
            let b: [u8; 8] = p.get(at..at + 8)?.try_into().ok()?;
            usize::try_from(u64::from_le_bytes(b)).ok()
        };
        while at < p.len() {
            let (i, len) = (word(at)?, word(at + 8)?);
            let bytes = p.get(at + 16..at + 16 + len)?;
            let slot = out.get_mut(i)?;
            if slot.replace(bytes.to_vec()).is_some() {
                return None;
            }
            at += 16 + len;
        }
    }
    out.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_results_come_back_in_job_order() {
        let r0 = vec![(0, vec![1u8, 2]), (2, Vec::new())];
        let r1 = vec![(1, vec![7u8; 20]), (3, vec![9u8])];
        let all = unpack(4, &[pack(&r0), pack(&r1)]).unwrap();
        assert_eq!(all, vec![vec![1, 2], vec![7; 20], Vec::new(), vec![9]]);
    }

    #[test]
    fn missing_duplicated_or_cut_results_are_refused() {
        let r0 = pack(&[(0, vec![1u8])]);
        assert!(
            unpack(2, std::slice::from_ref(&r0)).is_none(),
            "job 1 missing"
        );
        assert!(
            unpack(1, &[r0.clone(), r0.clone()]).is_none(),
            "job 0 twice"
        );
        assert!(
            unpack(1, &[r0[..r0.len() - 1].to_vec()]).is_none(),
            "cut short"
        );
        assert!(unpack(0, &[r0]).is_none(), "out of range");
        assert_eq!(unpack(0, &[]), Some(Vec::new()));
    }
}
