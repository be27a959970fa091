//! The `scg check` report as text.

use super::Report;
use crate::{DtChoice, Scene};

/// Render the report as text.
pub fn render(scene: &Scene, r: &Report) -> String {
    let mut s = format!(
        "scene `{}` ({}): {} steps of dt = {:.4e} s ({}), duration {} s, integrator {}\n",
        scene.name,
        scene.file,
        r.steps,
        r.dt,
        match scene.dt_choice {
            DtChoice::Auto => "auto",
            DtChoice::Fixed => "fixed",
        },
        scene.duration,
        scene.integrator.name()
    );
    s.push_str(&format!(
        "{:<16} {:>6} {:>4} {:>8} {:>11} {:>11} {:>11} {:>10} {:>10} {:>10}\n",
        "group", "law", "α", "count", "d [m]", "ρ [kg/m³]", "τ [s]", "slip[m/s]", "Re_p", "ρ/ρ_f"
    ));
    for g in &r.groups {
        s.push_str(&format!(
            "{:<16} {:>6} {:>4} {:>8} {:>11.4e} {:>11.5} {:>11.4e} {:>10.3e} {:>10.3e} {:>10.4}\n",
            g.name,
            g.law,
            g.alpha,
            g.count,
            g.diameter,
            g.density,
            g.tau,
            g.slip,
            g.reynolds,
            g.density_ratio
        ));
    }
    s.push_str(&time_scales(scene, r));
    for (i, f) in scene.feeders.iter().enumerate() {
        let g = &scene.groups[f.group];
        let name = match &g.size {
            None => format!("`{}`", g.name),
            Some(b) => format!(
                "`{}` ({} bins by size: `{}`, …)",
                b.parent,
                b.edges.len() - 1,
                g.name
            ),
        };
        let represented = g.density * g.fed_volume();
        s.push_str(&format!(
            "feeders[{i}] → {}: {:.6e} simulated particles/s ({:.6e} kg/s of the original powder, {} originals each), from {} s to {}\n",
            name,
            f.rate,
            f.rate * represented,
            g.alpha.powi(3),
            f.window.0,
            if f.window.1 >= f64::MAX / 2.0 {
                "the end".to_string()
            } else {
                format!("{} s", f.window.1)
            }
        ));
    }
    for w in &scene.impulse_walls {
        use scg_core::physics::mesh_flow::PatchInteraction;
        s.push_str(&format!(
            "wall `{}`: {}\n",
            w.wall.name,
            match w.model {
                PatchInteraction::Rebound { e, mu, friction } => format!(
                    "rebound as an impulse, restitution e = {e}, {} (no contact law)",
                    friction_text(mu, friction)
                ),
                PatchInteraction::Stick => "stick (particles touching it deposit)".into(),
                PatchInteraction::Escape => "escape (particles touching it leave)".into(),
            }
        ));
        if let scg_core::physics::wall_shape::WallShape::Mesh(m) = &w.wall.shape {
            s.push_str(&mesh_line(&w.wall.name, m));
        }
    }
    for w in &scene.walls {
        if let scg_core::physics::wall_shape::WallShape::Mesh(m) = &w.shape {
            s.push_str(&mesh_line(&w.name, m));
        }
    }
    for w in scene
        .walls
        .iter()
        .chain(scene.impulse_walls.iter().map(|w| &w.wall))
    {
        let m = &w.motion;
        if !m.is_fixed() {
            let rate = m.angular_velocity.length();
            s.push_str(&format!(
                "wall `{}` moves: velocity {:?} m/s, angular velocity {:?} rad/s ({:.4} rpm) \
                 about {:?} m at t = 0\n",
                w.name,
                m.velocity.to_array(),
                m.angular_velocity.to_array(),
                scg_core::physics::flow::rad_per_s_to_rpm(rate),
                m.centre.to_array()
            ));
        }
    }
    if let Some(m) = &scene.mesh_flow {
        s.push_str(&mesh_flow_lines(
            m,
            scene.patch_walls.as_ref(),
            &scene.patch_models,
        ));
        s.push_str(&inlet_lines(scene, m));
    }
    s.push_str(&format!(
        "Stokes number (paper eq. 1): {:.4e}\n",
        r.stokes_number
    ));
    if r.findings.is_empty() {
        s.push_str("no warnings\n");
    }
    for m in r.messages() {
        s.push_str(&m);
        s.push('\n');
    }
    s
}

