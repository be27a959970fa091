//! Ghost particles: particle contacts over the ranks' regions (issues 19 and 39).
//!
//! # Design
//!
//! LAMMPS's pattern. At a *rebuild* (decided collectively by the driver, `driver.rs`:
//! some rank's particle moved more than half the skin since its list was built, or some
//! rank's particle table changed), after the migration, every rank sends each *peer* (a
//! rank whose region, slab or box ([`crate::decomp::regions`]), lies within
//! 2·r_max + skin of its own, [`peers`]; empty messages too) a whole copy of its
//! particles that lie within the *halo* h = r + r_max + skin of that peer's region (r
//! its radius, r_max the largest radius of the scene's groups after coarse graining,
//! [`largest_radius`]; the distance to the region's box): id, group, radius, mass, x, v,
//! ω, what the pair kernel reads (`Halo::regather`, feature `mpi`). The receiver
//! appends them, peer by peer, after its table's rows ([`ContactState::set_ghosts`]),
//! and its list is rebuilt. Between rebuilds the sets are fixed: each step, before the
//! forces, every rank sends the same peers the x, v, ω of the same particles, in the same
//! order, 72 bytes each, and they go straight into the ghost rows (`Halo::forward`);
//! the list is not rebuilt. A pair closer than r_i + r_j + skin at the rebuild has each
//! particle closer than its h to the other's region, so every pair the one-rank list
//! would hold between a particle of this region and one of another is listed,
//! local–ghost; and as long as no particle moved half the skin, no pair outside the list
//! can touch. A particle strays up to half the skin beyond its region meanwhile (it
//! migrates at the next rebuild); its ghost copies follow it.
//!
//! The contact stage lists the local–local and local–ghost pairs (never ghost–ghost),
//! computes them and kicks its own particles only; ghosts are not entities, so they are
//! never integrated, recorded, counted, drained or fed. A pair across a cut is computed
//! by both of its ranks (no force is sent back), and a contact started across it is
//! counted by each rank for its own particle's group, so the summed collision counts are
//! one rank's.
//!
//! In a periodic box the regions tile [0, P) along each periodic axis and meet across
//! the box's sides: a particle within its halo of a region across a side (the nearest
//! image of the region's box) is sent to it at its own, unwrapped position (the pair list
//! and kernel take the minimum image).
//!
//! A local–ghost pair's tangential history is carried over list rebuilds by the two ids
//! like any other; each of the two ranks keeps its own copy of it, both computed from the
//! same inputs. When a particle migrates, the histories of its touching pairs travel with
//! it in the migration message ([`Migrants`]) and the next rebuild on the new rank takes
//! them up ([`ContactState::receive_histories`]) for the pairs it did not carry already;
//! its wall history, ω and mesh cell are in its [`ParticleRecord`].
//!
//! # Bits
//!
//! A particle's contact force is summed over its pairs in the order of the force slots:
//! pairs sorted by *row* (table order, which depends on the history of spawns and
//! despawns on the rank), cut into slots by pair count. On N ranks a particle's rows,
//! its pairs' orientation (i < j by row) and the slot cuts differ from one rank's, so the
//! sum may be taken in another order and the last bits differ where a particle has
//! several contacts at once; granular contacts amplify them. Summing by id would change
//! every single-rank result (the golden recordings), so it is not done: dense beds agree
//! with one rank statistically (`tests/mpi_ranks.rs`), dilute flows whose contacts are
//! binary (the classifier) and drag-only runs bit for bit.
//!
//! # Cost
//!
//! Per step one point-to-point message each way with each peer (latency, ≈ 18 ns per
//! ghost on this machine); at rebuilds the migration and the whole sets. The numbers
//! and the model: docs/scaling.md.
//!
//! [`ContactState::set_ghosts`]: scg_core::stages::contacts::ContactState::set_ghosts
//! [`ContactState::receive_histories`]: scg_core::stages::contacts::ContactState::receive_histories
//! [`ParticleRecord`]: scg_core::checkpoint::ParticleRecord

