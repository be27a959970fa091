//! Checkpoints over ranks: every rank's [`Checkpoint`] (its own particles and logs, the
//! clock, feeders and streams every rank shares) merged into one, in the single-rank
//! format ([`merge`]): a decomposed run writes one file that restarts on any number of
//! ranks, one included. On a restart every rank restores the whole checkpoint and keeps
//! the particles of its region; rank 0 keeps the logs and counts, the others start theirs
//! from zero ([`strip_logs`]), so that the sums over the ranks stay the run's.
//!
//! What a rank holds only its share of: the particles (concatenated, in id order),
//! particle-steps, drained and collision counts, the outlet's, patches', impulse walls'
//! and collecting zones' logs, the erosion log (summed, or concatenated and sorted). The largest
//! displacement is the largest over the ranks. Particle contacts: the touching pairs of
//! every rank, each once, keyed by ids ([`merge_contacts`]), for the first neighbour
//! stage after the restart to take up whatever the particles' new rows. Collecting zones
//! that wait are not merged yet: [`refusal`] names them.

use std::collections::BTreeMap;

use glam::DVec3;
use scg_core::checkpoint::Checkpoint;
use scg_core::checkpoint::records::{ContactRecord, ErosionRecord, PairRecord};

/// Why a scene's checkpoints cannot yet be written or read over ranks, if they cannot.
pub fn refusal(scene: &scg_scene::Scene) -> Option<&'static str> {
    if scene.zones.iter().any(|z| z.collects_after > 0.0) {
        return Some(
            "collecting zones that wait (`collects_after`: who waits where is not merged over ranks yet)",
        );
    }
    None
}

/// Sum `b` into `a` element by element (shapes as the scene makes them on every rank).
fn add(a: &mut [Vec<u64>], b: &[Vec<u64>]) {
    for (x, y) in a.iter_mut().zip(b) {
        for (p, q) in x.iter_mut().zip(y) {
            *p += q;
        }
    }
}

/// Append `b`'s lists to `a`'s, list by list.
fn append(a: &mut [Vec<f64>], b: &[Vec<f64>]) {
    for (x, y) in a.iter_mut().zip(b) {
        x.extend_from_slice(y);
    }
}

/// One checkpoint from the ranks' own (rank 0 first): the shared state from rank 0, the
/// particles of all in id order, the counts and logs summed or concatenated (time lists
/// sorted), as a single-rank run's checkpoint holds them.
pub fn merge(mut parts: Vec<Checkpoint>) -> Option<Checkpoint> {
    if parts.is_empty() {
        return None;
    }
    let contacts: Vec<Option<ContactRecord>> =
        parts.iter_mut().map(|c| c.contacts.take()).collect();
    let rest = parts.split_off(1);
    let mut out = parts.pop()?;
    out.contacts = merge_contacts(&contacts);
    let mut largest = f64::from_bits(out.displacement.0);
    for c in rest {
        out.particle_steps += c.particle_steps;
        out.particles.extend(c.particles);
        for k in [0, 2] {
            // drained and collisions; fed counts the feeders every rank runs
            for (a, b) in out.tally[k].iter_mut().zip(&c.tally[k]) {
                *a += b;
            }
        }
        let d = f64::from_bits(c.displacement.0);
        if d > largest {
            largest = d;
        }
        out.displacement.1 |= c.displacement.1;
        if let (Some(a), Some(b)) = (out.outlet.as_mut(), c.outlet.as_ref()) {
            append(&mut a[0], &b[0]);
            append(&mut a[1], &b[1]);
        }
        if let (Some(a), Some(b)) = (out.patches.as_mut(), c.patches.as_ref()) {
            add(&mut a[0], &b[0]);
            add(&mut a[1], &b[1]);
        }
        if let (Some(a), Some(b)) = (out.impulse_walls.as_mut(), c.impulse_walls.as_ref()) {
            add(&mut a[0], &b[0]);
            add(&mut a[1], &b[1]);
        }
        if let (Some(a), Some(b)) = (out.collected.as_mut(), c.collected.as_ref()) {
            for (x, y) in a.iter_mut().zip(b) {
                append(x, y);
            }
        }
        out.collect_inside.extend(c.collect_inside);
        if let (Some(a), Some(b)) = (out.erosion.as_mut(), c.erosion.as_ref()) {
            merge_erosion(a, b);
        }
    }
    out.displacement.0 = largest.to_bits();
    out.particles.sort_by_key(|p| p.id);
    let sort = |v: &mut Vec<f64>| v.sort_by(f64::total_cmp);
    if let Some(o) = out.outlet.as_mut() {
        o.iter_mut().flatten().for_each(sort);
    }
    if let Some(z) = out.collected.as_mut() {
        z.iter_mut().flatten().for_each(sort);
    }
    out.collect_inside.sort_unstable();
    Some(out)
}

