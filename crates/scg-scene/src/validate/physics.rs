//! The vessel and the physics: `[material]`, `[contacts]`, `[flow]`, `[outlet]`
//! (`[[walls]]`: walls.rs).

use glam::DVec3;

use scg_core::physics::contact::tangential::TangentialStiffness;
use scg_core::physics::contact::{Material, NormalLaw};
use scg_core::physics::flow::{FlowField, Vortex, rpm_to_rad_per_s};
use scg_core::stages::contacts::ContactConfig;
use scg_core::stages::outlet::OutletGeometry;

use super::Ctx;
use crate::error::SceneError;
use crate::model::{FieldReader, Group, Outlet, SceneMeshFlow};
use crate::raw::{RawContacts, RawFlow, RawFlowKind, RawMaterial, RawNormalModel, RawOutlet};
use crate::raw::{RawInterpolation, RawTime};
use crate::raw::{RawWallFunction, RawWallFunctionModel};
use scg_core::physics::drag::DragLaw;
use scg_core::physics::flow::Fluid;
use scg_core::physics::mesh_flow::{MeshFlow, PatchRole, WallFunctionSpec};
use scg_core::physics::wall_function::{FrictionVelocity, LogLaw};
use scg_mesh::{
    Interpolation,
    foam::{self, TimeSel},
};

/// `[material]`: the contact material and the normal law it gives.
pub(super) fn material(m: &RawMaterial, cx: &Ctx) -> Result<(Material, NormalLaw), SceneError> {
    let mat = Material {
        youngs_modulus: cx.positive("material.youngs_modulus", m.youngs_modulus)?,
        poisson_ratio: cx.finite("material.poisson_ratio", m.poisson_ratio)?,
        restitution: cx.positive("material.restitution", m.restitution)?,
        friction: cx.non_negative("material.friction", m.friction)?,
    };
    if !(-1.0 < mat.poisson_ratio && mat.poisson_ratio < 0.5) {
        return Err(cx.err("material.poisson_ratio", "must lie in (−1, 0.5)"));
    }
    if mat.restitution > 1.0 {
        return Err(cx.err("material.restitution", "must lie in (0, 1]"));
    }
    let law = match m.normal_model {
        None | Some(RawNormalModel::Hertz) => NormalLaw::hertz(mat.restitution),
        Some(RawNormalModel::Linear) => {
            let k = cx.need("material.linear_stiffness", &m.linear_stiffness)?;
            NormalLaw::linear(
                cx.positive("material.linear_stiffness", k)?,
                mat.restitution,
            )
        }
    };
    Ok((mat, law))
}

/// Largest simulated (coarse-grained) diameter over the groups, m.
fn max_simulated_diameter(groups: &[Group]) -> f64 {
    groups
        .iter()
        .map(|g| {
            scg_core::physics::scaling::coarse_grain(g.law, g.alpha, g.max_diameter(), g.density)
                .diameter
        })
        .fold(0.0, f64::max)
}

/// `[contacts]`, with the material's contact law.
pub(super) fn contacts(
    c: &RawContacts,
    mat: Material,
    law: NormalLaw,
    groups: &[Group],
    cx: &Ctx,
) -> Result<ContactConfig, SceneError> {
    let dmax = max_simulated_diameter(groups);
    let skin = match c.skin {
        Some(s) => cx.positive("contacts.skin", s)?,
        None => 0.1 * dmax,
    };
    let rolling_friction = cx.non_negative("contacts.rolling_friction", c.rolling_friction)?;
    let periodic = match c.periodic {
        None => None,
        Some(l) => {
            for (a, x) in l.iter().enumerate() {
                cx.positive("contacts.periodic", *x)?;
                // Minimum image needs every cut-off below half the box.
                if *x < 2.0 * (dmax + skin) {
                    return Err(cx.err(
                        "contacts.periodic",
                        format!(
                            "box length {x} m along axis {a} is below 2·(d_max + skin) = {:.4e} m",
                            2.0 * (dmax + skin)
                        ),
                    ));
                }
            }
            Some(DVec3::from_array(l))
        }
    };
    let tangential_stiffness = match c.tangential_stiffness_ratio {
        None => TangentialStiffness::Mindlin,
        Some(r) => {
            TangentialStiffness::Ratio(cx.positive("contacts.tangential_stiffness_ratio", r)?)
        }
    };
    Ok(ContactConfig {
        law,
        material: mat,
        skin,
        periodic,
        rolling_friction,
        tangential_stiffness,
    })
}

