//! `scg check`: derived quantities per group and warnings where the model's assumptions
//! break. Also the `auto` time-step rule.

use glam::DVec3;

use scg_core::physics::contact::NormalLaw;
use scg_core::physics::contact::normal::{hertz_contact_time, linear_contact_time};
use scg_core::physics::drag::{DragLaw, particle_reynolds};
use scg_core::physics::flow::FlowField;
use scg_core::physics::integrate::Integrator;
use scg_core::physics::scaling::coarse_grain;
use scg_core::physics::wall_shape::WallShape;

use crate::model::{Allow, FeedSource};
use crate::{Placement, Scene};
use slip::{fluid_velocity, terminal_slip};

mod dispersion;
mod dt;
mod forces_at;
mod mesh;
mod overlaps;
mod render;
mod slip;
mod speeds;
mod zones;

pub use dt::auto_dt;
use mesh::mesh_flow_findings;
pub use overlaps::initial_overlaps;
pub use render::{render, tracker_records};
pub use speeds::{EXACT_DIFFERENCES, largest_difference, particle_contact_time};

/// Derived quantities of one group.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupReport {
    /// Group name.
    pub name: String,
    /// Law name.
    pub law: &'static str,
    /// α.
    pub alpha: f64,
    /// Particles at the start.
    pub count: usize,
    /// Simulated diameter, m.
    pub diameter: f64,
    /// Simulated density, kg/m³.
    pub density: f64,
    /// Stokes response time τ, s (∞ without drag).
    pub tau: f64,
    /// Estimated slip speed, m/s.
    pub slip: f64,
    /// Estimated particle Reynolds number.
    pub reynolds: f64,
    /// ρ_p/ρ_f (∞ without fluid).
    pub density_ratio: f64,
    /// Hertz contact time at the reference speed, s (with walls).
    pub contact_time: Option<f64>,
}

/// Severity of a finding.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// Information (e.g. warnings the scene allows).
    Note,
    /// The run goes on, but a model assumption breaks.
    Warning,
    /// The run would be meaningless; `scg run` refuses it.
    Error,
}

impl Level {
    /// Lower-case name, as printed.
    pub fn name(self) -> &'static str {
        match self {
            Level::Note => "note",
            Level::Warning => "warning",
            Level::Error => "error",
        }
    }
}

/// A warning or error about a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    /// Severity.
    pub level: Level,
    /// Message.
    pub message: String,
}

/// The whole check.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// Per group.
    pub groups: Vec<GroupReport>,
    /// Stokes number of paper eq. 1 (τ_v/τ_c), the whole scene.
    pub stokes_number: f64,
    /// Time step, s.
    pub dt: f64,
    /// Steps.
    pub steps: u64,
    /// Findings.
    pub findings: Vec<Finding>,
}

impl Report {
    /// Warning messages (for recordings).
    pub fn messages(&self) -> Vec<String> {
        self.findings
            .iter()
            .map(|f| format!("{}: {}", f.level.name(), f.message))
            .collect()
    }

    /// True when a finding is an error.
    pub fn has_errors(&self) -> bool {
        self.findings.iter().any(|f| f.level == Level::Error)
    }
}

/// Largest distance of a particle (or a cylinder wall) from a rotating flow's axis, m.
fn max_radius(scene: &Scene) -> f64 {
    let (FlowField::Vortex(v) | FlowField::Classifier { vortex: v, .. }) = scene.flow else {
        return 0.0;
    };
    let mut r: f64 = 0.0;
    for w in &scene.walls {
        if let WallShape::CylinderInside { radius, .. } = w.shape {
            r = r.max(radius);
        }
    }
    for f in &scene.feeders {
        if let FeedSource::Region(crate::Region::Cylinder { radius_max, .. }) = f.source {
            r = r.max(radius_max);
        }
    }
    for g in &scene.groups {
        match &g.placement {
            Placement::Explicit { positions, .. } => {
                for p in positions {
                    r = r.max(v.radial(*p).length());
                }
            }
            Placement::Random { region, .. } => {
                if let crate::Region::Cylinder { radius_max, .. } = region {
                    r = r.max(*radius_max);
                }
            }
        }
    }
    r
}

