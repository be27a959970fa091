//! `[dispersion]`: the model, and the turbulence it reads — numbers or a profile on
//! analytic flows, the CFD's fields on mesh flows (k and ε, or k and ω with
//! ε = C_μ·k·ω).

use std::sync::Arc;

use glam::DVec3;

use scg_core::physics::dispersion::{
    C_MU, CellTurbulence, Model, Profile, Turbulence, epsilon_from_omega, sigma_of,
};
use scg_core::stages::carrier::Dispersion;
use scg_mesh::{MeshGeometry, PolyMesh, ScalarField, foam};

use super::Ctx;
use crate::error::SceneError;
use crate::model::{FieldReader, SceneMeshFlow};
use crate::raw::{RawDispersion, RawDispersionModel, RawProfile, RawTurbulenceValue};

/// Why `langevin` needs `c0` stated, and which values mean what (docs/dispersion.md).
const C0_MISSING: &str = "missing: the Langevin walk's C₀ sets its Lagrangian time \
    T_L = 4k/(3·C₀·ε) and so the tracers' diffusivity 8k²/(9·C₀·ε), and no one value is right \
    for every field; state it: 8.9 spreads tracers as the RANS model's own diffusivity \
    C_μ·k²/(Sc_t·ε) with Sc_t = 0.9 (as OpenFOAM's stochastic_ras and Fluent's random walk \
    with T_L = 0.15·k/ε do), 2.1 is Pope's simplified Langevin model (4.2 times that); \
    docs/dispersion.md, \"Which C₀\"";

/// `[dispersion]` → the carrier modifier, a line saying where its turbulence came from and,
/// on a mesh, the fields it was read from.
pub(super) fn dispersion(
    d: &RawDispersion,
    mesh: Option<&SceneMeshFlow>,
    seed: u64,
    cx: &Ctx,
) -> Result<(Dispersion, String, Option<TurbulenceFields>), SceneError> {
    let model = match d.model {
        RawDispersionModel::StochasticRas => {
            for (key, given) in [("c0", d.c0.is_some()), ("csanady", d.csanady.is_some())] {
                if given {
                    return Err(cx.err(
                        &format!("dispersion.{key}"),
                        "is a parameter of the `langevin` model, not of `stochastic_ras` \
                         (whose eddies end when the particle crosses them: its own \
                         crossing-trajectories effect); to switch a scene's walk to the \
                         eddy model from the command line replace the whole table: --set \
                         'dispersion={model=\"stochastic_ras\", k=\"k\", omega=\"omega\"}'",
                    ));
                }
            }
            Model::StochasticRas
        }
        RawDispersionModel::Langevin => Model::Langevin {
            c0: match d.c0 {
                Some(c0) => cx.positive("dispersion.c0", c0)?,
                None => return Err(cx.err("dispersion.c0", C0_MISSING)),
            },
            csanady: d
                .csanady
                .map(|b| cx.positive("dispersion.csanady", b))
                .transpose()?,
        },
    };
    if d.epsilon.is_some() && d.omega.is_some() {
        return Err(cx.err(
            "dispersion.omega",
            "give either `epsilon` or `omega`, not both",
        ));
    }
    let mut fields = None;
    let (turbulence, source, mask) = match (mesh, &d.profile) {
        (Some(_), Some(_)) => {
            return Err(cx.err(
                "dispersion.profile",
                "a mesh flow reads k and ε from its fields (`k = \"k\"`, `epsilon = \
                 \"epsilon\"` or `omega = \"omega\"`); a profile is for analytic flows",
            ));
        }
        (None, Some(p)) => {
            for key in ["k", "epsilon", "omega"] {
                let given = match key {
                    "k" => d.k.is_some(),
                    "epsilon" => d.epsilon.is_some(),
                    _ => d.omega.is_some(),
                };
                if given {
                    return Err(cx.err(
                        &format!("dispersion.{key}"),
                        "give the turbulence either as numbers or as [dispersion.profile]",
                    ));
                }
            }
            let (p, src) = profile(p, cx)?;
            (Turbulence::Profile(p), src, DVec3::ONE)
        }
        (None, None) => {
            let k = match &d.k {
                Some(RawTurbulenceValue::Value(k)) => cx.non_negative("dispersion.k", *k)?,
                Some(RawTurbulenceValue::Field(_)) => {
                    return Err(cx.err(
                        "dispersion.k",
                        "a field name needs a flow on a mesh (flow.kind = \"openfoam\" or \
                         \"vtk\"); an analytic flow takes a number, m²/s²",
                    ));
                }
                None => {
                    return Err(cx.err(
                        "dispersion.k",
                        "missing: the turbulent kinetic energy, m²/s² (or [dispersion.profile])",
                    ));
                }
            };
            let value = |key: &str, v: &Option<RawTurbulenceValue>| match v {
                Some(RawTurbulenceValue::Value(x)) => {
                    cx.positive(&format!("dispersion.{key}"), *x).map(Some)
                }
                Some(RawTurbulenceValue::Field(_)) => Err(cx.err(
                    &format!("dispersion.{key}"),
                    "a field name needs a flow on a mesh; an analytic flow takes a number",
                )),
                None => Ok(None),
            };
            let (epsilon, src) = match (value("epsilon", &d.epsilon)?, value("omega", &d.omega)?) {
                (Some(e), _) => (e, format!("uniform k = {k} m²/s², ε = {e} m²/s³")),
                (None, Some(w)) => {
                    let e = epsilon_from_omega(k, w);
                    (
                        e,
                        format!("uniform k = {k} m²/s², ω = {w} 1/s: ε = {C_MU}·k·ω = {e} m²/s³"),
                    )
                }
                (None, None) => {
                    return Err(cx.err(
                        "dispersion.epsilon",
                        "missing: the dissipation rate ε, m²/s³ (or ω, 1/s)",
                    ));
                }
            };
            (Turbulence::Uniform { k, epsilon }, src, DVec3::ONE)
        }
        (Some(m), None) => {
            let (t, src, f) = mesh_turbulence(d, m, matches!(model, Model::Langevin { .. }), cx)?;
            fields = Some(f);
            (
                Turbulence::Cells(Arc::new(t)),
                src,
                solved_directions(m.flow.mesh()),
            )
        }
    };
    Ok((
        Dispersion {
            model,
            turbulence,
            seed,
            mask,
            own_pass: false,
        },
        source,
        fields,
    ))
}