/// `[flow]`.
pub(super) fn flow_field(f: &RawFlow, cx: &Ctx) -> Result<FlowField, SceneError> {
    let vortex = |cx: &Ctx| -> Result<Vortex, SceneError> {
        Ok(Vortex {
            center: cx.vec3("flow.center", f.center.unwrap_or([0.0; 3]))?,
            axis: cx.unit("flow.axis", f.axis.unwrap_or([0.0, 0.0, 1.0]))?,
            omega: rpm_to_rad_per_s(cx.finite("flow.rpm", cx.need("flow.rpm", &f.rpm)?)?),
            inflow_ratio: cx.finite("flow.inflow_ratio", f.inflow_ratio.unwrap_or(0.0))?,
        })
    };
    let mesh_kind = matches!(f.kind, RawFlowKind::Openfoam | RawFlowKind::Vtk);
    let analytic_keys = [
        ("flow.velocity", f.velocity.is_some()),
        ("flow.center", f.center.is_some()),
        ("flow.axis", f.axis.is_some()),
        ("flow.rpm", f.rpm.is_some()),
        ("flow.inflow_ratio", f.inflow_ratio.is_some()),
        ("flow.nozzle_radius", f.nozzle_radius.is_some()),
        ("flow.axial_speed", f.axial_speed.is_some()),
    ];
    let mesh_keys = [
        ("flow.case", f.case.is_some()),
        ("flow.file", f.file.is_some()),
        ("flow.time", f.time.is_some()),
        ("flow.series", f.series.is_some()),
        ("flow.field", f.field.is_some()),
        ("flow.interpolation", f.interpolation.is_some()),
        ("flow.scale", f.scale.is_some()),
        ("flow.translate", f.translate.is_some()),
        ("flow.patches", f.patches.is_some()),
        ("flow.sort_every", f.sort_every.is_some()),
        ("flow.wall_function", f.wall_function.is_some()),
    ];
    let (wrong, kinds) = if mesh_kind {
        (&analytic_keys[..], "still, uniform, vortex or classifier")
    } else {
        (&mesh_keys[..], "openfoam or vtk")
    };
    if let Some((k, _)) = wrong.iter().find(|(_, given)| *given) {
        return Err(cx.err(k, format!("is only used by flow.kind = {kinds}")));
    }
    Ok(match f.kind {
        RawFlowKind::Openfoam | RawFlowKind::Vtk => FlowField::Still,
        RawFlowKind::Still => FlowField::Still,
        RawFlowKind::Uniform => {
            FlowField::Uniform(cx.vec3("flow.velocity", cx.need("flow.velocity", &f.velocity)?)?)
        }
        RawFlowKind::Vortex => FlowField::Vortex(vortex(cx)?),
        RawFlowKind::Classifier => FlowField::Classifier {
            vortex: vortex(cx)?,
            nozzle_radius: cx.positive(
                "flow.nozzle_radius",
                cx.need("flow.nozzle_radius", &f.nozzle_radius)?,
            )?,
            axial_speed: cx.finite(
                "flow.axial_speed",
                cx.need("flow.axial_speed", &f.axial_speed)?,
            )?,
        },
    })
}

