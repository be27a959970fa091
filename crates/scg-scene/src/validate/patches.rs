//! What particles do at the patches of a mesh flow: `[flow.patches]` `wall_model`,
//! `restitution`, `friction`, `friction_model` and the per-patch `[flow.patches.interaction]` (OpenFOAM's
//! `localInteraction`), and the contact wall built from the `contact` patches.

use scg_core::physics::contact::Material;
use scg_core::physics::mesh_flow::{PatchInteraction, PatchRole, WallFriction};
use scg_core::physics::trimesh::TriMesh;
use scg_core::physics::wall_shape::WallShape;
use scg_core::stages::walls::Wall;

use super::Ctx;
use crate::error::SceneError;
use crate::model::{PatchModel, PatchWalls, SceneMeshFlow};
use crate::raw::{RawFlow, RawWall, RawWallModel};

/// Mesh patch types whose unlisted patches reflect particles specularly, as OpenFOAM's
/// tracking does at constraint patches ([`scg_mesh::polymesh::CONSTRAINT_KINDS`]).
pub const MIRROR_KINDS: [&str; 4] = scg_mesh::polymesh::CONSTRAINT_KINDS;

/// The model of every patch of `mf`, in mesh order. Wall patches take `wall_model`
/// (default `contact` with a `[material]`, else `rebound`); unlisted constraint patches
/// ([`MIRROR_KINDS`]) reflect specularly; outlets, inlets and other unlisted patches
/// escape; `interaction.<patch>` overrides either. A `rebound` takes its
/// `restitution`, `friction` and `friction_model` from its own entry, else from
/// `[flow.patches]`, else e from `material.restitution` (1 without a material), μ = 0 and
/// the Coulomb impact. `contact` needs a
/// `[material]`; its patches' centres rebound with the material's restitution (the guard
/// behind the contact law).
pub(super) fn patch_models(
    f: &RawFlow,
    mf: &SceneMeshFlow,
    material: Option<Material>,
    cx: &Ctx,
) -> Result<Vec<PatchModel>, SceneError> {
    let patches = f.patches.clone().unwrap_or_default();
    let flow = &mf.flow;
    let mesh = flow.mesh();
    let unit = |key: &str, x: Option<f64>| -> Result<Option<f64>, SceneError> {
        match x {
            None => Ok(None),
            Some(x) if x.is_finite() && (0.0..=1.0).contains(&x) => Ok(Some(x)),
            Some(_) => Err(cx.err(key, "must lie in [0, 1]")),
        }
    };
    let friction = |key: &str, x: Option<f64>| -> Result<Option<f64>, SceneError> {
        match x {
            None => Ok(None),
            Some(x) => cx.non_negative(key, x).map(Some),
        }
    };
    let e_default = unit("flow.patches.restitution", patches.restitution)?
        .unwrap_or(material.map_or(1.0, |m| m.restitution));
    let mu_default = friction("flow.patches.friction", patches.friction)?.unwrap_or(0.0);
    let fm_default = patches.friction_model.unwrap_or_default();
    let model =
        |m: RawWallModel, key: &str, e: Option<f64>, mu: Option<f64>, fm: Option<WallFriction>| {
            Ok(match m {
                RawWallModel::Contact => {
                    let Some(mat) = material else {
                        return Err(cx.err(
                            key,
                            "\"contact\" needs a [material] table (the contact law)",
                        ));
                    };
                    PatchModel {
                        interaction: PatchInteraction::frictionless(mat.restitution),
                        contact: true,
                    }
                }
                RawWallModel::Rebound => PatchModel {
                    interaction: PatchInteraction::Rebound {
                        e: e.unwrap_or(e_default),
                        mu: mu.unwrap_or(mu_default),
                        friction: fm.unwrap_or(fm_default),
                    },
                    contact: false,
                },
                RawWallModel::Stick => PatchModel {
                    interaction: PatchInteraction::Stick,
                    contact: false,
                },
                RawWallModel::Escape => PatchModel {
                    interaction: PatchInteraction::Escape,
                    contact: false,
                },
            })
        };
    let wall_model = patches.wall_model.unwrap_or(if material.is_some() {
        RawWallModel::Contact
    } else {
        RawWallModel::Rebound
    });
    let mut out = Vec::with_capacity(mesh.patches.len());
    for (r, p) in flow.roles().iter().zip(&mesh.patches) {
        out.push(match r {
            PatchRole::Wall => model(wall_model, "flow.patches.wall_model", None, None, None)?,
            // OpenFOAM's constraint patches reflect a particle specularly (its
            // hitSymmetryPatch): symmetry planes, and the two sides of a 2-D (`empty`) or
            // axisymmetric (`wedge`) case, which keeps its motion in the slab
            PatchRole::Lost if MIRROR_KINDS.contains(&p.kind.as_str()) => PatchModel {
                interaction: PatchInteraction::frictionless(1.0),
                contact: false,
            },
            _ => model(RawWallModel::Escape, "flow.patches", None, None, None)?,
        });
    }
    for (name, entry) in &patches.interaction {
        let key = format!("flow.patches.interaction.{name}");
        let Some(i) = mesh.patches.iter().position(|p| &p.name == name) else {
            let known: Vec<&str> = mesh.patches.iter().map(|p| p.name.as_str()).collect();
            return Err(cx.err(
                &key,
                format!("unknown patch `{name}`; the mesh has: {}", known.join(", ")),
            ));
        };
        if entry.model != RawWallModel::Rebound {
            for (k, v) in [
                ("restitution", entry.restitution.is_some()),
                ("friction", entry.friction.is_some()),
                ("friction_model", entry.friction_model.is_some()),
            ] {
                if v {
                    return Err(cx.err(
                        &format!("{key}.{k}"),
                        "is used by \"rebound\" only, not by this model",
                    ));
                }
            }
        }
        if entry.model == RawWallModel::Contact && flow.roles()[i] != PatchRole::Wall {
            return Err(cx.err(
                &format!("{key}.model"),
                "\"contact\" is for wall patches (list the patch in flow.patches.walls)",
            ));
        }
        let e = unit(&format!("{key}.restitution"), entry.restitution)?;
        let mu = friction(&format!("{key}.friction"), entry.friction)?;
        let fm = entry.friction_model;
        out[i] = model(entry.model, &format!("{key}.model"), e, mu, fm)?;
    }
    Ok(out)
}

