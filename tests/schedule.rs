//! The schedule holds only the effects a scene declares.

mod common;

use scg::core::step::{StepSet, StepSystem};

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
            .any(|s| s.system.name().contains("contact") || s.system.name().contains("neighbour"))
    );
    assert!(plan.contains(StepSystem::IntegrateStokesExponential));
    assert!(plan.contains(StepSystem::RecordFrame));
}

#[test]
fn walls_add_force_systems_in_order() {
    let scene = common::case("vortex", &[]);
    let sim = scene.build(false);
    let plan = sim.plan();
    let pos = |n: StepSystem| {
        plan.position(n)
            .unwrap_or_else(|| panic!("{n} in {}", plan.render()))
    };
    // Particles enter coarse-grained: the scaling set runs nothing per step, and the
    // walls see coarse-grained particles from the first step on.
    assert_eq!(plan.in_set(StepSet::Scaling).count(), 0);
    assert!(
        !plan
            .systems
            .iter()
            .any(|s| s.system.name() == "clear_forces"),
        "walls set the force, nothing clears it"
    );
    assert!(pos(StepSystem::WallNormalForces) < pos(StepSystem::IntegrateStokesExponential));
    assert!(pos(StepSystem::IntegrateStokesExponential) < pos(StepSystem::AdvanceClock));
    assert!(!plan.contains(StepSystem::RecordFrame), "recording off");
}

#[test]
fn integrator_and_drag_law_pick_the_system() {
    let s = common::case("uniform", &["integrator=\"explicit\""]).build(false);
    assert!(s.plan().contains(StepSystem::IntegrateDragExplicit));
    let s = common::case("uniform", &["drag.law=\"schiller_naumann\""]).build(false);
    assert!(s.plan().contains(StepSystem::IntegrateDragExponential));
}
