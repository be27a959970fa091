//! The few collectives a decomposed run needs, on byte buffers, over MPI's world
//! communicator.

use mpi::Count;
use mpi::datatype::{Partition, PartitionMut};
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use serde::{Deserialize, Serialize};

/// The ranks of a run.
pub struct Comm {
    world: SimpleCommunicator,
}

fn displacements(counts: &[Count]) -> Vec<Count> {
    counts
        .iter()
        .scan(0, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect()
}

fn split(buf: &[u8], counts: &[Count]) -> Vec<Vec<u8>> {
    let mut at = 0;
    counts
        .iter()
        .map(|&c| {
            let part = buf[at..at + c as usize].to_vec();
            at += c as usize;
            part
        })
        .collect()
}

fn count(len: usize) -> Count {
    Count::try_from(len).expect("an MPI message over 2 GiB")
}

impl Comm {
    /// The world communicator.
    pub fn new(world: SimpleCommunicator) -> Self {
        Comm { world }
    }

    /// This rank.
    pub fn rank(&self) -> usize {
        self.world.rank() as usize
    }

    /// Number of ranks.
    pub fn size(&self) -> usize {
        self.world.size() as usize
    }

    /// Every rank's `words`, concatenated in rank order, on every rank (all ranks pass
    /// the same length).
    pub fn all_gather_u64(&self, words: &[u64]) -> Vec<u64> {
        let mut out = vec![0u64; words.len() * self.size()];
        self.world.all_gather_into(words, &mut out[..]);
        out
    }

    /// Every rank's `bytes`, in rank order, on every rank.
    pub fn all_gather_bytes(&self, bytes: &[u8]) -> Vec<Vec<u8>> {
        let n = count(bytes.len());
        let mut counts = vec![0 as Count; self.size()];
        self.world.all_gather_into(&n, &mut counts[..]);
        let displs = displacements(&counts);
        let total: usize = counts.iter().map(|&c| c as usize).sum();
        let mut buf = vec![0u8; total];
        {
            let mut part = PartitionMut::new(&mut buf[..], &counts[..], &displs[..]);
            self.world.all_gather_varcount_into(bytes, &mut part);
        }
        split(&buf, &counts)
    }

    /// `send[r]` goes to rank r; returns what each rank sent here, in rank order.
    pub fn all_to_all_bytes(&self, send: &[Vec<u8>]) -> Vec<Vec<u8>> {
        assert_eq!(send.len(), self.size());
        let send_counts: Vec<Count> = send.iter().map(|b| count(b.len())).collect();
        let mut recv_counts = vec![0 as Count; self.size()];
        self.world
            .all_to_all_into(&send_counts[..], &mut recv_counts[..]);
        let flat: Vec<u8> = send.concat();
        let send_displs = displacements(&send_counts);
        let recv_displs = displacements(&recv_counts);
        let total: usize = recv_counts.iter().map(|&c| c as usize).sum();
        let mut buf = vec![0u8; total];
        {
            let s = Partition::new(&flat[..], &send_counts[..], &send_displs[..]);
            let mut r = PartitionMut::new(&mut buf[..], &recv_counts[..], &recv_displs[..]);
            self.world.all_to_all_varcount_into(&s, &mut r);
        }
        split(&buf, &recv_counts)
    }

    /// `send[k]` goes to rank `peers[k]`, and one message comes from each of `peers`,
    /// returned in the order of `peers`: point to point, no collective. The peers must be
    /// symmetric (q among this rank's peers exactly when this rank is among q's), and
    /// every rank must call this the same number of times (messages between two ranks
    /// arrive in the order they were sent).
    pub fn exchange_with(&self, peers: &[usize], send: &[Vec<u8>]) -> Vec<Vec<u8>> {
        assert_eq!(peers.len(), send.len());
        // The tag of these exchanges (the collectives never match it).
        const TAG: mpi::Tag = 19;
        let at = |q: usize| {
            self.world
                .process_at_rank(mpi::Rank::try_from(q).expect("a rank"))
        };
        mpi::request::scope(|scope| {
            let sent: Vec<_> = peers
                .iter()
                .zip(send)
                .map(|(&q, b)| at(q).immediate_send_with_tag(scope, &b[..], TAG))
                .collect();
            let got = peers
                .iter()
                .map(|&q| at(q).receive_vec_with_tag::<u8>(TAG).0)
                .collect();
            for r in sent {
                r.wait();
            }
            got
        })
    }

    /// Every rank's `bytes`, in rank order, on rank 0 (`None` on the others).
    pub fn gather_bytes(&self, bytes: &[u8]) -> Option<Vec<Vec<u8>>> {
        let root = self.world.process_at_rank(0);
        let n = count(bytes.len());
        if self.rank() == 0 {
            let mut counts = vec![0 as Count; self.size()];
            root.gather_into_root(&n, &mut counts[..]);
            let displs = displacements(&counts);
            let total: usize = counts.iter().map(|&c| c as usize).sum();
            let mut buf = vec![0u8; total];
            {
                let mut part = PartitionMut::new(&mut buf[..], &counts[..], &displs[..]);
                root.gather_varcount_into_root(bytes, &mut part);
            }
            Some(split(&buf, &counts))
        } else {
            root.gather_into(&n);
            root.gather_varcount_into(bytes);
            None
        }
    }
}

/// `v` as a message to another rank (postcard).
pub(crate) fn encode<T: Serialize>(v: &T) -> Vec<u8> {
    postcard::to_stdvec(v).expect("serialising to memory")
}

/// A message of another rank ([`encode`]).
pub(crate) fn decode<'a, T: Deserialize<'a>>(b: &'a [u8]) -> T {
    postcard::from_bytes(b).expect("a message of another rank of the same build")
}