/// The directions a case solves: 0 along the normal of `empty` patches (a 2-D case), as
/// OpenFOAM's `solutionD`.
fn solved_directions(mesh: &PolyMesh) -> DVec3 {
    let mut mask = DVec3::ONE;
    for p in mesh.patches.iter().filter(|p| p.kind == "empty") {
        for f in p.start..p.start + p.size.min(64) {
            let (_, a) = scg_mesh::geometry::face_centre_and_area(&mesh.points, mesh.face(f));
            let n = a.normalize_or_zero().abs();
            for c in 0..3 {
                if n[c] > 0.999 {
                    mask[c] = 0.0;
                }
            }
        }
    }
    mask
}

/// `[dispersion.profile]`.
fn profile(p: &RawProfile, cx: &Ctx) -> Result<(Profile, String), SceneError> {
    let axis = match p.axis.as_str() {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        other => {
            return Err(cx.err(
                "dispersion.profile.axis",
                format!("expected \"x\", \"y\" or \"z\", got \"{other}\""),
            ));
        }
    };
    let n = p.at.len();
    if n < 2 {
        return Err(cx.err("dispersion.profile.at", "needs at least two coordinates"));
    }
    for (i, w) in p.at.windows(2).enumerate() {
        cx.finite("dispersion.profile.at", w[0])?;
        cx.finite("dispersion.profile.at", w[1])?;
        if w[1] <= w[0] {
            return Err(cx.err(
                "dispersion.profile.at",
                format!(
                    "must increase strictly: at[{}] = {} ≤ at[{i}] = {}",
                    i + 1,
                    w[1],
                    w[0]
                ),
            ));
        }
    }
    let same_length = |key: &str, v: &[f64]| {
        if v.len() == n {
            Ok(())
        } else {
            Err(cx.err(
                &format!("dispersion.profile.{key}"),
                format!("{} values where `at` has {n}", v.len()),
            ))
        }
    };
    same_length("k", &p.k)?;
    for &k in &p.k {
        cx.non_negative("dispersion.profile.k", k)?;
    }
    let (epsilon, what) = match (&p.epsilon, &p.omega) {
        (Some(e), None) => {
            same_length("epsilon", e)?;
            for &x in e {
                cx.positive("dispersion.profile.epsilon", x)?;
            }
            (e.clone(), "k and ε")
        }
        (None, Some(w)) => {
            same_length("omega", w)?;
            for &x in w {
                cx.positive("dispersion.profile.omega", x)?;
            }
            let e =
                p.k.iter()
                    .zip(w)
                    .map(|(&k, &w)| epsilon_from_omega(k, w))
                    .collect();
            (e, "k and ω (ε = 0.09·k·ω)")
        }
        (Some(_), Some(_)) => {
            return Err(cx.err(
                "dispersion.profile.omega",
                "give either `epsilon` or `omega`, not both",
            ));
        }
        (None, None) => {
            return Err(cx.err(
                "dispersion.profile.epsilon",
                "missing: ε at each coordinate, m²/s³ (or `omega`, 1/s)",
            ));
        }
    };
    let periodic = p.periodic.unwrap_or(false);
    if periodic && (p.k[0] != p.k[n - 1] || epsilon[0] != epsilon[n - 1]) {
        return Err(cx.err(
            "dispersion.profile.periodic",
            "a periodic profile must end with the values it starts with",
        ));
    }
    let src = format!(
        "{what} tabulated along {} at {n} points{}",
        p.axis,
        if periodic { ", periodic" } else { "" }
    );
    Ok((
        Profile {
            axis,
            at: p.at.clone(),
            k: p.k.clone(),
            epsilon,
            periodic,
        },
        src,
    ))
}

