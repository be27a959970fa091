//! The tables and files a run ends with (the same for one rank and for a decomposed run,
//! whose ranks' logs and particles are first merged on rank 0): the fates of every
//! group, the distributions by mass, the erosion table and files, `--fates-csv` and
//! `--summary-json`.

use scg_core::Simulation;
use scg_scene::Scene;

use crate::distribution::DistributionFates as ByMass;
use crate::fates::{GroupCounts, GroupFates};
use crate::run::RunArgs;

/// Print the fates, the distributions by mass and (with `[erosion]`) the erosion table,
/// and write `--erosion-csv`, `--erosion-vtk` and `--fates-csv`; `None` (the message
/// printed) when a file cannot be written.
pub fn end_tables(
    scene: &Scene,
    args: &RunArgs,
    sim: &mut Simulation,
) -> Option<(Vec<GroupFates>, Vec<ByMass>)> {
    let fates = crate::fates::fates(scene, sim);
    eprint!("{}", crate::fates::render(&fates));
    let by_mass = crate::distribution::by_mass(scene, &fates);
    eprint!("{}", crate::distribution::render(&by_mass));
    if let Some(rows) = crate::erosion::rows(scene, sim) {
        eprint!("{}", crate::erosion::render(scene, sim, &rows));
        if let Some(path) = &args.erosion_csv
            && !write_text(path, &crate::erosion::csv(&rows))
        {
            return None;
        }
        if let (Some(path), Some(text)) = (&args.erosion_vtk, crate::erosion::vtk(scene, sim))
            && !write_text(path, &text)
        {
            return None;
        }
    }
    if let Some(path) = &args.fates_csv
        && !write_text(path, &crate::fates::csv(&fates))
    {
        return None;
    }
    Some((fates, by_mass))
}

/// Write `--summary-json` (when asked for) from the run's figures, its fates and
/// distributions; false (the message printed) when it cannot be written.
pub fn write_summary(
    scene: &Scene,
    args: &RunArgs,
    sim: &mut Simulation,
    fates: &[GroupFates],
    by_mass: &[ByMass],
    run: &RunFigures,
) -> bool {
    if let Some(path) = &args.summary_json {
        let json = summary(scene, sim, fates, by_mass, run);
        let text = serde_json::to_string_pretty(&json).unwrap_or_default();
        if !write_text(path, &(text + "\n")) {
            return false;
        }
    }
    true
}

/// The `--summary-json` document of a finished run: [`summary_json`] with each group's
/// fates and (when the scene has size distributions) the distributions by mass.
pub fn summary(
    scene: &Scene,
    sim: &mut Simulation,
    fates: &[GroupFates],
    by_mass: &[ByMass],
    run: &RunFigures,
) -> serde_json::Value {
    let counts = GroupCounts::of(sim);
    let groups: Vec<(&str, f64, f64)> = scene
        .groups
        .iter()
        .map(|g| (g.name.as_str(), g.diameter, g.density))
        .collect();
    let mut json = summary_json(&scene.name, &groups, &counts, run);
    if let Some(gs) = json["groups"].as_array_mut() {
        for (g, f) in gs.iter_mut().zip(fates) {
            g["fates"] = crate::fates::json(f);
        }
    }
    if !by_mass.is_empty() {
        json["distributions"] = crate::distribution::json(by_mass);
    }
    json
}

/// Figures of a whole run for [`summary_json`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunFigures {
    /// Steps done.
    pub steps: u64,
    /// Time step, s.
    pub dt: f64,
    /// Simulated time at the end, s.
    pub time: f64,
    /// Sum over the steps of the particles in the domain.
    pub particle_steps: u64,
    /// Wall time of the steps, s (scene loading excluded).
    pub wall_s: f64,
    /// Worker threads (over all MPI ranks of a decomposed run).
    pub threads: usize,
}

/// The `--summary-json` document: `groups` = (name, diameter m, density kg/m³) in scene
/// order; a group missing from `counts` counts zero.
pub fn summary_json(
    name: &str,
    groups: &[(&str, f64, f64)],
    counts: &GroupCounts,
    run: &RunFigures,
) -> serde_json::Value {
    let classes: Vec<serde_json::Value> = groups
        .iter()
        .enumerate()
        .map(|(i, (g, d, rho))| {
            let times = |v: &Vec<Vec<f64>>| v.get(i).cloned().unwrap_or_default();
            let drained = times(&counts.drained);
            let lost = times(&counts.lost);
            serde_json::json!({
                "group": g,
                "diameter": d,
                "density": rho,
                "fed": counts.fed.get(i).copied().unwrap_or(0),
                "drained": drained.len(),
                "lost": lost.len(),
                "held": counts.held.get(i).copied().unwrap_or(0),
                "drained_times": drained,
                "lost_times": lost,
            })
        })
        .collect();
    serde_json::json!({
        "code": "scg",
        "version": env!("CARGO_PKG_VERSION"),
        "scene": name,
        "groups": classes,
        "steps": run.steps,
        "dt": run.dt,
        "time": run.time,
        "particle_steps": run.particle_steps,
        "wall_s": run.wall_s,
        "particle_steps_per_s": run.particle_steps as f64 / run.wall_s.max(1e-12),
        "threads": run.threads,
    })
}

/// Write `text` to `path` and say so, or say why not (false).
pub(crate) fn write_text(path: &std::path::Path, text: &str) -> bool {
    match std::fs::write(path, text) {
        Ok(()) => {
            eprintln!("wrote {}", path.display());
            true
        }
        Err(e) => {
            eprintln!("error: cannot write {}: {e}", path.display());
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_lists_each_group_with_its_counts_and_times() {
        let counts = GroupCounts {
            fed: vec![5, 3],
            drained: vec![vec![0.5, 0.75], vec![]],
            lost: vec![vec![], vec![1.25]],
            held: vec![3],
        };
        let run = RunFigures {
            steps: 100,
            dt: 0.01,
            time: 1.0,
            particle_steps: 400,
            wall_s: 2.0,
            threads: 2,
        };
        let j = summary_json(
            "s",
            &[("a", 1e-6, 2000.0), ("b", 2e-6, 1500.0)],
            &counts,
            &run,
        );
        let g = j["groups"].as_array().unwrap();
        assert_eq!(g.len(), 2);
        assert_eq!(g[0]["group"], "a");
        assert_eq!(g[0]["fed"], 5);
        assert_eq!(g[0]["drained"], 2);
        assert_eq!(g[0]["lost"], 0);
        assert_eq!(g[0]["held"], 3);
        assert_eq!(g[0]["drained_times"][1], 0.75);
        assert_eq!(g[1]["diameter"], 2e-6);
        assert_eq!(g[1]["density"], 1500.0);
        assert_eq!(g[1]["lost"], 1);
        assert_eq!(g[1]["lost_times"][0], 1.25);
        // no particle of group b is left: held counts zero
        assert_eq!(g[1]["held"], 0);
        assert_eq!(j["particle_steps"], 400);
        assert_eq!(j["particle_steps_per_s"], 200.0);
        assert_eq!(j["threads"], 2);
    }
}
