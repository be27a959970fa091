//! Contact kicks: the slots' sums applied to the particles (first system of the
//! integration stage).

use bevy_ecs::prelude::*;
use bytemuck::TransparentWrapper;
use glam::DVec3;

use super::ContactState;
use super::slots::{Slot, slot_sum};
use crate::components::*;
use crate::stages::table::{bypass, columns_mut};

/// Apply the contact forces and torques of this step as kicks (first system of the
/// integration stage): v += F·dt/m, ω += T·dt/I with I = 0.4·m·r², F and T the slots'
/// sums. After a step with few contacts only the particles touched are visited; after a
/// dense one every particle, in parallel chunks. Equivalent to adding them to the force
/// the integrator kicks with, since every force of the step was computed from the state
/// before any kick.
pub fn apply_contact_kicks(
    mut state: ResMut<ContactState>,
    mut q: Query<(&ParticleId, &mut Velocity, &mut AngularVelocity)>,
) {
    let st = &mut *state;
    if st.active == 0 {
        return;
    }
    let Some((ids, vs, ws)) = columns_mut(&mut q) else {
        return;
    };
    // The pair sums are indexed by the rows the neighbour stage gathered this step;
    // every particle kicked is checked to be the one its index names.
    const MOVED: &str = "the particle table changed after the neighbour stage";
    let local = st.local;
    assert_eq!(ids.len(), local, "{MOVED}");
    let vs = Velocity::peel_slice_mut(bypass(vs));
    let ws = AngularVelocity::peel_slice_mut(bypass(ws));
    let (kick_v, kick_w) = (&st.kick_v, &st.kick_w);
    if !st.sparse {
        assert!(ParticleId::peel_slice(ids) == &st.ids[..local], "{MOVED}");
        kick_all(vs, ws, &mut st.slots, kick_v, kick_w);
        return;
    }
    let slots = &st.slots;
    // The particles to visit on a sparse step, in slot order, each once.
    for s in slots {
        for &k in &s.touched {
            let k = k as usize;
            // Ghost rows (a decomposed run) are kicked by their owner.
            if k >= local || st.marked[k] {
                continue;
            }
            st.marked[k] = true;
            assert_eq!(ids[k].0, st.ids[k], "{MOVED}");
            let (f, t) = slot_sum(slots, k);
            vs[k] += f * kick_v[k];
            ws[k] += t * kick_w[k];
        }
    }
    for s in slots {
        for &k in &s.touched {
            st.marked[k as usize] = false;
        }
    }
}

/// Part of a slot's sums read by one chunk of the kicks: (first particle, rows).
type SumsPart<'a> = (usize, &'a mut [[DVec3; 2]]);

/// The kicks of [`apply_contact_kicks`] for every particle, in parallel chunks (each
/// particle's update is independent). Each particle's force and torque are the covering
/// slots' sums added in slot order (to zero first, as [`slot_sum`] adds them); the kick
/// zeroes the rows it read, so the next force stage has nothing left to clear (no slot
/// covers the ghost rows of a decomposed run).
fn kick_all(v: &mut [DVec3], w: &mut [DVec3], slots: &mut [Slot], kick_v: &[f64], kick_w: &[f64]) {
    const C: usize = 4096;
    let n = v.len();
    // Each chunk's part of every slot's sums, in slot order: (first particle, rows).
    let mut shares: Vec<Vec<SumsPart>> = (0..n.div_ceil(C)).map(|_| Vec::new()).collect();
    for s in slots.iter_mut() {
        let base = s.base;
        let end = (base + s.sums.len()).min(n);
        let mut rest: &mut [[DVec3; 2]] = &mut s.sums;
        let mut at = base;
        while at < end {
            let k = at / C;
            let stop = ((k + 1) * C).min(end);
            let (mine, tail) = std::mem::take(&mut rest).split_at_mut(stop - at);
            shares[k].push((at, mine));
            (rest, at) = (tail, stop);
        }
        s.consumed = n;
    }
    let mut work: Vec<KickChunk> = (v.chunks_mut(C).zip(w.chunks_mut(C)).zip(shares))
        .enumerate()
        .map(|(k, ((v, w), parts))| KickChunk {
            base: k * C,
            v,
            w,
            parts,
            kick_v,
            kick_w,
        })
        .collect();
    crate::exec::team::for_each_item(&mut work, |_, c| kick_rows(c));
}

