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
    let slots = &st.slots;
    let (kick_v, kick_w) = (&st.kick_v, &st.kick_w);
    if !st.sparse {
        assert!(ParticleId::peel_slice(ids) == &st.ids[..local], "{MOVED}");
        kick_all(vs, ws, slots, kick_v, kick_w);
        return;
    }
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

/// The kicks of [`apply_contact_kicks`] for every particle, in parallel chunks (each
/// particle's update is independent). A chunk sums the slots covering it, in slot order,
/// into a buffer (contiguous runs), then kicks.
fn kick_all(v: &mut [DVec3], w: &mut [DVec3], slots: &[Slot], kick_v: &[f64], kick_w: &[f64]) {
    const C: usize = 4096;
    // Sums are built in blocks small enough to stay in the L1 cache.
    const B: usize = 256;
    let block = |base: usize, vc: &mut [DVec3], wc: &mut [DVec3]| {
        let len = vc.len();
        let mut f = [DVec3::ZERO; B];
        let mut t = [DVec3::ZERO; B];
        let (f, t) = (&mut f[..len], &mut t[..len]);
        for s in slots {
            let lo = base.max(s.base);
            let hi = (base + len).min(s.base + s.sums.len());
            if lo >= hi {
                continue;
            }
            let ss = &s.sums[lo - s.base..hi - s.base];
            for ((a, c), [b, d]) in f[lo - base..hi - base]
                .iter_mut()
                .zip(t[lo - base..hi - base].iter_mut())
                .zip(ss)
            {
                *a += *b;
                *c += *d;
            }
        }
        let kv = &kick_v[base..base + len];
        for ((v, f), k) in vc.iter_mut().zip(&*f).zip(kv) {
            *v += *f * *k;
        }
        let kw = &kick_w[base..base + len];
        for ((w, t), k) in wc.iter_mut().zip(&*t).zip(kw) {
            *w += *t * *k;
        }
    };
    let chunk = |base: usize, vc: &mut [DVec3], wc: &mut [DVec3]| {
        for (b, (vb, wb)) in vc.chunks_mut(B).zip(wc.chunks_mut(B)).enumerate() {
            block(base + b * B, vb, wb);
        }
    };
    if v.len() < 2 * C {
        chunk(0, v, w);
        return;
    }
    // (velocities, angular velocities) of each chunk; chunk k starts at particle k·C.
    let mut work: Vec<(&mut [DVec3], &mut [DVec3])> =
        v.chunks_mut(C).zip(w.chunks_mut(C)).collect();
    crate::exec::team::for_each_item(&mut work, |k, (vc, wc)| chunk(k * C, vc, wc));
}