use glam::DVec3;
use scg_core::checkpoint::ParticleRecord;
use scg_core::stages::contacts::ghosts::PairHistory;
use serde::{Deserialize, Serialize};

use crate::decomp::Regions;

/// What migrates from one rank to another: the particles with their whole state, and the
/// tangential histories of their touching pairs (contacts), keyed by ids.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Migrants {
    /// The particles.
    pub particles: Vec<ParticleRecord>,
    /// Their touching pairs' histories, seen from the migrating particle.
    pub pairs: Vec<PairHistory>,
}

/// Halo width of a particle of radius `r`, m: within this distance of another rank's
/// region it may come within the skin of one of that rank's particles
/// (radius ≤ `r_max`), so the neighbour list there must hold it.
pub fn reach(r: f64, r_max: f64, skin: f64) -> f64 {
    r + r_max + skin
}

/// The largest radius a particle of `scene` has, m: every particle, initial or fed, has
/// its group's coarse-grained diameter (the bound the scene's default skin uses too), so
/// every rank knows it without asking the others.
pub fn largest_radius(scene: &scg_scene::Scene) -> f64 {
    scene
        .groups
        .iter()
        .map(|g| {
            0.5 * scg_core::physics::scaling::coarse_grain(
                g.law,
                g.alpha,
                g.max_diameter(),
                g.density,
            )
            .diameter
        })
        .fold(0.0, f64::max)
}

/// [`Regions::within`] into `out` (cleared first): the ranks a particle of `me` at `x`
/// with halo `halo` is a ghost on. A region thinner than the halo lets a particle be a
/// ghost on several ranks. A non-finite position goes nowhere (rank 0's guard reports
/// the particle).
pub fn ghost_targets(regions: &Regions, me: usize, x: DVec3, halo: f64, out: &mut Vec<usize>) {
    out.clear();
    out.extend(regions.within(me, x, halo));
}

/// The ranks whose region lies within `reach` of region `me` (other than `me`),
/// ascending: those that may send this rank ghosts, and receive its own, when no particle
/// reaches farther than `reach` (2·r_max + skin). Symmetric: q is among r's exactly when
/// r is among q's.
pub fn peers(regions: &Regions, me: usize, reach: f64) -> Vec<usize> {
    let r2 = reach * reach;
    (0..regions.ranks())
        .filter(|&q| q != me && regions.gap_squared(me, q) <= r2)
        .collect()
}

#[cfg(feature = "mpi")]
pub use exchange::Halo;

#[cfg(feature = "mpi")]
mod exchange {
    use std::collections::HashMap;

    use scg_core::Simulation;
    use scg_core::checkpoint::ParticleRecord;
    use scg_core::stages::contacts::ContactState;
    use scg_core::stages::contacts::ghosts::{
        Ghosts, STATE_BYTES, TableStates, table_rows_indexed_where,
    };

    use super::{Migrants, ghost_targets, peers, reach};
    use crate::comm::{Comm, decode, encode};
    use crate::decomp::Owners;

    /// The ghosts of a run with contacts: the set given at the last rebuild and the
    /// rows forwarded since, and what it did.
    #[derive(Default)]
    pub struct Halo {
        /// The largest particle radius of the scene, m ([`super::largest_radius`]).
        pub r_max: f64,
        /// Ghost sets given so far (one per rebuild).
        pub exchanges: u64,
        /// Steps whose ghost states were forwarded.
        pub forwards: u64,
        /// Ghost rows held, summed over the steps.
        pub received: u64,
        /// The peers of the current set (ascending).
        with: Vec<usize>,
        /// Per peer: the table rows whose states go to it, in the order of its ghosts.
        send: Vec<Vec<u32>>,
        /// Per peer: how many of this rank's ghost rows it owns (in peer order).
        recv: Vec<usize>,
        /// Every rank's peers are all the other ranks (decided with the set).
        all_peers: bool,
        /// The reader of the forwarded states (made with the first set).
        states: Option<TableStates>,
    }