/// One chunk of the dense kicks: particles `base..base + v.len()`, their velocities,
/// angular velocities and the parts of the sums covering them (slot order), and every
/// particle's kick factors.
struct KickChunk<'a> {
    base: usize,
    v: &'a mut [DVec3],
    w: &'a mut [DVec3],
    parts: Vec<SumsPart<'a>>,
    kick_v: &'a [f64],
    kick_w: &'a [f64],
}

/// Kick a chunk with the sums of its parts (slot order), zeroing the rows read.
fn kick_rows(c: &mut KickChunk) {
    #[cfg(target_arch = "x86_64")]
    if crate::exec::lanes() {
        // SAFETY: the CPU supports AVX2 (`exec::lanes` checked it).
        unsafe { kick_rows_avx2(c) };
        return;
    }
    kick_rows_body(c);
}

/// [`kick_rows`] compiled for AVX2 (the same operations: no fused multiply–adds).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn kick_rows_avx2(c: &mut KickChunk) {
    kick_rows_body(c);
}

/// The kicks of [`kick_rows`]: the chunk is cut where the set of covering parts changes,
/// and each piece runs a loop over its particles with that set fixed.
#[inline(always)]
fn kick_rows_body(c: &mut KickChunk) {
    let KickChunk {
        base,
        v,
        w,
        parts,
        kick_v,
        kick_w,
    } = c;
    let (base, kick_v, kick_w) = (*base, *kick_v, *kick_w);
    let len = v.len();
    let (kick_v, kick_w) = (&kick_v[base..base + len], &kick_w[base..base + len]);
    // Chunk-local places where a part starts or ends.
    let mut cuts: Vec<usize> = vec![0, len];
    for (start, rows) in parts.iter() {
        cuts.extend([start - base, start - base + rows.len()]);
    }
    cuts.sort_unstable();
    cuts.dedup();
    for piece in cuts.windows(2) {
        let (lo, hi) = (piece[0], piece[1]);
        // The parts covering lo..hi, in slot order, cut to it.
        let mut cover: Vec<&mut [[DVec3; 2]]> = parts
            .iter_mut()
            .filter(|(start, rows)| *start <= base + lo && base + hi <= *start + rows.len())
            .map(|(start, rows)| &mut rows[base + lo - *start..base + hi - *start])
            .collect();
        let (v, w) = (&mut v[lo..hi], &mut w[lo..hi]);
        let (kv, kw) = (&kick_v[lo..hi], &kick_w[lo..hi]);
        // A fixed count (an array) lets the loop over the parts unroll.
        match cover.len() {
            0 => kick_piece(&mut [], v, w, kv, kw),
            1 => kick_piece(&mut fixed::<1>(cover), v, w, kv, kw),
            2 => kick_piece(&mut fixed::<2>(cover), v, w, kv, kw),
            3 => kick_piece(&mut fixed::<3>(cover), v, w, kv, kw),
            _ => kick_piece(&mut cover, v, w, kv, kw),
        }
    }
}

/// The `K` parts of a piece, as an array.
#[inline(always)]
fn fixed<const K: usize>(cover: Vec<&mut [[DVec3; 2]]>) -> [&mut [[DVec3; 2]]; K] {
    cover.try_into().unwrap_or_else(|_| unreachable!("K parts"))
}