/// One line describing a mesh wall.
fn mesh_line(name: &str, m: &scg_core::physics::trimesh::TriMesh) -> String {
    let (lo, hi) = m.bounds();
    let (h, dims) = m.grid_shape();
    let f = |v: glam::DVec3| format!("[{:.6e}, {:.6e}, {:.6e}]", v.x, v.y, v.z);
    format!(
        "wall `{name}`: mesh of {} triangles, {} vertices, {} edges, {}, {} flat regions, {} feature edges, bounds {} to {} m, bin grid {}×{}×{} cells of {:.4e} m\n",
        m.triangle_count(),
        m.vertex_count(),
        m.edge_count(),
        if m.is_closed() { "closed" } else { "open" },
        m.region_count(),
        m.feature_edges().len(),
        f(lo),
        f(hi),
        dims[0],
        dims[1],
        dims[2],
        h
    )
}

/// The lines describing a flow on a mesh: sizes, bounds, patches with their roles, field
/// speeds.
fn mesh_flow_lines(
    m: &crate::model::SceneMeshFlow,
    walls: Option<&crate::PatchWalls>,
    models: &[crate::model::PatchModel],
) -> String {
    let f = &m.flow;
    let mesh = f.mesh();
    let [lo, hi] = f.geometry().bounds();
    let v = |v: glam::DVec3| format!("[{:.6e}, {:.6e}, {:.6e}]", v.x, v.y, v.z);
    let (umin, umax) = f.field_speed();
    let mut s = format!(
        "flow mesh {}: {} cells, volume {:.6e} m³, {} faces ({} internal), {} points, bounds {} to {} m, field `{}` ({:?}), speed {:.4e} to {:.4e} m/s\n",
        m.source,
        mesh.n_cells,
        f.geometry().cell_volumes.iter().sum::<f64>(),
        mesh.n_faces(),
        mesh.n_internal_faces(),
        mesh.points.len(),
        v(lo),
        v(hi),
        m.field,
        f.scheme(),
        umin,
        umax
    );
    s.push_str(&format!("  {}\n", tracker_records(f)));
    if let Some(p) = f.projection() {
        s.push_str(&format!(
            "  conservative interpolation: the cell field's face fluxes (linear between cells) were out of balance by Σ_cells |Σ_f φ| = {:.4e} m³/s, {:.4e} after the projection ({} conjugate-gradient iterations); it changed the faces' normal velocity by {:.4e} m/s on average (area-weighted), {:.4e} at most; {:.6e} m³/s in through the fixed-flux patches, {:.6e} out through the outlets (before: {:.6e}){}\n",
            p.imbalance_before,
            p.imbalance_after,
            p.iterations,
            p.mean_change,
            p.max_change,
            p.inflow,
            p.outflow_after,
            p.outflow_before,
            if p.unbalanced_cells > 0 {
                format!(
                    "; {} cells with degenerate tetrahedra keep their cell value (not conservative there)",
                    p.unbalanced_cells
                )
            } else {
                String::new()
            }
        ));
    }
    use scg_core::physics::mesh_flow::PatchInteraction;
    for (i, (p, role)) in mesh.patches.iter().zip(f.roles()).enumerate() {
        let model = models.get(i);
        let what = match model {
            Some(pm) if pm.contact => format!(
                "{}: contact wall with {} triangles (the [material] contact law; a rebound of the centre with e = {} only as a guard)",
                role.name(),
                walls
                    .and_then(|w| w.per_patch.iter().find(|(k, _)| *k == i))
                    .map_or(0, |(_, n)| *n),
                match pm.interaction {
                    PatchInteraction::Rebound { e, .. } => e,
                    _ => 1.0,
                }
            ),
            Some(pm) => match pm.interaction {
                PatchInteraction::Rebound { e, mu, friction } => format!(
                    "{}: rebound of the centre as an impulse, restitution e = {e}, {}",
                    role.name(),
                    friction_text(mu, friction)
                ),
                PatchInteraction::Stick => {
                    format!("{}: stick (particles reaching it deposit)", role.name())
                }
                PatchInteraction::Escape => {
                    format!("{}: escape (particles reaching it leave)", role.name())
                }
            },
            None => role.name().to_string(),
        };
        s.push_str(&format!(
            "  patch `{}` ({}): {} faces, {what}\n",
            p.name, p.kind, p.size,
        ));
    }
    for z in &m.rotors {
        let w = z.omega.length();
        let faces: Vec<String> = z
            .faces
            .iter()
            .map(|(p, n)| format!("{n} of `{p}`"))
            .collect();
        s.push_str(&format!(
            "  frozen-rotor (MRF) zone `{}`: cellZone `{}` ({} cells) turns at {w:.6e} rad/s \
             ({:.4} rpm) about {:?} through {:?}; its boundary faces ({}) move at Ω×r (their \
             field values set so, as OpenFOAM's MRF does; particles rebound relative to \
             them); the geometry stays (the frozen rotor's assumption)\n",
            z.name,
            z.cell_zone,
            z.cells,
            w * 60.0 / std::f64::consts::TAU,
            (z.omega / w).to_array(),
            z.origin.to_array(),
            if faces.is_empty() {
                "none".to_string()
            } else {
                faces.join(", ")
            }
        ));
    }
    if let Some(w) = walls
        && let scg_core::physics::wall_shape::WallShape::Mesh(t) = &w.wall.shape
    {
        s.push_str("  ");
        s.push_str(&mesh_line(&w.wall.name, t));
    }
    s
}