/// Representative (position, velocity) pairs of a group: its initial particles and the
/// centres of the regions its feeders feed, with the feeding velocity.
fn group_velocities(scene: &Scene, g: &crate::Group) -> Vec<(DVec3, DVec3)> {
    let mut out = placement_velocities(g);
    for f in &scene.feeders {
        if scene.groups[f.group].name == g.name {
            let c = match &f.source {
                FeedSource::Region(crate::Region::Box { min, max }) => 0.5 * (*min + *max),
                FeedSource::Region(crate::Region::Cylinder {
                    center,
                    axis,
                    radius_max,
                    height,
                    ..
                }) => {
                    *center
                        + *axis * (0.5 * (height.0 + height.1))
                        + *radius_max * axis.any_orthonormal_vector()
                }
                FeedSource::Patch(p) => {
                    p.faces().iter().map(|f| f.centre * f.area).sum::<DVec3>() / p.area()
                }
            };
            let given = match (&f.source, &scene.mesh_flow) {
                (FeedSource::Patch(p), Some(m)) if f.field_velocity => {
                    p.flux(&m.flow).mean_velocity
                }
                _ => f.velocity,
            };
            let swirl = scene.flow.vortex().map_or(DVec3::ZERO, |v| {
                (v.axis * (v.omega * f.swirl)).cross(c - v.center)
            });
            out.push((c, given + swirl));
        }
    }
    out
}

/// Particles of group `gi` fed over the whole run (0 without feeders).
pub fn fed_count(scene: &Scene, gi: usize) -> f64 {
    scene
        .feeders
        .iter()
        .filter(|f| f.group == gi)
        .map(|f| f.rate * (scene.duration.min(f.window.1) - f.window.0).max(0.0))
        .sum()
}

/// Largest fluid speed inside the vessel (rotating flows), m/s.
fn max_flow_speed(scene: &Scene) -> f64 {
    match scene.flow {
        FlowField::Vortex(v) => {
            v.omega.abs() * max_radius(scene) * (1.0 + v.inflow_ratio.powi(2)).sqrt()
        }
        FlowField::Classifier {
            vortex: v,
            axial_speed,
            ..
        } => {
            v.omega.abs() * max_radius(scene) * (1.0 + v.inflow_ratio.powi(2)).sqrt()
                + axial_speed.abs()
        }
        _ => f64::INFINITY,
    }
}

fn placement_velocities(g: &crate::Group) -> Vec<(DVec3, DVec3)> {
    match &g.placement {
        Placement::Explicit {
            positions,
            velocities,
        } => positions
            .iter()
            .copied()
            .zip(velocities.iter().copied())
            .collect(),
        Placement::Random {
            velocity, region, ..
        } => {
            let c = match region {
                crate::Region::Box { min, max } => 0.5 * (*min + *max),
                crate::Region::Cylinder { center, .. } => *center,
            };
            vec![(c, *velocity)]
        }
    }
}

/// Impact speed known before the run, m/s: the fastest initial or feeding velocity of the
/// group (with the feeder's swirl), or its settling speed τ·g (at most 10 m/s). The flow
/// speed is not used: measured in the shipped cases, particles meet walls and each other
/// far slower than the fluid moves (a vortex carries them along the wall, and the inflow
/// pushes them off it), and the run measures every contact's approach speed itself
/// ([`scg_core::sim::Resolved`]). `None` when nothing is known (particles at rest in the
/// flow, no gravity).
fn known_speed(scene: &Scene, tau: f64, g: &crate::Group) -> Option<f64> {
    let mut v: f64 = 0.0;
    for (_, u) in group_velocities(scene, g) {
        v = v.max(u.length());
    }
    if let Some(gr) = scene.gravity {
        v = v.max((gr.length() * tau.min(1.0)).min(10.0));
    }
    (v > 0.0).then_some(v)
}