/// Kick a piece covered by the parts `cover` (each as long as `v`): the parts' rows added
/// to zero in order, then zeroed.
#[inline(always)]
fn kick_piece(
    cover: &mut [&mut [[DVec3; 2]]],
    v: &mut [DVec3],
    w: &mut [DVec3],
    kv: &[f64],
    kw: &[f64],
) {
    let n = v.len();
    let (w, kv, kw) = (&mut w[..n], &kv[..n], &kw[..n]);
    for rows in cover.iter_mut() {
        *rows = &mut std::mem::take(rows)[..n];
    }
    for p in 0..n {
        let (mut f, mut t) = (DVec3::ZERO, DVec3::ZERO);
        for rows in cover.iter_mut() {
            let [rf, rt] = std::mem::take(&mut rows[p]);
            f += rf;
            t += rt;
        }
        v[p] += f * kv[p];
        w[p] += t * kw[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stages::contacts::slots::layout_slots;
    use rand::{Rng, SeedableRng};

    /// The dense kicks add each particle's covering slot sums in slot order (the bits of
    /// [`slot_sum`]) and zero the rows they read, which leaves every sum zero; no slot
    /// covers a ghost row.
    #[test]
    fn dense_kicks_add_the_slots_in_order_and_consume_them() {
        // Up to three slots cover a particle; up to seven.
        for reach in [1800, 6000] {
            kicks_against_slot_sums(reach);
        }
    }

    fn kicks_against_slot_sums(reach: u32) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (local, ghosts) = (9000usize, 500usize);
        let rows = local + ghosts;
        let mut pairs: Vec<[u32; 2]> = (0..40_000)
            .map(|_| {
                let i = rng.random_range(0..local as u32);
                [
                    i,
                    rng.random_range(i + 1..=(i + reach).min(rows as u32 - 1)),
                ]
            })
            .collect();
        pairs.sort_unstable();
        let mut slots = layout_slots(&pairs, rows, local);
        assert!(slots.len() > 2, "{} slots", slots.len());
        let mut draw = || DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
        for s in &mut slots {
            for r in &mut s.sums {
                *r = [draw(), draw()];
            }
            s.dirty = true;
        }
        let v: Vec<DVec3> = (0..local).map(|_| draw()).collect();
        let w: Vec<DVec3> = (0..local).map(|_| draw() * 100.0).collect();
        let kick_v: Vec<f64> = (0..local).map(|_| rng.random_range(1.0..2.0)).collect();
        let kick_w: Vec<f64> = (0..local).map(|_| rng.random_range(1e3..2e3)).collect();
        let expected: Vec<(DVec3, DVec3)> = (0..local)
            .map(|k| {
                let (f, t) = slot_sum(&slots, k);
                (v[k] + f * kick_v[k], w[k] + t * kick_w[k])
            })
            .collect();
        // No slot covers a ghost row (the local–ghost pairs sum their local side only),
        // though some pairs reach them.
        assert!(pairs.iter().any(|p| p[1] as usize >= local));
        assert!((local..rows).all(|k| slots.iter().all(|s| !s.covers(k))));
        let most = (0..rows)
            .map(|k| slots.iter().filter(|s| s.covers(k)).count())
            .max();
        assert!(most > Some(if reach > 2000 { 4 } else { 2 }), "{most:?}");
        let (mut v2, mut w2) = (v.clone(), w.clone());
        kick_all(&mut v2, &mut w2, &mut slots, &kick_v, &kick_w);
        let bits = |a: DVec3| a.to_array().map(f64::to_bits);
        for k in 0..local {
            assert_eq!(bits(v2[k]), bits(expected[k].0), "v of {k}");
            assert_eq!(bits(w2[k]), bits(expected[k].1), "w of {k}");
            assert!(
                slots
                    .iter()
                    .all(|s| !s.covers(k) || s.sums[k - s.base] == [DVec3::ZERO; 2])
            );
        }
        for s in &mut slots {
            s.clear(1);
            assert!(s.sums.iter().all(|r| *r == [DVec3::ZERO; 2]));
        }
    }
}