/// `[flow]` of kind `openfoam` or `vtk`: the mesh and the field, read once, placed
/// (x' = translate + scale·x, m), patch roles from `[flow.patches]`; `None` for the
/// analytic kinds. Errors name the key and carry the mesh reader's message (file, entry).
pub(super) fn mesh_flow(
    f: &RawFlow,
    fluid: Option<&Fluid>,
    rotors: &[scg_mesh::foam::MrfZone],
    cx: &Ctx,
) -> Result<Option<SceneMeshFlow>, SceneError> {
    let base = cx.base;
    let field = f.field.clone().unwrap_or_else(|| "U".to_string());
    if field.is_empty() {
        return Err(cx.err("flow.field", "must name a field"));
    }
    let scheme = match f.interpolation {
        None | Some(RawInterpolation::CellPoint) => Interpolation::CellPoint,
        Some(RawInterpolation::CellPointIdw) => Interpolation::CellPointIdw,
        Some(RawInterpolation::CellValue) => Interpolation::CellValue,
        // the former name of the default
        Some(RawInterpolation::CellPointLinearExact) => Interpolation::CellPoint,
        Some(RawInterpolation::Conservative) => Interpolation::Conservative,
    };
    let scale = cx.positive("flow.scale", f.scale.unwrap_or(1.0))?;
    let sort_every = match f.sort_every {
        None => scg_core::stages::mesh_flow::SORT_EVERY,
        Some(n) if n >= 0 => n as u64,
        Some(n) => return Err(cx.err("flow.sort_every", format!("must be ≥ 0, got {n}"))),
    };
    let translate = cx.vec3("flow.translate", f.translate.unwrap_or([0.0; 3]))?;
    let (mut mesh, mut cells, source, reader, window) = match f.kind {
        RawFlowKind::Openfoam => {
            let case = base.join(cx.need("flow.case", &f.case)?);
            let shown = case.display().to_string();
            if !case.is_dir() {
                return Err(cx.err("flow.case", format!("{shown}: no such case folder")));
            }
            // a series: its first snapshot here, the window's others below
            let window = match &f.series {
                Some(s) => {
                    super::series::no_time(f, cx)?;
                    Some(super::series::window(s, &case, &field, cx)?)
                }
                None => None,
            };
            let time = match &f.time {
                _ if window.is_some() => TimeSel::Time(window.as_ref().expect("some")[0].0),
                None => TimeSel::Latest,
                Some(RawTime::Name(n)) if n == "latest" => TimeSel::Latest,
                Some(RawTime::Name(n)) => match n.trim().parse::<f64>() {
                    Ok(t) if t.is_finite() => TimeSel::Time(t),
                    _ => {
                        return Err(cx.err(
                            "flow.time",
                            format!("must be \"latest\" or a time in s, got \"{n}\""),
                        ));
                    }
                },
                Some(RawTime::Number(t)) => TimeSel::Time(cx.finite("flow.time", *t)?),
            };
            let mesh =
                foam::read_mesh(&case).map_err(|e| cx.err("flow.case", format!("{shown}: {e}")))?;
            let dir = foam::select_time(&case, time)
                .map_err(|e| cx.err("flow.time", format!("{shown}: {e}")))?;
            let u = foam::read_vector_field(&case, &mesh, time, &field)
                .map_err(|e| cx.err("flow.field", format!("{shown}: field `{field}`: {e}")))?;
            let reader = FieldReader::Foam { case, time };
            let source = match &window {
                None => format!("{shown} (field from {})", dir.display()),
                Some(w) => format!(
                    "{shown} (series of {} snapshots, {} … {})",
                    w.len(),
                    dir.display(),
                    w[w.len() - 1].1.display()
                ),
            };
            (mesh, u, source, reader, window)
        }
        RawFlowKind::Vtk => {
            let file = base.join(cx.need("flow.file", &f.file)?);
            let shown = file.display().to_string();
            if !file.is_file() {
                return Err(cx.err("flow.file", format!("{shown}: no such file")));
            }
            // a ParaView collection (.pvd): a series, its first time step here
            let pvd = file
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("pvd"));
            let window = match (&f.series, pvd) {
                (Some(s), true) => Some(super::series::vtk_window(s, &file, cx)?),
                (None, true) => {
                    return Err(cx.err(
                        "flow.file",
                        format!(
                            "{shown}: a .pvd collection is a time series: give flow.series \
                             (`series = {{}}` for all its time steps) or name one of its files"
                        ),
                    ));
                }
                (Some(_), false) => {
                    return Err(cx.err(
                        "flow.series",
                        format!(
                            "{shown}: a VTK series is read from a ParaView collection (.pvd) \
                             listing its files, one per time step"
                        ),
                    ));
                }
                (None, false) => None,
            };
            let first = window.as_ref().map_or(file.clone(), |w| w[0].1.clone());
            let (mesh, u) = scg_mesh::vtk::read(&first, &field).map_err(|e| {
                cx.err(
                    "flow.file",
                    format!("{}: field `{field}`: {e}", first.display()),
                )
            })?;
            let source = match &window {
                None => shown,
                Some(w) => format!(
                    "{shown} (series of {} snapshots, {} … {})",
                    w.len(),
                    first.display(),
                    w[w.len() - 1].1.display()
                ),
            };
            (mesh, u, source, FieldReader::Vtk { file: first }, window)
        }
        _ => return Ok(None),
    };
    // a series reads its later snapshots with the mesh as the case gives it
    let read_mesh = window.as_ref().map(|_| std::sync::Arc::new(mesh.clone()));
    if scale != 1.0 || translate != DVec3::ZERO {
        for p in &mut mesh.points {
            *p = translate + scale * *p;
        }
    }
    let mesh_file = match f.kind {
        RawFlowKind::Vtk => f.file.clone().unwrap_or_default(),
        _ => f.case.clone().unwrap_or_default(),
    };
    let patches = f.patches.clone().unwrap_or_default();
    let mut roles = vec![PatchRole::Lost; mesh.patches.len()];
    for (key, names, role) in [
        ("flow.patches.walls", &patches.walls, PatchRole::Wall),
        ("flow.patches.outlets", &patches.outlets, PatchRole::Outlet),
        ("flow.patches.inlets", &patches.inlets, PatchRole::Inlet),
    ] {
        for name in names {
            let Some(i) = mesh.patches.iter().position(|p| &p.name == name) else {
                let known: Vec<&str> = mesh.patches.iter().map(|p| p.name.as_str()).collect();
                return Err(cx.err(
                    key,
                    format!(
                        "unknown patch `{name}` in {mesh_file}; the mesh has: {}",
                        known.join(", ")
                    ),
                ));
            };
            if roles[i] != PatchRole::Lost {
                return Err(cx.err(key, format!("patch `{name}` is given two roles")));
            }
            roles[i] = role;
        }
    }
    let key = if f.kind == RawFlowKind::Vtk {
        "flow.file"
    } else {
        "flow.case"
    };
    let wall = match &f.wall_function {
        None => None,
        Some(w) => wall_function(w, fluid, &mesh, &reader, cx)?,
    };
    if wall.is_some() && scheme == Interpolation::Conservative {
        let why = "cannot be combined with interpolation = \"conservative\": the log law \
                   would change the face fluxes the conservative field keeps (its wall \
                   tetrahedra slide along the wall already); remove one";
        return Err(cx.err("flow.wall_function", why));
    }
    let (moving, rotors) = match &reader {
        FieldReader::Foam { case, .. } => {
            super::mrf::rotor_faces(case, &mesh, &mut cells, rotors, cx)?
        }
        _ => (None, Vec::new()),
    };
    if window.is_some() && !rotors.is_empty() {
        return Err(cx.err(
            "flow.series",
            "cannot be combined with an MRF case's rotor zones yet (their face fluxes are \
             taken from one snapshot)",
        ));
    }
    if window.is_some()
        && let Some(w) = &wall
        && matches!(w.friction, FrictionVelocity::FromK(_))
    {
        return Err(cx.err(
            "flow.wall_function.k",
            "cannot be combined with flow.series yet (k is read from one snapshot); \
             leave it out for u_τ from the velocity",
        ));
    }
    let mut flow = MeshFlow::with_wall_function(mesh, &cells, scheme, roles, wall.as_ref())
        .map_err(|e| cx.err(key, format!("{source}: {e}")))?;
    if let Some(m) = moving {
        flow.set_moving_faces(m);
    }
    let flow = std::sync::Arc::new(flow);
    let series = match (window, &f.series, read_mesh) {
        (Some(steps), Some(s), Some(read_mesh)) => {
            let read = match &reader {
                FieldReader::Foam { case, .. } => {
                    let times = steps.iter().map(|(t, _)| *t).collect();
                    super::series::foam_read(case, &field, read_mesh, times)
                }
                FieldReader::Vtk { .. } => {
                    let files = steps.iter().map(|(_, f)| f.clone()).collect();
                    super::series::vtk_read(files, &field, read_mesh)
                }
            };
            Some(super::series::series(s, steps, read, &flow, wall, cx)?)
        }
        _ => None,
    };
    Ok(Some(SceneMeshFlow {
        flow,
        series,
        source,
        field,
        sort_every,
        reader: Some(reader),
        rotors,
    }))
}