fn contact_time(scene: &Scene, d: f64, rho: f64, v: f64) -> Option<f64> {
    let mat = scene.material?;
    let m = scg_core::physics::scaling::sphere_mass(d, rho);
    let e_eff = mat.effective_modulus();
    match scene.normal_law? {
        // Wall contact: R* = d/2, m* = m.
        NormalLaw::Hertz { .. } => Some(hertz_contact_time(m, 0.5 * d, e_eff, v)),
        NormalLaw::Linear { stiffness, zeta } => Some(linear_contact_time(m, stiffness, zeta)),
    }
}

/// A group's report; a size bin's at its smallest size (the fastest response to the air
/// and the shortest contact, which bound the time step).
fn group_report(scene: &Scene, g: &crate::Group) -> GroupReport {
    let s = coarse_grain(g.law, g.alpha, g.min_diameter(), g.density);
    let (tau, slip, re, ratio) = match (scene.fluid, scene.drag) {
        (Some(f), Some(_)) => {
            // τ as the spawn sets it (the slip correction and added mass included)
            let cg = scg_core::components::CoarseGrain {
                alpha: g.alpha,
                law: g.law,
                original_diameter: g.min_diameter(),
                original_density: g.density,
            };
            let as_original =
                scene.scg_at_original && g.law == scg_core::physics::scaling::CoarseGrainLaw::Scg;
            let tau = scg_core::spawn::coarse_grained(
                &cg,
                Some(&f),
                scene.dt.max(f64::MIN_POSITIVE),
                as_original,
                &scene.extra_forces,
            )
            .3
            .tau;
            let law = scene.drag.unwrap_or_default();
            let mut slip: f64 = 0.0;
            for (x, v) in group_velocities(scene, g) {
                slip = slip.max((fluid_velocity(scene, x) - v).length());
            }
            let omega = match scene.flow {
                FlowField::Vortex(v) | FlowField::Classifier { vortex: v, .. } => v.omega.abs(),
                _ => 0.0,
            };
            // The terminal slips under the drag law: the centrifugal drift at the largest
            // radius (at most the largest fluid speed: a particle cannot slip faster than the
            // flow that drives it), and settling.
            let terminal = |a: f64| terminal_slip(law, tau, a, s.drag_diameter, f);
            slip = slip.max(terminal(omega * omega * max_radius(scene)).min(max_flow_speed(scene)));
            if let Some(gr) = scene.gravity {
                slip = slip.max(terminal(gr.length()));
            }
            let re = particle_reynolds(s.drag_diameter, slip, f.density, f.viscosity);
            (tau, slip, re, s.density / f.density)
        }
        (Some(f), None) => (f64::INFINITY, 0.0, 0.0, s.density / f.density),
        _ => (f64::INFINITY, 0.0, 0.0, f64::INFINITY),
    };
    let contact_time = scene
        .contact_walls()
        .next()
        .is_some()
        .then(|| known_speed(scene, tau, g))
        .flatten()
        .and_then(|v| contact_time(scene, s.diameter, s.density, v));
    GroupReport {
        name: g.name.clone(),
        law: g.law.name(),
        alpha: g.alpha,
        count: g.count(),
        diameter: s.diameter,
        density: s.density,
        tau,
        slip,
        reynolds: re,
        density_ratio: ratio,
        contact_time,
    }
}