    /// What a forward message starts with: the sender's flags (a little-endian u64).
    const HEADER: usize = 8;

    impl Halo {
        /// The ghosts of a run of `scene`.
        pub fn new(scene: &scg_scene::Scene) -> Self {
            Halo {
                r_max: super::largest_radius(scene),
                ..Default::default()
            }
        }

        /// How far a ghost may reach into `sim`'s other regions, m: 2·r_max + skin (the
        /// largest halo, [`reach`]); `None` without particle contacts.
        pub fn reach_in(&self, sim: &Simulation) -> Option<f64> {
            let skin = sim.world.get_resource::<ContactState>()?.list.skin;
            Some(reach(self.r_max, self.r_max, skin))
        }

        /// True while a ghost set is held (contacts, regions, another rank within reach).
        pub fn active(&self) -> bool {
            !self.with.is_empty()
        }

        /// Whether every rank's peers are all the other ranks (the same answer on every
        /// rank), so that a forward exchange reaches everybody and can carry the step's
        /// flags in place of a collective.
        pub fn reaches_all(&self) -> bool {
            self.all_peers
        }

        /// Give every rank a new ghost set (a collective, at a rebuild: after the
        /// migration, with the regions as they now are). Each rank sends each peer its
        /// particles within their reach of the peer's region, whole (id, group, radius,
        /// mass, x, v, ω), and remembers their table rows for [`Halo::forward`]; the
        /// ghost rows come in peer order, each peer's in its table order. Nothing when
        /// the scene has no contacts or the owners are not regions.
        pub fn regather(&mut self, comm: &Comm, sim: &mut Simulation, owners: &Owners) {
            self.with.clear();
            self.send.clear();
            self.recv.clear();
            self.all_peers = false;
            let Owners::Regions(regions) = owners else {
                return;
            };
            let Some(skin) = sim
                .world
                .get_resource::<ContactState>()
                .map(|c| c.list.skin)
            else {
                return;
            };
            let me = comm.rank();
            let with = peers(regions, me, reach(self.r_max, self.r_max, skin));
            let full = u64::from(with.len() + 1 == comm.size());
            self.all_peers = comm.all_gather_u64(&[full]).iter().all(|&f| f == 1);
            if with.is_empty() {
                return;
            }
            let r_max = self.r_max;
            let (rows, g) = table_rows_indexed_where(&mut sim.world, |x, r| {
                regions
                    .within(me, x, reach(r, r_max, skin))
                    .next()
                    .is_some()
            });
            let mut to = Vec::new();
            let mut out = vec![Ghosts::default(); with.len()];
            let mut send = vec![Vec::new(); with.len()];
            for (k, &row) in rows.iter().enumerate() {
                let halo = reach(g.radius[k], self.r_max, skin);
                ghost_targets(regions, me, g.pos[k], halo, &mut to);
                for &q in &to {
                    let p = with.binary_search(&q).expect("a ghost goes to a peer");
                    out[p].push_row(&g, k);
                    send[p].push(row);
                }
            }
            let msgs: Vec<Vec<u8>> = out.iter().map(encode).collect();
            let mut ghosts = Ghosts::default();
            let mut recv = Vec::with_capacity(with.len());
            for part in comm.exchange_with(&with, &msgs) {
                let got = decode::<Ghosts>(&part);
                recv.push(got.len());
                ghosts.extend(&got);
            }
            self.exchanges += 1;
            self.received += ghosts.len() as u64;
            (self.with, self.send, self.recv) = (with, send, recv);
            if self.states.is_none() {
                self.states = Some(TableStates::new(&mut sim.world));
            }
            sim.world.resource_mut::<ContactState>().set_ghosts(ghosts);
        }