/// `[flow.wall_function]`: `None` for `model = "none"`.
fn wall_function(
    w: &RawWallFunction,
    fluid: Option<&Fluid>,
    mesh: &scg_mesh::PolyMesh,
    reader: &FieldReader,
    cx: &Ctx,
) -> Result<Option<WallFunctionSpec>, SceneError> {
    if w.model == RawWallFunctionModel::None {
        for (k, given) in [
            ("k", w.k.is_some()),
            ("kappa", w.kappa.is_some()),
            ("e", w.e.is_some()),
            ("c_mu", w.c_mu.is_some()),
        ] {
            if given {
                return Err(cx.err(
                    &format!("flow.wall_function.{k}"),
                    "is only used by model = \"log_law\"",
                ));
            }
        }
        return Ok(None);
    }
    let Some(fluid) = fluid else {
        return Err(cx.err(
            "flow.wall_function",
            "the log law needs the fluid's viscosity: add a [fluid] table",
        ));
    };
    if fluid.density <= 0.0 {
        return Err(cx.err(
            "fluid.density",
            "the wall function needs ν = viscosity/density: the density must be > 0",
        ));
    }
    let d = LogLaw::default();
    let law = LogLaw {
        kappa: cx.positive("flow.wall_function.kappa", w.kappa.unwrap_or(d.kappa))?,
        e: cx.positive("flow.wall_function.e", w.e.unwrap_or(d.e))?,
        c_mu: cx.positive("flow.wall_function.c_mu", w.c_mu.unwrap_or(d.c_mu))?,
    };
    if law.e <= 1.0 {
        return Err(cx.err(
            "flow.wall_function.e",
            "must be > 1 (9.8 for a smooth wall)",
        ));
    }
    let friction = match &w.k {
        None => FrictionVelocity::FromVelocity,
        Some(name) if name.is_empty() => {
            return Err(cx.err("flow.wall_function.k", "must name a field"));
        }
        Some(name) => {
            let (shown, r) = match reader {
                FieldReader::Foam { case, time } => (
                    case.display().to_string(),
                    foam::read_scalar_field(case, mesh, *time, name),
                ),
                FieldReader::Vtk { file } => (
                    file.display().to_string(),
                    scg_mesh::vtk::read_scalar(file, name),
                ),
            };
            let k = r.map_err(|e| {
                cx.err(
                    "flow.wall_function.k",
                    format!("{shown}: field `{name}`: {e}"),
                )
            })?;
            k.check_non_negative(&shown, name, mesh)
                .map_err(|e| cx.err("flow.wall_function.k", format!("field `{name}`: {e}")))?;
            FrictionVelocity::FromK(k.cells)
        }
    };
    Ok(Some(WallFunctionSpec {
        law,
        nu: fluid.viscosity / fluid.density,
        friction,
    }))
}

