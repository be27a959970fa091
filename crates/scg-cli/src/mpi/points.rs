//! The independent points of `scg cost` and `scg study` spread over the ranks: each rank
//! runs its share ([`crate::points::shares`], balanced by estimated cost) one after
//! another, and rank 0 gathers every result ([`scg_mpi::points::pack`]) and writes the
//! outputs.

use scg_mpi::comm::Comm;
use scg_mpi::points::{pack, unpack};

use crate::points::{Points, shares};

/// [`Points`] over the ranks of `comm`.
pub struct RankPoints<'a> {
    /// The ranks.
    pub comm: &'a Comm,
}

impl Points for RankPoints<'_> {
    fn map_bytes(
        &self,
        n: usize,
        cost: &[f64],
        job: &mut dyn FnMut(usize) -> Vec<u8>,
    ) -> Option<Vec<Vec<u8>>> {
        let share = &shares(n, cost, self.comm.size())[self.comm.rank()];
        let mine: Vec<(usize, Vec<u8>)> = share.iter().map(|&i| (i, job(i))).collect();
        let parts = self.comm.gather_bytes(&pack(&mine))?;
        Some(unpack(n, &parts).expect("every point's result gathered once"))
    }

    fn processes(&self) -> usize {
        self.comm.size()
    }

    fn writer(&self) -> bool {
        self.comm.rank() == 0
    }
}