/// The `contact` patches of a mesh flow as one contact wall: every face of every such
/// patch, polygons fanned about their face centres (so the surface is the one the locator
/// tracks against). `None` without such patches.
pub(super) fn patch_walls(
    mf: &SceneMeshFlow,
    models: &[PatchModel],
    cx: &Ctx,
) -> Result<Option<PatchWalls>, SceneError> {
    let flow = &mf.flow;
    let walls: Vec<usize> = models
        .iter()
        .enumerate()
        .filter(|(_, m)| m.contact)
        .map(|(i, _)| i)
        .collect();
    if walls.is_empty() {
        return Ok(None);
    }
    let s = scg_mesh::surface::patch_surface(flow.mesh(), &walls, scg_mesh::surface::Fan::Centre);
    let mesh = TriMesh::new(s.vertices, s.triangles).map_err(|e| {
        cx.err(
            "flow.patches.walls",
            format!("{}: the wall patches as a contact wall: {e}", mf.source),
        )
    })?;
    Ok(Some(PatchWalls {
        wall: Wall {
            name: PatchWalls::NAME.to_string(),
            shape: WallShape::Mesh(std::sync::Arc::new(mesh)),
            motion: Default::default(),
        },
        per_patch: walls.into_iter().zip(s.per_patch).collect(),
    }))
}

/// The model of `[[walls]]` entry `i`: `None` for a contact wall (the default; the
/// `[material]` contact law), else the impulse it acts as. `restitution` (default
/// `material.restitution`, else 1) and `friction` (default 0) only with `rebound`.
pub(super) fn wall_model(
    w: &RawWall,
    i: usize,
    material: Option<Material>,
    cx: &Ctx,
) -> Result<Option<PatchInteraction>, SceneError> {
    let k = |s: &str| format!("walls[{i}].{s}");
    let model = w.model.unwrap_or(RawWallModel::Contact);
    if model != RawWallModel::Rebound {
        for (key, v) in [
            ("restitution", w.restitution.is_some()),
            ("friction", w.friction.is_some()),
            ("friction_model", w.friction_model.is_some()),
        ] {
            if v {
                return Err(cx.err(&k(key), "is used by model = \"rebound\" only"));
            }
        }
    }
    Ok(match model {
        RawWallModel::Contact => None,
        RawWallModel::Stick => Some(PatchInteraction::Stick),
        RawWallModel::Escape => Some(PatchInteraction::Escape),
        RawWallModel::Rebound => {
            let e = match w.restitution {
                Some(e) if e.is_finite() && (0.0..=1.0).contains(&e) => e,
                Some(_) => return Err(cx.err(&k("restitution"), "must lie in [0, 1]")),
                None => material.map_or(1.0, |m| m.restitution),
            };
            let mu = match w.friction {
                Some(mu) => cx.non_negative(&k("friction"), mu)?,
                None => 0.0,
            };
            Some(PatchInteraction::Rebound {
                e,
                mu,
                friction: w.friction_model.unwrap_or_default(),
            })
        }
    })
}

