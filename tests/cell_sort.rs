//! `sort_by_cell`: the particle table reordered by mesh cell (mesh flows without
//! particle contacts) changes no result, leaves the table in cell order, and refuses a
//! particle layout it does not fully know.
//!
//! Run: `cargo test --release --test cell_sort -- --nocapture`.

mod common;

use bevy_ecs::prelude::*;
use scg::core::components::{CellHint, ParticleId};
use scg::core::stages::outlet::OutletLog;
use scg::core::state::Tally;
use scg::core::step::StepSystem;
use scg::scene::Scene;

/// The fixture box of [`common::cfd_box_scene`] for 50 ms.
fn fixture_box(sets: &[String]) -> Scene {
    let mut all = vec!["duration=0.05".to_string()];
    all.extend(sets.iter().cloned());
    scg::scene::parse(&common::cfd_box_scene(), "fixture-box.toml", "box", &all)
        .unwrap_or_else(|e| panic!("{e}"))
}

fn cyclone(sets: &[String]) -> Scene {
    let mut all = vec!["feed_scale=0.5".to_string(), "duration=0.3".to_string()];
    all.extend(sets.iter().cloned());
    let all: Vec<&str> = all.iter().map(String::as_str).collect();
    common::case("cyclone", &all)
}

/// Digests of the state every 25 steps, and the final counts.
fn history(scene: &Scene) -> (Vec<u64>, Tally, OutletLog, bool) {
    let mut sim = scene.build(false);
    let planned = sim.plan().contains(StepSystem::SortByCell);
    let mut digests = Vec::new();
    let steps = scene.steps();
    for k in 1..=steps {
        sim.step().unwrap();
        if k % 25 == 0 || k == steps {
            digests.push(common::state_digest(&sim.particles()));
        }
    }
    let tally = sim.world.resource::<Tally>().clone();
    let log = sim.world.resource::<OutletLog>().clone();
    (digests, tally, log, planned)
}

#[test]
fn sorting_by_cell_changes_no_result() {
    for (name, make) in [
        ("cyclone", cyclone as fn(&[String]) -> Scene),
        ("fixture box", fixture_box),
    ] {
        let base = history(&make(&["flow.sort_every=0".into()]));
        assert!(!base.3, "{name}: sort_every = 0 still sorts");
        let fed: u64 = base.1.fed.iter().sum();
        let drained: u64 = base.1.drained.iter().sum();
        println!(
            "{name}: {fed} fed, {drained} drained, {} states compared",
            base.0.len()
        );
        assert!(fed > 50, "{name}: too few particles to test ({fed})");
        for every in [1, 7, 100] {
            let run = history(&make(&[format!("flow.sort_every={every}")]));
            assert!(run.3, "{name}: sort_by_cell not planned");
            assert_eq!(run.0, base.0, "{name}, sort_every = {every}: states differ");
            assert_eq!(run.1, base.1, "{name}, sort_every = {every}: tally");
            assert_eq!(run.2.drained, base.2.drained, "{name}, {every}: drained");
            assert_eq!(run.2.lost, base.2.lost, "{name}, {every}: lost");
        }
    }
}

/// Whether the table rows are in (cell, id) order.
fn in_cell_order(world: &mut World) -> bool {
    let mut q = world.query::<(&CellHint, &ParticleId)>();
    let keys: Vec<(u32, u32)> = q.iter(world).map(|(h, id)| (h.0, id.0)).collect();
    keys.is_sorted()
}

#[test]
fn the_table_is_in_cell_order_after_a_sort() {
    // 40 steps: sorted after step 40 with sort_every = 10; a particle fed at step 40 may
    // not have a cell yet, so feed nothing after 0.005 s (step 25).
    let sets = ["duration=0.008".to_string()];
    for every in [0u64, 10] {
        let mut sets = sets.to_vec();
        sets.push(format!("flow.sort_every={every}"));
        let mut scene = cyclone(&sets);
        for f in &mut scene.feeders {
            f.rate = 50_000.0;
            f.window.1 = 0.005;
        }
        let mut sim = scene.build(false);
        sim.run(scene.steps(), |_| true).unwrap();
        let n = sim.particles().len();
        let sorted = in_cell_order(&mut sim.world);
        println!("sort_every = {every}: {n} particles, table in cell order: {sorted}");
        assert!(n > 500);
        assert_eq!(sorted, every > 0, "sort_every = {every}");
    }
}

#[derive(Component)]
struct Stranger;

#[test]
#[should_panic(expected = "does not know the particle components")]
fn an_unknown_particle_component_stops_the_sort() {
    let scene = cyclone(&["flow.sort_every=1".into()]);
    let mut sim = scene.build(false);
    sim.run(300, |_| true).unwrap(); // 60 ms: about 60 particles fed
    let es: Vec<Entity> = sim
        .world
        .query_filtered::<Entity, With<ParticleId>>()
        .iter(&sim.world)
        .collect();
    assert!(!es.is_empty());
    for e in es {
        sim.world.entity_mut(e).insert(Stranger);
    }
    sim.step().unwrap();
}
