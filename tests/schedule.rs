//! The schedule holds only the effects a scene declares.

mod common;

use scg::core::step::StepSet;

#[test]
fn drag_only_scene_runs_no_neighbour_search_or_contacts() {
    let scene = common::case("uniform", &[]);
    let sim = scene.build(true);
    let plan = sim.plan();
    assert_eq!(plan.in_set(StepSet::NeighbourSearch).count(), 0);
    assert_eq!(plan.in_set(StepSet::Forces).count(), 0, "{}", plan.render());
    assert!(
        !plan
            .systems
            .iter()
            .any(|s| s.system.contains("contact") || s.system.contains("neighbour"))
    );
    assert!(plan.contains("integrate_stokes_exponential"));
    assert!(plan.contains("record_frame"));
}

#[test]
fn walls_add_force_systems_in_order() {
    let scene = common::case("vortex", &[]);
    let sim = scene.build(false);
    let plan = sim.plan();
    let names: Vec<_> = plan.systems.iter().map(|s| s.system).collect();
    let pos = |n: &str| {
        names
            .iter()
            .position(|s| *s == n)
            .unwrap_or_else(|| panic!("{n} in {names:?}"))
    };
    assert!(pos("coarse_grain_new_particles") < pos("wall_normal_forces"));
    assert!(
        !plan.contains("clear_forces"),
        "walls set the force, nothing clears it"
    );
    assert!(pos("wall_normal_forces") < pos("integrate_stokes_exponential"));
    assert!(pos("integrate_stokes_exponential") < pos("advance_clock"));
    assert!(!plan.contains("record_frame"), "recording off");
}

#[test]
fn integrator_and_drag_law_pick_the_system() {
    let s = common::case("uniform", &["integrator=\"explicit\""]).build(false);
    assert!(s.plan().contains("integrate_drag_explicit"));
    let s = common::case("uniform", &["drag.law=\"schiller_naumann\""]).build(false);
    assert!(s.plan().contains("integrate_drag_exponential"));
}