/// Rank `b`'s erosion log added into `a`: per face the impacts and sums added (in rank
/// order: a face worn on several ranks sums its impacts in another order than one rank
/// does, equal to rounding), per particle the volumes added (a particle that migrated
/// wore walls on each rank it was on); both in key order, as one rank keeps them.
pub fn merge_erosion(a: &mut ErosionRecord, b: &ErosionRecord) {
    let mut faces: BTreeMap<(u32, u32), (u64, [f64; 5])> = a.0.drain(..).collect();
    for &(k, (n, sums)) in &b.0 {
        let f = faces.entry(k).or_insert((0, [0.0; 5]));
        f.0 += n;
        for (x, y) in f.1.iter_mut().zip(sums) {
            *x += y;
        }
    }
    a.0 = faces.into_iter().collect();
    let mut by: BTreeMap<u32, f64> = a.1.drain(..).collect();
    for &(id, v) in &b.1 {
        *by.entry(id).or_insert(0.0) += v;
    }
    a.1 = by.into_iter().collect();
}

/// The touching pairs of every rank's contact record (rows of its particles and its
/// ghosts) as one record over their ids: each pair once (a pair across a cut is held by
/// the two ranks of its particles, the same history seen from either), oriented from the
/// lower id, the list to be rebuilt (no reference positions). Restored, by one rank or
/// many, it is not the particle table's rows, so the first neighbour stage gathers the
/// rows, rebuilds the list and gives each touching pair its history by the two ids
/// (`ContactState::restore`). `None` without contacts.
pub fn merge_contacts(parts: &[Option<ContactRecord>]) -> Option<ContactRecord> {
    let first = parts.iter().flatten().next()?;
    let mut touching: BTreeMap<(u32, u32), (DVec3, DVec3)> = BTreeMap::new();
    let (mut builds, mut checks) = (0, 0);
    for rec in parts.iter().flatten() {
        builds = builds.max(rec.builds);
        checks += rec.checks;
        for p in rec.pairs.iter().filter(|p| p.touching) {
            let (Some(&a), Some(&b)) = (rec.ids.get(p.i as usize), rec.ids.get(p.j as usize))
            else {
                continue;
            };
            let (key, history, shift) = if a < b {
                ((a, b), p.history, p.shift)
            } else {
                ((b, a), -p.history, -p.shift)
            };
            touching.entry(key).or_insert((history, shift));
        }
    }
    let mut ids: Vec<u32> = touching.keys().flat_map(|&(a, b)| [a, b]).collect();
    ids.sort_unstable();
    ids.dedup();
    let row = |id: u32| ids.binary_search(&id).expect("an id of a pair") as u32;
    let list_pairs: Vec<[u32; 2]> = touching.keys().map(|&(a, b)| [row(a), row(b)]).collect();
    let pairs = (touching.values().zip(&list_pairs))
        .map(|(&(history, shift), &[i, j])| PairRecord {
            i,
            j,
            touching: true,
            shift,
            history,
        })
        .collect();
    Some(ContactRecord {
        list_pairs,
        reference: Vec::new(),
        builds,
        checks,
        drift_bound: 0.0,
        pairs,
        sparse: first.sparse,
        active: touching.len(),
        ids,
    })
}