/// One line per patch feeder: the patch, its area, the mean field velocity over it and
/// the flow rate through it.
fn inlet_lines(scene: &Scene, m: &crate::model::SceneMeshFlow) -> String {
    let mut s = String::new();
    let imbalance = if scene
        .feeders
        .iter()
        .any(|f| matches!(f.source, crate::model::FeedSource::Patch(_)))
    {
        m.flow.cell_imbalance()
    } else {
        0.0
    };
    for (i, f) in scene.feeders.iter().enumerate() {
        let crate::model::FeedSource::Patch(p) = &f.source else {
            continue;
        };
        let q = p.flux(&m.flow);
        let u = q.mean_velocity;
        let volume: f64 = m.flow.geometry().cell_volumes.iter().sum();
        s.push_str(&format!(
            "  feeders[{i}] on patch `{}`: area {:.6e} m², mean field velocity [{:.6e}, {:.6e}, {:.6e}] m/s, inflow Q = ∫u·n_in dA = {:.6e} m³/s (mean normal speed {:.6e} m/s; the mesh's volume over it, V/Q = {:.4e} s, is a fluid tracer's mean residence time when the field conserves volume: the cells' imbalance is {:.3}·Q), velocity {}\n",
            p.name,
            q.area,
            u.x,
            u.y,
            u.z,
            q.inflow,
            q.inflow / q.area,
            volume / q.inflow,
            0.5 * imbalance / q.inflow,
            if f.field_velocity {
                "from the field".to_string()
            } else {
                format!("{:?} m/s", f.velocity.to_array())
            }
        ));
    }
    s
}

/// The time scales dt is measured against: the drag time (the shortest τ) and the contact
/// times of the Hertz contacts in the scene, or that there are none.
fn time_scales(scene: &Scene, r: &Report) -> String {
    let tau = r.groups.iter().map(|g| g.tau).fold(f64::INFINITY, f64::min);
    let mut s = String::from("time scales: ");
    if tau.is_finite() {
        s += &format!("drag τ_min = {tau:.4e} s (dt/τ = {:.3})", r.dt / tau);
    } else {
        s += "no drag";
    }
    let tc = r
        .groups
        .iter()
        .filter_map(|g| g.contact_time)
        .fold(f64::INFINITY, f64::min);
    let pair = super::particle_contact_time(scene);
    match (tc.is_finite(), pair) {
        (false, None) => {
            s += "; no Hertz contact in the scene (walls rebound, stick or escape as impulses): dt follows the drag"
        }
        _ => {
            if tc.is_finite() {
                s += &format!("; wall contact t_c = {tc:.4e} s ({:.1} steps)", tc / r.dt);
            }
            if let Some(t) = pair {
                s += &format!("; particle contact t_c = {t:.4e} s ({:.1} steps)", t / r.dt);
            }
        }
    }
    s.push('\n');
    s
}

/// A rebound's friction in words: the coefficient and what it does.
fn friction_text(mu: f64, friction: scg_core::physics::patch_interaction::WallFriction) -> String {
    use scg_core::physics::patch_interaction::WallFriction;
    match friction {
        WallFriction::Coulomb => format!("Coulomb friction μ = {mu}"),
        WallFriction::OpenfoamFraction => format!(
            "OpenFOAM's rebound friction μ = {mu} (the fraction μ of the tangential velocity removed)"
        ),
    }
}

/// What the tracker's per-cell records of `flow` take (`scg_mesh::CellTable`), or that it
/// has none and why (`scg check`, `scg bench mesh`).
pub fn tracker_records(flow: &scg_core::physics::mesh_flow::MeshFlow) -> String {
    match flow.table() {
        Some(t) => format!(
            "tracker records {:.1} MB ({:.2} kB per cell)",
            t.bytes() as f64 / 1e6,
            t.bytes() as f64 / 1e3 / flow.mesh().n_cells.max(1) as f64
        ),
        None => format!(
            "no tracker records (they would exceed {} GiB, or the memory was refused): particles are located by walking the mesh, several times slower",
            scg_mesh::CellTable::MAX_BYTES >> 30
        ),
    }
}
