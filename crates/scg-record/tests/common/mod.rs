//! Synthetic runs shared by the integration tests.

#![allow(dead_code)]

use scg_core::frame::{Frame, GroupMeta, Outline, PatchSurface, RunMeta};

/// Number of particles in a full frame.
pub const N_PARTICLES: u32 = 50;
/// Number of frames of [`frames`].
pub const N_FRAMES: usize = 5;

/// A run description with three groups, two outlines and two warnings.
pub fn meta() -> RunMeta {
    RunMeta {
        case: "synthetic-case".into(),
        scg_version: "0.1.0-test".into(),
        ranks: 3,
        seed: 0xDEAD_BEEF_0123_4567,
        dt: 1.0e-5 / 3.0,
        record_every: 250,
        groups: vec![
            GroupMeta {
                name: "small".into(),
                law: "scg".into(),
                alpha: 2.5,
                original_diameter: 1.0e-4 / 3.0,
                color: [230, 80, 40],
            },
            GroupMeta {
                name: "large grains".into(),
                law: "none".into(),
                alpha: 1.0,
                original_diameter: 2.0e-3,
                color: [40, 120, 230],
            },
            GroupMeta {
                name: "parcels/α".into(),
                law: "parcel".into(),
                alpha: 7.123_456_789_012_345,
                original_diameter: 5.0e-5,
                color: [20, 200, 90],
            },
        ],
        scene_toml: "# synthetic scene\n[domain]\nsize = [0.1, 0.2, 0.3]\nname = \"ü\"\n".into(),
        scene_dir: "/data/flüid cases".into(),
        outlines: vec![
            Outline {
                name: "vessel".into(),
                strips: vec![
                    vec![
                        [0.0, 0.0, 0.0],
                        [0.1, 0.0, 0.0],
                        [0.1, 0.2, 0.0],
                        [0.0, 0.2, 0.0],
                    ],
                    vec![[0.0, 0.0, 0.3], [0.1, 0.0, 0.3]],
                ],
                ..Default::default()
            },
            Outline {
                name: "nozzle".into(),
                strips: vec![vec![[0.05, 0.1, 0.3], [0.05, 0.1, 0.25]]],
                ..Default::default()
            },
        ],
        patches: vec![
            PatchSurface {
                name: "walls".into(),
                role: "wall".into(),
                vertices: vec![
                    [0.0, 0.0, 0.0],
                    [0.1, 0.0, 0.0],
                    [0.1, 0.2, 0.0],
                    [0.0, 0.2, 1.0 / 3.0],
                ],
                triangles: vec![[0, 1, 2], [0, 2, 3]],
            },
            PatchSurface {
                name: "out let/α".into(),
                role: "outlet".into(),
                vertices: vec![[0.0, 0.0, 0.3], [0.1, 0.0, 0.3], [0.1, 0.2, 0.3]],
                triangles: vec![[0, 1, 2]],
            },
        ],
        warnings: vec![
            "time step is close to the collision time".into(),
            "group `small`: α = 2.5 is large".into(),
        ],
        parts: Vec::new(),
    }
}

/// Deterministic pseudo-random numbers in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Five frames of up to 50 particles in three groups, with values that vary from frame to
/// frame and some awkward numbers (subnormals, −0, huge, tiny, NaN scalar). Frame 2 lacks a
/// few particles and frame 3 has no particle of group 2.
pub fn frames() -> Vec<Frame> {
    let meta = meta();
    let mut rng = Lcg(42);
    (0..N_FRAMES)
        .map(|k| {
            let step = 250 * k as u64;
            let mut frame = Frame {
                step,
                time: step as f64 * meta.dt,
                ..Frame::default()
            };
            for id in 0..N_PARTICLES {
                let group = id % 3;
                if k == 2 && id % 11 == 5 {
                    continue;
                }
                if k == 3 && group == 2 {
                    continue;
                }
                let r = |rng: &mut Lcg| rng.next() - 0.5;
                frame.id.push(id);
                frame.group.push(group);
                frame.position.push([
                    r(&mut rng) * 0.1,
                    r(&mut rng) * 0.2,
                    r(&mut rng) * 0.3 + 0.15,
                ]);
                frame
                    .velocity
                    .push([r(&mut rng), r(&mut rng) * 1e-3, -9.81 * frame.time]);
                frame
                    .diameter
                    .push(meta.groups[group as usize].original_diameter * (1.0 + 0.1 * rng.next()));
                frame.density.push(2500.0 + 100.0 * r(&mut rng));
            }
            // Awkward values on particle 0 of each frame.
            let awkward = [f64::MIN_POSITIVE / 8.0, -0.0, 1.0e300, 1.0 / 3.0, -1.0e-300];
            frame.position[0][0] = awkward[k];
            frame.velocity[0][1] = awkward[(k + 1) % awkward.len()];
            frame.stats = vec![
                (
                    "count/small".into(),
                    frame.group.iter().filter(|&&g| g == 0).count() as f64,
                ),
                ("energy/kinetic".into(), rng.next() * 1e-6),
                ("height max".into(), 0.1 + rng.next() / 3.0),
            ];
            if k == 4 {
                frame.stats.push(("undefined".into(), f64::NAN));
            }
            frame
        })
        .collect()
}

/// Bitwise equality of two frames (NaN-aware, −0-aware).
pub fn assert_frames_bit_equal(got: &[Frame], want: &[Frame]) {
    assert_eq!(got.len(), want.len(), "number of frames");
    for (g, w) in got.iter().zip(want) {
        assert_eq!(g.step, w.step);
        assert_eq!(
            g.time.to_bits(),
            w.time.to_bits(),
            "time of step {}",
            w.step
        );
        assert_eq!(g.id, w.id, "ids of step {}", w.step);
        assert_eq!(g.group, w.group, "groups of step {}", w.step);
        let bits3 = |v: &[[f64; 3]]| -> Vec<[u64; 3]> {
            v.iter()
                .map(|p| [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()])
                .collect()
        };
        let bits = |v: &[f64]| -> Vec<u64> { v.iter().map(|x| x.to_bits()).collect() };
        assert_eq!(
            bits3(&g.position),
            bits3(&w.position),
            "positions of step {}",
            w.step
        );
        assert_eq!(
            bits3(&g.velocity),
            bits3(&w.velocity),
            "velocities of step {}",
            w.step
        );
        assert_eq!(
            bits(&g.diameter),
            bits(&w.diameter),
            "diameters of step {}",
            w.step
        );
        assert_eq!(
            bits(&g.density),
            bits(&w.density),
            "densities of step {}",
            w.step
        );
        let stats = |s: &[(String, f64)]| -> Vec<(String, u64)> {
            s.iter().map(|(n, v)| (n.clone(), v.to_bits())).collect()
        };
        assert_eq!(stats(&g.stats), stats(&w.stats), "stats of step {}", w.step);
    }
}