        /// Forward this rank's particles' states to their ghosts on the peers and take in
        /// the ghosts' (point to point, along the lists of the last [`Halo::regather`]),
        /// each message led by the sender's `flags`; returns the peers' flags or-ed with
        /// these. When `flags` has `stale` set this rank's table changed since the
        /// rebuild, so it sends its flags alone; when any peer's has, nothing is taken
        /// in (a rebuild follows).
        pub fn forward(
            &mut self,
            comm: &Comm,
            sim: &mut Simulation,
            flags: u64,
            stale: u64,
        ) -> u64 {
            if !self.active() {
                return flags;
            }
            let states = self
                .states
                .as_mut()
                .expect("a states reader with the ghost set");
            let msgs: Vec<Vec<u8>> = self
                .send
                .iter()
                .map(|rows| {
                    let mut bytes = Vec::with_capacity(HEADER + STATE_BYTES * rows.len());
                    bytes.extend_from_slice(&flags.to_le_bytes());
                    if flags & stale == 0 {
                        states.append(&sim.world, rows, &mut bytes);
                    }
                    bytes
                })
                .collect();
            let got = comm.exchange_with(&self.with, &msgs);
            let mut any = flags;
            for part in &got {
                any |= u64::from_le_bytes(part[..HEADER].try_into().expect("a flag word"));
            }
            if any & stale != 0 {
                return any;
            }
            let mut st = sim.world.resource_mut::<ContactState>();
            let mut at = 0;
            for (part, &count) in got.iter().zip(&self.recv) {
                assert!(
                    part.len() == HEADER + STATE_BYTES * count,
                    "a peer forwarded {} bytes of states for {count} ghosts",
                    part.len() - HEADER
                );
                at = st.put_ghost_states(at, &part[HEADER..]);
            }
            assert_eq!(
                at,
                st.ghosts().len(),
                "forwarded states for another ghost set"
            );
            self.forwards += 1;
            self.received += at as u64;
            any
        }
    }

    /// The migration messages: `out[r]` to rank r with the histories of its particles'
    /// touching pairs (the last force stage's, still in [`ContactState`]).
    pub(crate) fn migrants(sim: &Simulation, out: &[Vec<ParticleRecord>]) -> Vec<Migrants> {
        let mut msgs: Vec<Migrants> = out
            .iter()
            .map(|p| Migrants {
                particles: p.clone(),
                pairs: Vec::new(),
            })
            .collect();
        if let Some(st) = sim.world.get_resource::<ContactState>() {
            let dest: HashMap<u32, usize> = out
                .iter()
                .enumerate()
                .flat_map(|(r, ps)| ps.iter().map(move |p| (p.id, r)))
                .collect();
            if !dest.is_empty() {
                for h in st.histories_of(|id| dest.contains_key(&id)) {
                    msgs[dest[&h.a]].pairs.push(h);
                }
            }
        }
        msgs
    }

    /// Take in what arrived: the particles, and their pairs' histories.
    pub(crate) fn arrive(sim: &mut Simulation, m: Migrants) -> Result<usize, String> {
        sim.insert_particles(&m.particles)?;
        if !m.pairs.is_empty()
            && let Some(mut st) = sim.world.get_resource_mut::<ContactState>()
        {
            st.receive_histories(m.pairs);
        }
        Ok(m.particles.len())
    }
}