/// `[erosion]`: the model, the patches it logs (default: every wall patch of a mesh flow
/// that rebounds or sticks) and the `[[walls]]` it logs (default: every impulse wall that
/// rebounds or sticks). A listed patch must be a wall whose particles rebound or stick, a
/// listed wall a `[[walls]]` entry with `model = "rebound"` or `"stick"` (contact-law
/// impacts are resolved over several steps and are not logged).
pub(super) fn erosion(
    e: &crate::raw::RawErosion,
    mf: Option<&SceneMeshFlow>,
    models: &[PatchModel],
    impulse_walls: &[scg_core::stages::impulse_walls::ImpulseWall],
    cx: &Ctx,
) -> Result<scg_core::stages::erosion::ErosionSpec, SceneError> {
    use crate::raw::RawErosionModel;
    use scg_core::physics::erosion::ErosionModel;
    let not = |key: &str, given: bool, model: &str| -> Result<(), SceneError> {
        if given {
            Err(cx.err(
                &format!("erosion.{key}"),
                format!("does not belong to `{model}`"),
            ))
        } else {
            Ok(())
        }
    };
    let model = match e.model {
        RawErosionModel::Finnie => {
            not("n", e.n.is_some(), "finnie")?;
            not("wall_density", e.wall_density.is_some(), "finnie")?;
            ErosionModel::Finnie {
                flow_stress: cx.positive(
                    "erosion.flow_stress",
                    cx.need("erosion.flow_stress", &e.flow_stress)?,
                )?,
                psi: cx.positive("erosion.psi", e.psi.unwrap_or(2.0))?,
                k: cx.positive("erosion.k", e.k.unwrap_or(2.0))?,
            }
        }
        RawErosionModel::Dnv => {
            not("flow_stress", e.flow_stress.is_some(), "dnv")?;
            not("psi", e.psi.is_some(), "dnv")?;
            ErosionModel::Dnv {
                k: cx.positive("erosion.k", e.k.unwrap_or(2.0e-9))?,
                n: cx.positive("erosion.n", e.n.unwrap_or(2.6))?,
                wall_density: cx.positive(
                    "erosion.wall_density",
                    cx.need("erosion.wall_density", &e.wall_density)?,
                )?,
            }
        }
    };
    let walls = erosion_walls(e, impulse_walls, cx)?;
    let Some(mf) = mf else {
        if e.patches.is_some() {
            return Err(cx.err(
                "erosion.patches",
                "needs a mesh flow (flow.kind = \"openfoam\" or \"vtk\")",
            ));
        }
        if !walls.contains(&true) {
            return Err(cx.err(
                "erosion",
                "nothing to erode: no mesh flow wall patch and no [[walls]] entry whose \
                 particles rebound or stick (model = \"rebound\" or \"stick\")",
            ));
        }
        return Ok(scg_core::stages::erosion::ErosionSpec {
            model,
            patches: Vec::new(),
            walls,
        });
    };
    let mesh = mf.flow.mesh();
    let roles = mf.flow.roles();
    let loggable = |p: usize| {
        roles[p] == PatchRole::Wall
            && models.get(p).is_some_and(|m| {
                !m.contact
                    && matches!(
                        m.interaction,
                        PatchInteraction::Rebound { .. } | PatchInteraction::Stick
                    )
            })
    };
    let patches = match &e.patches {
        None => (0..mesh.patches.len()).map(loggable).collect(),
        Some(names) => {
            let mut on = vec![false; mesh.patches.len()];
            for name in names {
                let Some(p) = mesh.patches.iter().position(|p| &p.name == name) else {
                    return Err(cx.err(
                        "erosion.patches",
                        format!("unknown patch `{name}` in {}", mf.source),
                    ));
                };
                if !loggable(p) {
                    return Err(cx.err(
                        "erosion.patches",
                        format!(
                            "patch `{name}` is not a wall whose particles rebound or stick \
                             (flow.patches.walls with wall_model rebound or stick)"
                        ),
                    ));
                }
                on[p] = true;
            }
            on
        }
    };
    if !patches.contains(&true) && !walls.contains(&true) {
        return Err(cx.err(
            "erosion",
            "no wall patch or [[walls]] entry whose particles rebound or stick: nothing to erode",
        ));
    }
    Ok(scg_core::stages::erosion::ErosionSpec {
        model,
        patches,
        walls,
    })
}

/// `erosion.walls`: per impulse wall, whether its impacts are logged.
fn erosion_walls(
    e: &crate::raw::RawErosion,
    walls: &[scg_core::stages::impulse_walls::ImpulseWall],
    cx: &Ctx,
) -> Result<Vec<bool>, SceneError> {
    let wears = |w: &scg_core::stages::impulse_walls::ImpulseWall| {
        matches!(
            w.model,
            PatchInteraction::Rebound { .. } | PatchInteraction::Stick
        )
    };
    let Some(names) = &e.walls else {
        return Ok(walls.iter().map(wears).collect());
    };
    let mut on = vec![false; walls.len()];
    for name in names {
        let Some(k) = walls.iter().position(|w| &w.wall.name == name) else {
            return Err(cx.err(
                "erosion.walls",
                format!(
                    "`{name}` is not a [[walls]] entry with model = \"rebound\", \"stick\" or \
                     \"escape\" (contact-law walls are not logged)"
                ),
            ));
        };
        if !wears(&walls[k]) {
            return Err(cx.err(
                "erosion.walls",
                format!("wall `{name}` lets particles escape: nothing strikes it"),
            ));
        }
        on[k] = true;
    }
    Ok(on)
}