/// `[outlet]` (its interval stays in seconds).
pub(super) fn outlet(o: &RawOutlet, cx: &Ctx) -> Result<Outlet, SceneError> {
    let interval = cx.non_negative("outlet.interval", o.interval.unwrap_or(0.0))?;
    let nozzle_radius = cx.positive("outlet.nozzle_radius", o.nozzle_radius)?;
    let domain_radius = cx.positive("outlet.domain_radius", o.domain_radius)?;
    let [h0, h1] = o.domain_height;
    let (h0, h1) = (
        cx.finite("outlet.domain_height", h0)?,
        cx.finite("outlet.domain_height", h1)?,
    );
    if h0 >= h1 {
        return Err(cx.err("outlet.domain_height", "must be [from, to] with from < to"));
    }
    let plane = cx.finite("outlet.plane", o.plane)?;
    if !(h0..=h1).contains(&plane) {
        return Err(cx.err("outlet.plane", "must lie inside domain_height"));
    }
    if nozzle_radius > domain_radius {
        return Err(cx.err("outlet.nozzle_radius", "must be ≤ domain_radius"));
    }
    Ok(Outlet {
        geometry: OutletGeometry {
            center: cx.vec3("outlet.center", o.center.unwrap_or([0.0; 3]))?,
            axis: cx.unit("outlet.axis", o.axis.unwrap_or([0.0, 0.0, 1.0]))?,
            nozzle_radius,
            plane,
            domain_radius,
            domain_height: (h0, h1),
        },
        interval,
    })
}