/// `c` as a rank other than 0 restores it: the counts and logs that are summed over the
/// ranks start from zero there (rank 0 carries the run's so far).
pub fn strip_logs(c: &mut Checkpoint) {
    c.particle_steps = 0;
    for k in [0, 2] {
        c.tally[k].iter_mut().for_each(|n| *n = 0);
    }
    if let Some(o) = c.outlet.as_mut() {
        o.iter_mut().flatten().for_each(Vec::clear);
    }
    for log in [c.patches.as_mut(), c.impulse_walls.as_mut()]
        .into_iter()
        .flatten()
    {
        log.iter_mut()
            .flatten()
            .for_each(|v| v.iter_mut().for_each(|n| *n = 0));
    }
    if let Some(z) = c.collected.as_mut() {
        z.iter_mut().flatten().for_each(Vec::clear);
    }
    c.collect_inside.clear();
    if let Some(e) = c.erosion.as_mut() {
        e.0.clear();
        e.1.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part(ids: &[u32], drained: u64, steps: u64, disp: f64) -> Checkpoint {
        let text = "duration = 1e-3\ndt = 1e-4\n[[groups]]\nname = \"a\"\ndiameter = 1e-3\ndensity = 1000.0\npositions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]\n";
        let sc = scg_scene::parse(text, "<t>", "t", &[]).unwrap();
        let mut sim = sc.build(false);
        let mut c = sim.checkpoint();
        let all = c.particles.clone();
        c.particles = ids.iter().map(|&i| all[i as usize].clone()).collect();
        c.tally[0] = vec![drained];
        c.tally[1] = vec![3];
        c.particle_steps = steps;
        c.displacement = (disp.to_bits(), false);
        c.outlet = Some([vec![vec![drained as f64]], vec![vec![]]]);
        c.patches = Some([vec![vec![drained]], vec![vec![1]]]);
        c
    }

    #[test]
    fn ranks_merge_into_one_checkpoint() {
        let m = merge(vec![part(&[2], 1, 10, 0.5), part(&[0, 1], 2, 20, 0.7)]).unwrap();
        let ids: Vec<u32> = m.particles.iter().map(|p| p.id).collect();
        assert_eq!(ids, [0, 1, 2]);
        assert_eq!(m.tally[0], [3]);
        assert_eq!(m.tally[1], [3], "fed: every rank runs the feeders");
        assert_eq!(m.particle_steps, 30);
        assert_eq!(f64::from_bits(m.displacement.0), 0.7);
        assert_eq!(m.outlet.as_ref().unwrap()[0], [vec![1.0, 2.0]]);
        assert_eq!(m.patches.as_ref().unwrap(), &[vec![vec![3]], vec![vec![2]]]);
        let mut s = m.clone();
        strip_logs(&mut s);
        assert_eq!(s.tally[0], [0]);
        assert_eq!(s.tally[1], [3]);
        assert_eq!(s.particle_steps, 0);
        assert!(s.outlet.as_ref().unwrap()[0][0].is_empty());
        assert_eq!(s.patches.as_ref().unwrap(), &[vec![vec![0]], vec![vec![0]]]);
        assert_eq!(s.particles.len(), 3, "every rank restores every particle");
        assert!(merge(Vec::new()).is_none());
    }

    fn record(ids: &[u32], pairs: &[(u32, u32, bool, f64)]) -> ContactRecord {
        ContactRecord {
            ids: ids.to_vec(),
            list_pairs: pairs.iter().map(|&(i, j, ..)| [i, j]).collect(),
            reference: Vec::new(),
            builds: 3,
            checks: 1,
            drift_bound: 0.0,
            pairs: pairs
                .iter()
                .map(|&(i, j, touching, h)| PairRecord {
                    i,
                    j,
                    touching,
                    shift: DVec3::ZERO,
                    history: DVec3::new(h, 0.0, 0.0),
                })
                .collect(),
            sparse: true,
            active: 1,
        }
    }

    #[test]
    fn erosion_logs_add_by_face_and_particle() {
        let mut a: ErosionRecord = (
            vec![
                ((u32::MAX, 4), (2, [1.0, 2.0, 0.0, 0.0, 0.0])),
                ((0, 1), (1, [0.5; 5])),
            ],
            vec![(3, 1e-9), (8, 0.5)],
        );
        let b: ErosionRecord = (
            vec![((0, 0), (1, [1.0; 5])), ((u32::MAX, 4), (3, [1.0; 5]))],
            vec![(8, 0.25), (5, 4e-9)],
        );
        merge_erosion(&mut a, &b);
        assert_eq!(
            a.0,
            vec![
                ((0, 0), (1, [1.0; 5])),
                ((0, 1), (1, [0.5; 5])),
                ((u32::MAX, 4), (5, [2.0, 3.0, 1.0, 1.0, 1.0])),
            ]
        );
        assert_eq!(a.1, vec![(3, 1e-9), (5, 4e-9), (8, 0.75)]);
        let mut c = part(&[0], 0, 0, 0.0);
        c.erosion = Some(b);
        strip_logs(&mut c);
        assert_eq!(c.erosion, Some((vec![], vec![])));
    }

    #[test]
    fn touching_pairs_merge_once_by_ids() {
        // Rank 0 holds 7 and 9 with ghost 4; rank 1 holds 4 with ghost 9. The pair
        // (9, 4) crosses the cut: both hold it, seen from 9 on rank 0 and from 4 on
        // rank 1 (opposite histories). (7, 9) is listed but not touching.
        let a = record(&[7, 9, 4], &[(0, 1, false, 5.0), (1, 2, true, 2.0)]);
        let b = record(&[4, 9], &[(0, 1, true, -2.0)]);
        let m = merge_contacts(&[Some(a), None, Some(b)]).unwrap();
        assert_eq!(m.ids, [4, 9]);
        assert_eq!(m.list_pairs, [[0, 1]]);
        assert_eq!(m.pairs.len(), 1);
        assert_eq!(m.pairs[0].history.x, -2.0, "seen from the lower id, 4");
        assert!(m.pairs[0].touching);
        assert!(m.reference.is_empty(), "the list is rebuilt");
        assert_eq!((m.builds, m.checks), (3, 2));
        assert!(merge_contacts(&[None, None]).is_none());
    }
}
