//! Tests of [`super`] (slots).

use super::*;
use crate::physics::contact::Material;
use crate::physics::contact::normal::effective;
use crate::physics::contact::pair::{PairArrays, PairState};
use crate::physics::contact::{NormalLaw, TangentialLaw};
use rand::{Rng, SeedableRng};

/// The kernel of the tests: `bodies` in one group, dt = 1 µs, every row local.
fn test_kernel<'a>(bodies: Bodies<'a>, par: PairParams, group: &'a [u32]) -> Kernel<'a> {
    Kernel {
        local: bodies.pos.len(),
        bodies,
        par,
        lanes: HertzMindlin::of(&par),
        dt: 1e-6,
        group,
    }
}

/// A pair indexing past the particle arrays stops the slot loop (the four-lane path
/// reads the arrays unchecked after its own test) rather than reading beyond them.
#[test]
#[should_panic(expected = "past the particle arrays")]
fn a_pair_past_the_particles_panics() {
    if !cfg!(target_arch = "x86_64") || !std::arch::is_x86_feature_detected!("avx2") {
        panic!("a pair indexes past the particle arrays (no AVX2 here: nothing to check)");
    }
    let n = 8;
    let pos: Vec<DVec3> = (0..n).map(|k| DVec3::X * k as f64 * 1e-3).collect();
    let (vel, radius) = (vec![DVec3::ZERO; n], vec![0.6e-3; n]);
    let material = Material {
        youngs_modulus: 1e8,
        poisson_ratio: 0.3,
        restitution: 0.6,
        friction: 0.4,
    };
    let par = super::super::ContactConfig {
        law: NormalLaw::hertz(0.6),
        material,
        skin: 1e-4,
        periodic: None,
        rolling_friction: 0.0,
        tangential_stiffness: crate::physics::contact::tangential::TangentialStiffness::Mindlin,
    }
    .pair_params();
    let list: Vec<[u32; 2]> = (0..n as u32 - 1)
        .map(|i| [i, i + 1])
        .chain([[6, 40]])
        .collect();
    let mut pairs = PairArrays::default();
    for _ in &list {
        pairs.touching.push(false);
        pairs.state.push(PairState {
            history: DVec3::ZERO,
            hertz: HertzPair::new(par.e_eff, 0.3e-3, 1e-6),
        });
    }
    let group = vec![0; n];
    let bodies = Bodies {
        pos: (&pos).into(),
        vel: (&vel).into(),
        omega: (&vel).into(),
        radius: &radius,
    };
    let kernel = test_kernel(bodies, par, &group);
    let mut slot = Slot {
        pairs: 0..list.len(),
        base: 0,
        sums: vec![[DVec3::ZERO; 2]; 64],
        marked: vec![false; 64],
        ..Default::default()
    };
    slot.run(&mut pairs.view(&list, 0..list.len()), &kernel, 1, false);
}