/// The fields a mesh flow's turbulence is read from.
#[derive(Clone, Debug)]
pub(super) struct TurbulenceFields {
    k: String,
    dissipation: Dissipation,
    /// ∇σ as well (the Langevin walk's drift).
    gradient: bool,
}

/// ε directly, or ω with ε = C_μ·k·ω.
#[derive(Clone, Debug)]
enum Dissipation {
    Epsilon(String),
    Omega(String),
}

/// k and ε per cell from the mesh flow's source, the line saying so, and the fields'
/// names (an unsteady series reads the same fields from each of its snapshots).
fn mesh_turbulence(
    d: &RawDispersion,
    m: &SceneMeshFlow,
    gradient: bool,
    cx: &Ctx,
) -> Result<(CellTurbulence, String, TurbulenceFields), SceneError> {
    let Some(reader) = &m.reader else {
        return Err(cx.err("dispersion", "this flow has no source to read k and ε from"));
    };
    let field_name = |key: &str, v: &Option<RawTurbulenceValue>| match v {
        Some(RawTurbulenceValue::Field(f)) if !f.is_empty() => Ok(Some(f.clone())),
        Some(RawTurbulenceValue::Field(_)) => {
            Err(cx.err(&format!("dispersion.{key}"), "must name a field"))
        }
        Some(RawTurbulenceValue::Value(_)) => Err(cx.err(
            &format!("dispersion.{key}"),
            "a mesh flow reads the turbulence from its fields: give the field's name, e.g. \
             `k = \"k\"`",
        )),
        None => Ok(None),
    };
    let k_name = field_name("k", &d.k)?.ok_or_else(|| {
        cx.err(
            "dispersion.k",
            "missing: the name of the turbulent kinetic energy field (e.g. `k = \"k\"`)",
        )
    })?;
    let (dissipation, src) = match (
        field_name("epsilon", &d.epsilon)?,
        field_name("omega", &d.omega)?,
    ) {
        (Some(e), _) => (
            Dissipation::Epsilon(e.clone()),
            format!("k and ε from the fields `{k_name}` and `{e}`"),
        ),
        (None, Some(w)) => (
            Dissipation::Omega(w.clone()),
            format!(
                "k from the field `{k_name}`, ε = {C_MU}·k·ω from the field `{w}` (no ε given)"
            ),
        ),
        (None, None) => {
            return Err(cx.err(
                "dispersion.epsilon",
                "missing: the name of the dissipation field (`epsilon = \"epsilon\"`) or of \
                 the specific dissipation (`omega = \"omega\"`, ε = 0.09·k·ω)",
            ));
        }
    };
    let fields = TurbulenceFields {
        k: k_name,
        dissipation,
        gradient,
    };
    let t = read_turbulence(&fields, reader, m.flow.mesh(), m.flow.geometry())
        .map_err(|(key, e)| cx.err(key, e))?;
    Ok((t, src, fields))
}