/// Stokes number of paper eq. 1: St = 4√π·n·ρ_p·d̄⁴·|u_r| / (18·μ), with n the number
/// density over the vessel (or the particles' bounding box) and group means. A fed group
/// counts the particles fed over the whole run (an upper bound of those resident).
pub fn stokes_number(scene: &Scene, reports: &[GroupReport]) -> f64 {
    let Some(f) = scene.fluid else { return 0.0 };
    let counts: Vec<f64> = reports
        .iter()
        .enumerate()
        .map(|(i, r)| r.count as f64 + fed_count(scene, i))
        .collect();
    let n_total: f64 = counts.iter().sum();
    if n_total <= 0.0 {
        return 0.0;
    }
    let w = |sel: &dyn Fn(&GroupReport) -> f64| -> f64 {
        reports
            .iter()
            .zip(&counts)
            .map(|(r, c)| sel(r) * c)
            .sum::<f64>()
            / n_total
    };
    let d = w(&|r| r.diameter);
    let rho = w(&|r| r.density);
    let ur = w(&|r| r.slip);
    let mut volume = None;
    for wall in &scene.walls {
        if let WallShape::CylinderInside {
            radius,
            extent: Some((a, b)),
            ..
        } = wall.shape
        {
            volume = Some(std::f64::consts::PI * radius * radius * (b - a));
        }
    }
    let volume = volume.unwrap_or_else(|| scene.extent().powi(3));
    let n = n_total / volume;
    4.0 * std::f64::consts::PI.sqrt() * n * rho * d.powi(4) * ur / (18.0 * f.viscosity)
}

/// α from which `scg check` calls coarse graining extreme.
pub const EXTREME_ALPHA: f64 = 16.0;

/// A warning `m` with the allowance `code`: counted in `allowed` when the scene accepts
/// it (`[checks] allow`), else kept in `findings`.
fn warn_or_allow(
    scene: &Scene,
    findings: &mut Vec<Finding>,
    allowed: &mut Vec<(Allow, usize)>,
    code: Option<Allow>,
    m: String,
) {
    match code {
        Some(c) if scene.allow.contains(&c) => match allowed.iter_mut().find(|a| a.0 == c) {
            Some(a) => a.1 += 1,
            None => allowed.push((c, 1)),
        },
        _ => findings.push(Finding {
            level: Level::Warning,
            message: m,
        }),
    }
}