#[cfg(feature = "mpi")]
pub(crate) use exchange::{arrive, migrants};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decomp::Shape;

    fn on_x(x: f64) -> DVec3 {
        DVec3::new(x, 0.3, -0.2)
    }

    #[test]
    fn ghosts_go_to_the_regions_within_the_halo() {
        // Slabs (-inf, 0), [0, 1), [1, 1.5), [1.5, inf) along x.
        let s = Regions::slabs(0, vec![0.0, 1.0, 1.5], [None; 3]);
        let mut to = Vec::new();
        let mut at = |me, x| {
            ghost_targets(&s, me, on_x(x), 0.3, &mut to);
            to.clone()
        };
        assert_eq!(at(1, 0.5), Vec::<usize>::new(), "the middle of a wide slab");
        assert_eq!(at(1, 0.2), vec![0]);
        assert_eq!(at(0, -0.3), vec![1], "at the halo's edge");
        assert_eq!(at(0, -0.31), Vec::<usize>::new());
        assert_eq!(at(1, 0.9), vec![2], "slab 2 is within 0.1");
        // Slab 2 is 0.5 wide: from its middle both neighbours are within the halo.
        assert_eq!(at(2, 1.1), vec![1]);
        assert_eq!(at(2, 1.25), vec![1, 3]);
        assert_eq!(at(3, 9.0), Vec::<usize>::new());
        assert_eq!(at(3, 1.7), vec![2]);
        assert_eq!(at(3, f64::NAN), Vec::<usize>::new());
        // A halo wider than a slab reaches past it.
        ghost_targets(&s, 1, on_x(0.6), 1.0, &mut to);
        assert_eq!(to, vec![0, 2, 3]);
        assert_eq!(reach(1e-3, 2e-3, 5e-4), 3.5e-3);
        // Boxes: a particle near a corner is a ghost of the diagonal box only within the
        // halo of its corner (Euclidean distance), not of its faces' extensions.
        let xs: Vec<DVec3> = (0..16)
            .map(|k| DVec3::new((k % 4) as f64, (k / 4) as f64, 0.0))
            .collect();
        let r = Regions::balanced(Shape::Bisection, 4, &xs, [None; 3], 0.5);
        let me = r.owner(DVec3::new(1.2, 1.2, 0.0));
        let diagonal = r.owner(DVec3::new(2.0, 2.0, 0.0));
        ghost_targets(&r, me, DVec3::new(1.2, 1.2, 0.0), 0.5, &mut to);
        assert_eq!(to.len(), 3, "two faces and the corner: {to:?}");
        assert!(to.contains(&diagonal));
        ghost_targets(&r, me, DVec3::new(1.1, 1.1, 0.0), 0.5, &mut to);
        assert!(!to.contains(&diagonal), "0.57 from the corner: {to:?}");
        assert_eq!(to.len(), 2);
    }

    #[test]
    fn peers_are_the_regions_within_reach_and_symmetric() {
        let s = Regions::slabs(2, vec![0.0, 1.0, 1.2, 3.0], [None; 3]);
        assert_eq!(peers(&s, 0, 0.1), vec![1]);
        assert_eq!(peers(&s, 1, 0.1), vec![0, 2]);
        // Slab 2 is 0.2 thick: from slab 1, slab 3 is 0.2 away.
        assert_eq!(peers(&s, 1, 0.2), vec![0, 2, 3]);
        assert_eq!(peers(&s, 4, 0.2), vec![3]);
        assert_eq!(peers(&s, 4, 10.0), vec![0, 1, 2, 3]);
        let xs: Vec<DVec3> = (0..512)
            .map(|k| DVec3::new((k % 8) as f64, (k / 8 % 8) as f64, (k / 64) as f64))
            .collect();
        let rcb = Regions::balanced(Shape::Bisection, 7, &xs, [Some(8.0), None, None], 1.0);
        for r in [s, rcb] {
            for reach in [0.0, 0.1, 0.2, 1.1, 5.0] {
                for a in 0..r.ranks() {
                    for b in peers(&r, a, reach) {
                        assert!(peers(&r, b, reach).contains(&a), "{a} {b} {reach}");
                    }
                }
            }
        }
        assert!(peers(&Regions::new(0, 1), 0, 1.0).is_empty());
    }

    /// Every pair closer than r_i + r_j + skin across two regions has each particle
    /// within the halo of the other's region (a brute-force check over random
    /// particles), for slabs and bisection boxes, in an open domain and in a box periodic
    /// along every axis (positions spread over three boxes, the minimum image for the
    /// distance); the ranks a particle goes to are its region's peers.
    #[test]
    fn every_cross_region_pair_in_reach_is_seen() {
        let mut state = 12345u64;
        let mut rnd = || {
            state = crate::decomp::splitmix64(state);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (skin, r_max) = (0.01, 0.04);
        let halo = reach(r_max, r_max, skin);
        let lengths = DVec3::new(0.6, 1.2, 0.5);
        for periodic in [false, true] {
            let spread = if periodic { 3.0 } else { 1.0 };
            let ps: Vec<(DVec3, f64)> = (0..1500)
                .map(|_| {
                    let u = DVec3::new(rnd(), rnd(), rnd()) * spread - (spread - 1.0) / 2.0;
                    (u * lengths, r_max * (0.3 + 0.7 * rnd()))
                })
                .collect();
            let xs: Vec<DVec3> = ps.iter().map(|p| p.0).collect();
            let period = if periodic {
                [Some(lengths.x), Some(lengths.y), Some(lengths.z)]
            } else {
                [None; 3]
            };
            let sep = |a: DVec3, b: DVec3| {
                let mut d = b - a;
                if periodic {
                    d -= lengths * (d / lengths).round();
                }
                d.length()
            };
            for (shape, ranks) in [(Shape::Slabs(1), 5), (Shape::Bisection, 6)] {
                let s = Regions::balanced(shape, ranks, &xs, period, halo);
                let mut to = Vec::new();
                let mut crossing = 0;
                for (a, &(xa, ra)) in ps.iter().enumerate() {
                    for &(xb, rb) in &ps[a + 1..] {
                        let (oa, ob) = (s.owner(xa), s.owner(xb));
                        if oa == ob || sep(xa, xb) >= ra + rb + skin {
                            continue;
                        }
                        crossing += 1;
                        ghost_targets(&s, oa, xa, reach(ra, r_max, skin), &mut to);
                        assert!(to.contains(&ob), "{xa} of {oa} is not a ghost on {ob}");
                        assert!(to.iter().all(|q| peers(&s, oa, halo).contains(q)));
                        ghost_targets(&s, ob, xb, reach(rb, r_max, skin), &mut to);
                        assert!(to.contains(&oa), "{xb} of {ob} is not a ghost on {oa}");
                    }
                }
                assert!(
                    crossing > 50,
                    "{crossing} pairs across regions: the test shows nothing"
                );
            }
        }
    }

    #[test]
    fn periodic_slabs_reach_round_the_box() {
        // [0, 0.1) [0.1, 0.5) [0.5, 0.9) [0.9, 1): the first and last touch across 0 ≡ 1.
        let s = Regions::slabs(0, vec![0.1, 0.5, 0.9], [Some(1.0), None, None]);
        assert_eq!(peers(&s, 0, 0.05), vec![1, 3]);
        assert_eq!(peers(&s, 3, 0.05), vec![0, 2]);
        // From slab 1, slab 3 is 0.4 away directly and 0.1 round the box.
        assert_eq!(peers(&s, 1, 0.05), vec![0, 2]);
        assert_eq!(peers(&s, 1, 0.1), vec![0, 2, 3]);
        let mut to = Vec::new();
        ghost_targets(&s, 0, on_x(0.02), 0.05, &mut to);
        assert_eq!(to, vec![3], "near 0: a ghost at the top of the box");
        ghost_targets(&s, 0, on_x(5.02), 0.05, &mut to);
        assert_eq!(to, vec![3], "five boxes up, the same");
        ghost_targets(&s, 3, on_x(0.97), 0.05, &mut to);
        assert_eq!(to, vec![0]);
        ghost_targets(&s, 1, on_x(0.3), 0.05, &mut to);
        assert!(to.is_empty());
    }
}