/// The turbulence of `fields` read by `reader` on `mesh`: k, ε (from ω when given so) and,
/// when asked, ∇σ per cell. An error gives its scene key and the message (file, field).
pub(super) fn read_turbulence(
    fields: &TurbulenceFields,
    reader: &FieldReader,
    mesh: &PolyMesh,
    geom: &MeshGeometry,
) -> Result<CellTurbulence, (&'static str, String)> {
    let read = |key: &'static str, name: &str| -> Result<ScalarField, (&'static str, String)> {
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
        let f = r.map_err(|e| (key, format!("{shown}: field `{name}`: {e}")))?;
        f.check_non_negative(&shown, name, mesh)
            .map_err(|e| (key, format!("field `{name}`: {e}")))?;
        Ok(f)
    };
    let k = read("dispersion.k", &fields.k)?;
    let epsilon = match &fields.dissipation {
        Dissipation::Epsilon(e) => read("dispersion.epsilon", e)?,
        Dissipation::Omega(w) => {
            let omega = read("dispersion.omega", w)?;
            let times = |a: &[f64], b: &[f64]| -> Vec<f64> {
                a.iter()
                    .zip(b)
                    .map(|(&k, &w)| epsilon_from_omega(k, w))
                    .collect()
            };
            let patches = k
                .patches
                .iter()
                .zip(&omega.patches)
                .map(|(a, b)| match (a, b) {
                    (Some(a), Some(b)) => Some(times(a, b)),
                    _ => None,
                })
                .collect();
            ScalarField {
                cells: times(&k.cells, &omega.cells),
                patches,
            }
        }
    };
    let grad_sigma = if fields.gradient {
        gauss_gradient_of_sigma(mesh, geom, &k)
    } else {
        Vec::new()
    };
    Ok(CellTurbulence {
        k: k.cells,
        epsilon: epsilon.cells,
        grad_sigma,
    })
}

/// ∇σ per cell, σ = √(2k/3), by the Gauss theorem: (1/V)·Σ_f σ_f·A_f, with σ_f linear
/// between the cells on either side of an internal face (weighted by their distances to
/// the face) and the patch value (the owner's where none is given) on a boundary face.
fn gauss_gradient_of_sigma(mesh: &PolyMesh, g: &MeshGeometry, k: &ScalarField) -> Vec<DVec3> {
    let sig: Vec<f64> = k.cells.iter().map(|&k| sigma_of(k)).collect();
    let mut grad = vec![DVec3::ZERO; mesh.n_cells];
    let ni = mesh.n_internal_faces();
    for f in 0..mesh.n_faces() {
        let o = mesh.owner[f] as usize;
        let a = g.face_areas[f];
        let sf = if f < ni {
            let n = mesh.neighbour[f] as usize;
            let xf = g.face_centres[f];
            let an = a.normalize_or_zero();
            let (dov, dn) = (
                (xf - g.cell_centres[o]).dot(an).abs(),
                (g.cell_centres[n] - xf).dot(an).abs(),
            );
            let w = if dov + dn > 0.0 { dn / (dov + dn) } else { 0.5 };
            let s = w * sig[o] + (1.0 - w) * sig[n];
            grad[n] -= s * a;
            s
        } else {
            mesh.patch_of_face(f)
                .and_then(|p| {
                    let patch = &mesh.patches[p];
                    k.patches[p].as_ref().map(|v| sigma_of(v[f - patch.start]))
                })
                .unwrap_or(sig[o])
        };
        grad[o] += sf * a;
    }
    for (gc, &v) in grad.iter_mut().zip(&g.cell_volumes) {
        *gc = if v > 0.0 { *gc / v } else { DVec3::ZERO };
    }
    grad
}