/// Check a scene.
pub fn check(scene: &Scene) -> Report {
    let groups: Vec<GroupReport> = scene
        .groups
        .iter()
        .map(|g| group_report(scene, g))
        .collect();
    let mut findings = Vec::new();
    let mut allowed: Vec<(Allow, usize)> = Vec::new();
    let mut warn_unless =
        |code: Option<Allow>, m: String| warn_or_allow(scene, &mut findings, &mut allowed, code, m);
    for r in &groups {
        if scene.drag == Some(DragLaw::Stokes) && r.reynolds > 0.1 {
            warn_unless(
                Some(Allow::StokesReynolds),
                format!(
                    "group `{}`: particle Reynolds number ≈ {:.3} > 0.1, outside Stokes drag (C_d = 24/Re) validity",
                    r.name, r.reynolds
                ),
            );
        }
        if scene.drag == Some(DragLaw::SchillerNaumann) && r.reynolds > 1000.0 {
            warn_unless(
                None,
                format!(
                    "group `{}`: particle Reynolds number ≈ {:.0} > 1000, outside Schiller–Naumann drag validity (C_d ≈ 0.44 beyond)",
                    r.name, r.reynolds
                ),
            );
        }
        if r.alpha >= EXTREME_ALPHA {
            warn_unless(
                None,
                format!(
                    "group `{}`: α = {} is extreme coarse graining: one particle stands for {:.0} originals and is {} m across; check that it still resolves the flow and the walls",
                    r.name,
                    r.alpha,
                    r.alpha.powi(3),
                    r.diameter
                ),
            );
        }
        if r.density_ratio < 1.0 {
            warn_unless(
                None,
                format!(
                    "group `{}`: simulated density {:.4} kg/m³ is below the fluid's ({:.4} kg/m³): the particle would float; buoyancy, added mass and pressure forces dominate and are not modelled",
                    r.name,
                    r.density,
                    r.density / r.density_ratio
                ),
            );
        } else if r.density_ratio < 10.0 {
            warn_unless(
                Some(Allow::LightParticles),
                format!(
                    "group `{}`: simulated density {:.4} kg/m³ is only {:.2}× the fluid's; added mass, buoyancy and pressure forces are not negligible",
                    r.name, r.density, r.density_ratio
                ),
            );
        }
        if scene.integrator == Integrator::Explicit && r.tau.is_finite() && scene.dt > 0.5 * r.tau {
            warn_unless(
                None,
                format!(
                    "group `{}`: explicit integrator with dt = {:.3e} s > τ/2 = {:.3e} s; the run sub-steps it {} times per step",
                    r.name,
                    scene.dt,
                    0.5 * r.tau,
                    scg_core::physics::integrate::explicit_substeps(r.tau, scene.dt)
                ),
            );
        }
        if let Some(tc) = r.contact_time
            && scene.dt > tc / 20.0
        {
            warn_unless(
                None,
                format!(
                    "group `{}`: dt = {:.3e} s gives {:.1} steps per wall contact (t_c ≈ {:.3e} s); at least 20 are needed",
                    r.name,
                    scene.dt,
                    tc / scene.dt,
                    tc
                ),
            );
        }
    }
    if let Some(tc) = particle_contact_time(scene)
        && scene.dt > tc / 20.0
    {
        warn_unless(
            None,
            format!(
                "dt = {:.3e} s gives {:.1} steps per particle–particle contact (t_c ≈ {:.3e} s); at least 20 are needed",
                scene.dt,
                tc / scene.dt,
                tc
            ),
        );
    }
    if scene.contacts.is_some() {
        for (a, b, frac) in initial_overlaps(scene) {
            warn_unless(
                None,
                format!(
                    "particles {a} and {b} start overlapping by {:.1} % of the smaller diameter; the contact turns its elastic energy into separation speed (bounded by that energy, not capped further)",
                    100.0 * frac
                ),
            );
        }
    }
    let st = stokes_number(scene, &groups);
    if st >= 100.0 {
        warn_unless(
            None,
            format!(
                "Stokes number of eq. 1 ≈ {st:.3e} ≥ 100: a dense system, collisions dominate and the SCG model's dilute assumption breaks"
            ),
        );
    }
    // Particles that start outside a wall.
    for (gi, g) in scene.groups.iter().enumerate() {
        if let Placement::Explicit { positions, .. } = &g.placement {
            let radius = 0.5 * coarse_grain(g.law, g.alpha, g.diameter, g.density).diameter;
            for (pi, p) in positions.iter().enumerate() {
                for w in scene.contact_walls() {
                    if let Some(t) = w.shape.touch(*p, radius)
                        && w.shape.contains(*p)
                    {
                        findings.push(Finding {
                            level: Level::Warning,
                            message: format!(
                                "groups[{gi}] (`{}`) particle {pi} starts overlapping wall `{}` by {:.1} % of its radius; the wall pushes it off (force capped at an overlap of one radius)",
                                g.name,
                                w.name,
                                100.0 * t.overlap / radius
                            ),
                        });
                    }
                    if !w.shape.contains(*p) {
                        findings.push(Finding {
                            level: Level::Error,
                            message: format!(
                                "groups[{gi}] (`{}`) particle {pi} at {:?} starts outside wall `{}`",
                                g.name,
                                p.to_array(),
                                w.name
                            ),
                        });
                    }
                }
            }
        }
    }
    findings.extend(forces_at::findings(scene, &groups));
    findings.extend(zones::findings(scene));
    findings.extend(mesh_flow_findings(scene));
    for f in mesh::series_findings(scene, &groups) {
        match f.level {
            Level::Warning => warn_or_allow(
                scene,
                &mut findings,
                &mut allowed,
                Some(Allow::SeriesSpacing),
                f.message,
            ),
            _ => findings.push(f),
        }
    }
    findings.extend(dispersion::findings(scene));
    for (code, n) in allowed {
        findings.push(Finding {
            level: Level::Note,
            message: format!(
                "{n} `{}` warning(s) allowed by the scene ([checks] allow)",
                code.name()
            ),
        });
    }
    Report {
        groups,
        stokes_number: st,
        dt: scene.dt,
        steps: scene.steps(),
        findings,
    }
}