/// `[forces]`: each force is opt-in; every one acts through the fluid, so it needs
/// `[drag]` (with `[fluid]`).
pub(super) fn forces(
    raw: &crate::raw::RawScene,
    drag: Option<DragLaw>,
    cx: &Ctx,
) -> Result<scg_core::physics::forces::ExtraForces, SceneError> {
    let mut out = scg_core::physics::forces::ExtraForces {
        frame: super::frame::frame(raw, drag, cx)?,
        ..Default::default()
    };
    let Some(f) = &raw.forces else {
        return Ok(out);
    };
    if out.frame.is_some() {
        for (key, on) in [
            ("forces.added_mass", f.added_mass.is_some()),
            ("forces.pressure_gradient", f.pressure_gradient),
            ("forces.saffman_mei", f.saffman_mei),
            ("forces.rubinow_keller", f.rubinow_keller),
        ] {
            if on {
                return Err(cx.err(
                    key,
                    "not in a rotating [frame]: its fluid acceleration and vorticity would \
                     need the frame's terms (only cunningham goes with a frame)",
                ));
            }
        }
    }
    if let Some(c) = &f.cunningham {
        if drag.is_none() {
            return Err(cx.err(
                "forces.cunningham",
                "corrects the drag: the scene needs [fluid] and [drag]",
            ));
        }
        out.cunningham = Some(cx.positive("forces.cunningham.mean_free_path", c.mean_free_path)?);
    }
    for (key, on) in [
        ("forces.added_mass", f.added_mass.is_some()),
        ("forces.pressure_gradient", f.pressure_gradient),
        ("forces.saffman_mei", f.saffman_mei),
        ("forces.rubinow_keller", f.rubinow_keller),
    ] {
        if on && drag.is_none() {
            return Err(cx.err(
                key,
                "acts through the fluid: the scene needs [fluid] and [drag]",
            ));
        }
    }
    if let Some(c) = f.added_mass {
        out.added_mass = Some(cx.positive("forces.added_mass", c)?);
    }
    out.pressure_gradient = f.pressure_gradient;
    out.saffman_mei = f.saffman_mei;
    out.rubinow_keller = f.rubinow_keller;
    Ok(out)
}