/// The four-lane AVX2 path of the slot loop (rolling resistance included) gives the
/// same sums, histories and contact flags, bit for bit, as the portable one.
#[test]
fn avx2_and_portable_slot_loops_agree_bit_for_bit() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let n = 400;
    let d = 1e-3;
    let pos: Vec<DVec3> = (0..n)
        .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) * 6.0 * d)
        .collect();
    let vel: Vec<DVec3> = (0..n)
        .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5)
        .collect();
    let omega: Vec<DVec3> = (0..n)
        .map(|_| (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 100.0)
        .collect();
    let radius: Vec<f64> = (0..n)
        .map(|_| 0.5 * d * rng.random_range(0.7..1.0))
        .collect();
    let mass: Vec<f64> = radius
        .iter()
        .map(|r| 2500.0 * 4.18879 * r * r * r)
        .collect();
    let material = Material {
        youngs_modulus: 1e8,
        poisson_ratio: 0.3,
        restitution: 0.6,
        friction: 0.4,
    };
    let law = NormalLaw::hertz(0.6);
    for (rolling, sparse) in [(0.05, true), (0.05, false), (0.0, true), (0.0, false)] {
        let par = PairParams {
            law,
            tangential: TangentialLaw::new(law, 0.4, rolling),
            e_eff: material.effective_modulus(),
            g_eff: material.effective_shear_modulus(),
            periodic: None,
            mindlin_c: (6.0 * material.effective_shear_modulus() / material.effective_modulus())
                .sqrt(),
        };
        let mut list: Vec<[u32; 2]> = Vec::new();
        let mut pairs = PairArrays::default();
        for i in 0..n {
            for j in i + 1..n {
                if (pos[j] - pos[i]).length() < 1.1 * (radius[i] + radius[j]) {
                    list.push([i as u32, j as u32]);
                    pairs.touching.push(rng.random());
                    pairs.state.push(PairState {
                        history: (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5)
                            * 1e-6,
                        hertz: HertzPair::new(
                            par.e_eff,
                            effective(radius[i], radius[j]),
                            effective(mass[i], mass[j]),
                        ),
                    });
                }
            }
        }
        let group = vec![0; n];
        let bodies = Bodies {
            pos: (&pos).into(),
            vel: (&vel).into(),
            omega: (&omega).into(),
            radius: &radius,
        };
        let kernel = test_kernel(bodies, par, &group);
        let run = |avx: bool, local: usize, list: &[[u32; 2]], pairs: &PairArrays| {
            let mut slots = layout_slots(list, n, local);
            let mut ps = pairs.clone();
            let slot = &mut slots[0];
            let mut view = ps.view(list, slot.pairs.clone());
            if avx {
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    let law = kernel.lanes.unwrap();
                    unsafe { slot.run_avx2(&mut view, &kernel, law, 1, sparse) };
                    return Some((slot.sums.clone(), ps));
                }
                return None;
            }
            slot.run_portable(&mut view, &kernel, 1, sparse);
            Some((slot.sums.clone(), ps))
        };
        let bits = |v: &[[DVec3; 2]]| -> Vec<u64> {
            v.iter()
                .flatten()
                .flat_map(|x| x.to_array().map(f64::to_bits))
                .collect()
        };
        let portable = run(false, n, &list, &pairs).unwrap();
        assert!(portable.0.iter().any(|f| f[0] != DVec3::ZERO));
        // more than two listing blocks, so that touching pairs are carried over
        assert!(list.len() > 2 * LIST_BLOCK, "{} pairs", list.len());
        if let Some(avx) = run(true, n, &list, &pairs) {
            assert_eq!(bits(&portable.0), bits(&avx.0));
            assert_eq!(portable.1, avx.1);
        }
        // The last 100 rows as ghosts (a decomposed run, whose list has no ghost–ghost
        // pairs): the slot covers the table's rows only, and their sums are the same
        // bits (only the ghosts' sides dropped).
        let local = n - 100;
        let keep: Vec<usize> = (0..list.len())
            .filter(|&k| (list[k][0] as usize) < local)
            .collect();
        let sub = |ps: &PairArrays| PairArrays {
            touching: keep.iter().map(|&k| ps.touching[k]).collect(),
            shift: Vec::new(),
            state: keep.iter().map(|&k| ps.state[k]).collect(),
        };
        let local_list: Vec<[u32; 2]> = keep.iter().map(|&k| list[k]).collect();
        assert!(local_list.iter().any(|p| p[1] as usize >= local));
        for avx in [false, true] {
            if let Some((sums, ps)) = run(avx, local, &local_list, &sub(&pairs)) {
                assert!(sums.len() <= local, "avx {avx}");
                assert_eq!(bits(&sums), bits(&portable.0[..sums.len()]), "avx {avx}");
                assert!(
                    portable.0[sums.len()..local]
                        .iter()
                        .all(|r| r[0] == DVec3::ZERO)
                );
                assert_eq!(ps, sub(&portable.1));
            }
        }
    }
}
