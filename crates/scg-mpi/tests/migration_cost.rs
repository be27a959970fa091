//! What migrating a particle costs on one rank, without the network: take it out of the
//! world with its whole state, encode, decode, put it in another world. A measurement for
//! docs/scaling.md, not a timed test:
//! `cargo test --release -p scg-mpi --test migration_cost -- --ignored --nocapture`.

use std::time::Instant;

use glam::DVec3;
use scg_core::checkpoint::ParticleRecord;
use scg_core::physics::flow::FlowField;
use scg_core::physics::scaling::CoarseGrainLaw;
use scg_core::{ParticleSpec, SimConfig, Simulation};

fn sim() -> Simulation {
    Simulation::new(SimConfig {
        dt: 1e-5,
        integrator: Default::default(),
        drag: None,
        fluid: None,
        flow: FlowField::Still,
        mesh_flow: None,
        gravity: Some(DVec3::new(0.0, 0.0, -9.81)),
        buoyancy: false,
        scg_at_original: false,
        extra_forces: Default::default(),
        walls: None,
        contacts: None,
        record_every: None,
        groups: vec!["g".into()],
        carrier: None,
    })
}

/// `n` SCG particles (α = 2) on the x axis at x = 0, 1, …, all with velocity `v`.
fn spawn_row(s: &mut Simulation, n: usize, v: DVec3) {
    for i in 0..n {
        s.spawn(&ParticleSpec {
            group: 0,
            diameter: 1e-4,
            density: 2000.0,
            alpha: 2.0,
            law: CoarseGrainLaw::Scg,
            position: DVec3::new(i as f64, 0.0, 0.0),
            velocity: v,
        });
    }
}

#[test]
fn migrated_particles_keep_their_state() {
    let mut a = sim();
    spawn_row(&mut a, 10, DVec3::new(0.0, 1.0, 0.0));
    a.step().unwrap();
    let before = a.particles();
    let gone: Vec<ParticleRecord> = a.extract_particles(|_, x| x.x >= 5.0);
    assert_eq!(gone.len(), 5);
    assert_eq!(a.particles().len(), 5);
    let bytes = postcard::to_stdvec(&gone).unwrap();
    let back: Vec<ParticleRecord> = postcard::from_bytes(&bytes).unwrap();
    let mut b = sim();
    b.insert_particles(&back).unwrap();
    let mut all = a.particles();
    all.extend(b.particles());
    all.sort_by_key(|p| p.id);
    assert_eq!(all, before, "the same particles, bit for bit");
}

#[test]
#[ignore = "a measurement: run with --ignored --nocapture"]
fn migration_cost_per_particle() {
    let n = 100_000;
    let mut a = sim();
    spawn_row(&mut a, n, DVec3::ZERO);
    let mut b = sim();
    let t = Instant::now();
    let gone = a.extract_particles(|_, _| true);
    let t_extract = t.elapsed();
    let t = Instant::now();
    let bytes = postcard::to_stdvec(&gone).unwrap();
    let t_encode = t.elapsed();
    let t = Instant::now();
    let back: Vec<ParticleRecord> = postcard::from_bytes(&bytes).unwrap();
    let t_decode = t.elapsed();
    let t = Instant::now();
    b.insert_particles(&back).unwrap();
    let t_insert = t.elapsed();
    let per = |d: std::time::Duration| d.as_secs_f64() / n as f64 * 1e9;
    println!(
        "MIGRATION n={n}: {:.0} bytes/particle; ns/particle: extract {:.0}, encode {:.0}, decode {:.0}, insert {:.0}",
        bytes.len() as f64 / n as f64,
        per(t_extract),
        per(t_encode),
        per(t_decode),
        per(t_insert)
    );
    assert_eq!(b.particles().len(), n);
}
