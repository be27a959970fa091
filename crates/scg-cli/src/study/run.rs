//! Running one variant of a study: the simulation with the analysis attached, timed.

use std::path::Path;
use std::time::Instant;

use scg_core::stages::outlet::OutletLog;

use crate::analysis::{self, Analysis, Params, SharedAnalysis};

/// One variant's run.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct VariantRun {
    /// Variant name.
    pub name: String,
    /// The analysis.
    pub result: analysis::Result,
    /// Wall time of the last 0.1 s of the window, s.
    pub time_s: f64,
    /// Wall time of the whole run, s.
    pub total_s: f64,
    /// Particles drained, per class (outlet log).
    pub drained: Vec<usize>,
    /// Particles lost (left the domain elsewhere), per class.
    pub lost: Vec<usize>,
    /// Particles resident at the end.
    pub resident: usize,
    /// Simulated particles fed.
    pub fed: Vec<u64>,
}

/// Run one variant of `text` with `overrides`; record to `mcap` when given.
pub fn run_variant(
    name: &str,
    text: &str,
    overrides: &[String],
    window: (f64, f64),
    mcap: Option<&Path>,
) -> Result<VariantRun, String> {
    let scene =
        scg_scene::parse(text, &format!("<{name}>"), name, overrides).map_err(|e| e.to_string())?;
    let params = Params::for_scene(&scene, window.0, window.1);
    let mut sim = scene.build(true);
    let meta = scene.run_meta(scg_scene::check::check(&scene).messages());
    let analysis = SharedAnalysis::attach(&mut sim, Analysis::new(&meta, &scene.flow, params));
    if let Some(p) = mcap {
        let sink = scg_record::McapSink::create(p, &meta).map_err(|e| e.to_string())?;
        sim.add_recorder(Box::new(sink));
    }
    let steps = scene.steps();
    let timed_from = (((window.1 - 0.1).max(0.0)) / scene.dt).round() as u64;
    let timed_from = timed_from.min(steps);
    let t0 = Instant::now();
    sim.record_now().map_err(|e| e.to_string())?;
    sim.run(timed_from, |_| true).map_err(|e| e.to_string())?;
    let t1 = Instant::now();
    sim.run(steps - timed_from, |_| true)
        .map_err(|e| e.to_string())?;
    let time_s = t1.elapsed().as_secs_f64();
    let total_s = t0.elapsed().as_secs_f64();
    sim.finish_recorders().map_err(|e| e.to_string())?;
    let log = sim.world.resource::<OutletLog>().clone();
    let fed = sim.world.resource::<scg_core::state::Tally>().fed.clone();
    let resident = sim.particles().len();
    let result = analysis.result()?;
    Ok(VariantRun {
        name: name.to_string(),
        result,
        time_s,
        total_s,
        drained: log.drained.iter().map(Vec::len).collect(),
        lost: log.lost.iter().map(Vec::len).collect(),
        resident,
        fed,
    })
}
