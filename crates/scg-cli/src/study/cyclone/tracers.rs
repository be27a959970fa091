//! The study's sanity check: fluid tracers (0.1 µm, τ ≈ 6·10⁻⁸ s ≪ dt) fed over the inlet
//! with the study's own models (wall function, dispersion, walls, collecting zones) must
//! behave as the air: leave through the outlet within 5·V/Q, with a mean residence time
//! of V/Q (V the vessel's volume, Q the inlet's flow: exact for a fluid tracer in a
//! steady, volume-conserving flow, the turbulence carrying it through recirculation too).
//! What they do instead measures what the set-up itself separates.

use scg_core::stages::feeder::FeedSource;
use serde::{Deserialize, Serialize};

use super::grade::wilson95;
use super::run::run_variant;

/// Tracer diameter, m.
pub const DIAMETER: f64 = 1e-7;

/// The tracers' fates and residence times.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TracerCheck {
    /// Tracer diameter, m.
    pub diameter: f64,
    /// Fed.
    pub fed: u64,
    /// Escaped through the outlet.
    pub escaped: u64,
    /// Of the escaped, those that left within 5·V/Q of their feed.
    pub within: u64,
    /// Collected in a collecting zone.
    pub collected: u64,
    /// Lost through the inlet.
    pub lost: u64,
    /// Still inside at the end.
    pub held: u64,
    /// V/Q: the mesh's volume over the inlet's flow (the feeder's patch), s.
    pub v_over_q: f64,
    /// Mean feed-to-escape time of the escaped, s.
    pub mean_residence: f64,
    /// Half-width of its 95 % interval (1.96 standard errors), s.
    pub mean_residence_95: f64,
    /// Wall time of the run, s.
    pub total_s: f64,
}

impl TracerCheck {
    /// Whether at least 98 % of the fed left within 5·V/Q.
    pub fn leave(&self) -> bool {
        self.within as f64 >= 0.98 * self.fed as f64
    }

    /// Mean residence over V/Q.
    pub fn ratio(&self) -> f64 {
        self.mean_residence / self.v_over_q
    }

    /// One paragraph for the report.
    pub fn text(&self) -> String {
        let pc = |k: u64| 100.0 * k as f64 / self.fed.max(1) as f64;
        let (clo, chi) = wilson95(self.collected, self.fed);
        let verdict = |ok: bool| if ok { "pass" } else { "FAIL" };
        format!(
            "tracer check ({:.1} µm, the study's models; V/Q = {:.3} s): fed {}; escaped {} \
             ({:.1} %; {:.1} % within 5·V/Q: {}), collected {} ({:.1} % [{:.1}, {:.1}]), held {}, \
             lost {}; mean residence of the escaped {:.3} ± {:.3} s = {:.3}·V/Q ({} within 5 %)\n",
            self.diameter * 1e6,
            self.v_over_q,
            self.fed,
            self.escaped,
            pc(self.escaped),
            pc(self.within),
            verdict(self.leave()),
            self.collected,
            pc(self.collected),
            100.0 * clo,
            100.0 * chi,
            self.held,
            self.lost,
            self.mean_residence,
            self.mean_residence_95,
            self.ratio(),
            verdict((self.ratio() - 1.0).abs() <= 0.05),
        )
    }
}

/// Run the tracer check on the cyclone scene `text` with the study's `set` overrides:
/// the first class becomes `rate` tracers per second over its feed window, weighted by
/// the inlet's flux (`weight = "flux"`: they enter with the air; the other classes are
/// not fed), run for the feed window and 5·V/Q after it.
pub fn run_tracers(text: &str, set: &[String], rate: f64) -> Result<TracerCheck, String> {
    let scene =
        scg_scene::parse(text, "<tracers>", "cyclone-tracers", set).map_err(|e| e.to_string())?;
    let m = scene
        .mesh_flow
        .as_ref()
        .ok_or("the tracer check needs a mesh flow")?;
    let f = scene
        .feeders
        .first()
        .ok_or("the tracer check needs a feeder")?;
    let FeedSource::Patch(inlet) = &f.source else {
        return Err("the tracer check needs a feeder on a patch (its Q)".into());
    };
    let volume: f64 = m.flow.geometry().cell_volumes.iter().sum();
    let v_over_q = volume / inlet.flux(&m.flow).inflow;
    let stop = f.window.1.min(scene.duration);
    let mut o = set.to_vec();
    o.push(format!("groups.0.diameter={DIAMETER:e}"));
    o.push(format!("feeders.0.rate={rate:e}"));
    // tracers enter with the air: V/Q is their mean residence only when fed by flux
    o.push("feeders.0.weight=\"flux\"".to_string());
    for i in 1..scene.feeders.len() {
        o.push(format!("feeders.{i}.rate=0"));
    }
    o.push(format!("duration={:e}", stop + 5.0 * v_over_q));
    let r = run_variant("tracers", text, &o, 0.0, None)?;
    let c = &r.classes[0];
    let t = &c.residence_times;
    let n = t.len() as f64;
    let mean = t.iter().sum::<f64>() / n;
    let sd = (t.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    Ok(TracerCheck {
        diameter: DIAMETER,
        fed: c.fed,
        escaped: c.escaped,
        within: t.iter().filter(|&&x| x <= 5.0 * v_over_q).count() as u64,
        collected: c.collected.unwrap_or(0),
        lost: c.lost,
        held: c.held,
        v_over_q,
        mean_residence: mean,
        mean_residence_95: 1.96 * sd / n.sqrt(),
        total_s: r.total_s,
    })
}
