//! A frozen-rotor (MRF) OpenFOAM case: the zones of `constant/MRFProperties` and their
//! cells (`constant/polyMesh/cellZones`). OpenFOAM's MRF solves the absolute velocity `U`
//! everywhere, adds the frame's terms inside each zone, and makes the boundary faces of the
//! zone move at Ω×(x − origin) (`MRFZone::correctBoundaryVelocity`: every face of a patch
//! that is not coupled and not in `nonRotatingPatches` whose cell is in the zone), whatever
//! the patch's own type says (`noSlip` on a rotor means Ω×r there).
//!
//! scg does the same with the field ([`rotor_faces`]: those faces' values become Ω×r) and
//! with the particles: they are tracked in the absolute frame through the frozen field,
//! and rebound off those faces relative to the surface's velocity; the rotor's geometry
//! does not turn (the frozen rotor's assumption: right where a particle crosses the rotor
//! in a fraction of a blade passage, wrong for one that stays among the blades).

use scg_core::physics::mesh_flow::{MovingFaces, Spin};
use scg_mesh::foam::MrfZone;
use scg_mesh::{CellField, PolyMesh};

use super::Ctx;
use crate::error::SceneError;
use crate::model::RotorZone;

/// Coupled patch kinds (refused by the field reader, listed for completeness): with the
/// constraint kinds ([`super::patches::MIRROR_KINDS`]) their faces never move with a zone.
const COUPLED_KINDS: [&str; 5] = [
    "cyclic",
    "cyclicAMI",
    "cyclicACMI",
    "cyclicSlip",
    "processor",
];

/// The moving faces of the active `zones` (origins already placed) on `mesh` (placed),
/// their face values in `field` set to Ω×(x − origin) as OpenFOAM's MRF sets them, and one
/// [`RotorZone`] per zone. `case` is the case folder (its cellZones).
pub(super) fn rotor_faces(
    case: &std::path::Path,
    mesh: &PolyMesh,
    field: &mut CellField,
    zones: &[MrfZone],
    cx: &Ctx,
) -> Result<(Option<MovingFaces>, Vec<RotorZone>), SceneError> {
    if zones.is_empty() {
        return Ok((None, Vec::new()));
    }
    let shown = case.display();
    let cell_zones = scg_mesh::foam::read_cell_zones(case, mesh.n_cells)
        .map_err(|e| cx.err("flow.case", e.to_string()))?;
    let mut spins = Vec::new();
    let mut moving = Vec::new();
    let mut out = Vec::new();
    let ni = mesh.n_internal_faces();
    for (zi, z) in zones.iter().enumerate() {
        let Some((_, cells)) = cell_zones.iter().find(|(n, _)| *n == z.cell_zone) else {
            let known: Vec<&str> = cell_zones.iter().map(|(n, _)| n.as_str()).collect();
            return Err(cx.err(
                "flow.case",
                format!(
                    "{shown}: constant/MRFProperties zone `{}` names cellZone `{}`, which \
                     constant/polyMesh/cellZones does not have (it has: {})",
                    z.name,
                    z.cell_zone,
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                ),
            ));
        };
        for p in &z.non_rotating_patches {
            if !mesh.patches.iter().any(|q| &q.name == p) {
                return Err(cx.err(
                    "flow.case",
                    format!(
                        "{shown}: constant/MRFProperties zone `{}`: nonRotatingPatches names \
                         `{p}`, which the mesh does not have",
                        z.name
                    ),
                ));
            }
        }
        let mut in_zone = vec![false; mesh.n_cells];
        for &c in cells {
            in_zone[c as usize] = true;
        }
        let spin = Spin {
            omega: z.axis * z.omega,
            origin: z.origin,
        };
        let mut faces = Vec::new();
        for (pi, p) in mesh.patches.iter().enumerate() {
            if super::patches::MIRROR_KINDS.contains(&p.kind.as_str())
                || COUPLED_KINDS.contains(&p.kind.as_str())
                || z.non_rotating_patches.contains(&p.name)
            {
                continue;
            }
            let mut n = 0;
            for k in 0..p.size {
                let f = p.start + k;
                if !in_zone[mesh.owner[f] as usize] {
                    continue;
                }
                let (xf, _) = scg_mesh::geometry::face_centre_and_area(&mesh.points, mesh.face(f));
                let values = field.patches[pi].get_or_insert_with(|| {
                    (p.start..p.start + p.size)
                        .map(|g| field.cells[mesh.owner[g] as usize])
                        .collect()
                });
                values[k] = spin.velocity(xf);
                moving.push((f as u32, zi));
                n += 1;
            }
            if n > 0 {
                faces.push((p.name.clone(), n));
            }
        }
        spins.push(spin);
        out.push(RotorZone {
            name: z.name.clone(),
            cell_zone: z.cell_zone.clone(),
            cells: cells.len(),
            omega: spin.omega,
            origin: spin.origin,
            faces,
        });
    }
    let faces = MovingFaces::new(ni, mesh.n_faces() - ni, spins, &moving)
        .map_err(|e| cx.err("flow.case", format!("{shown}: {e}")))?;
    Ok((Some(faces), out))
}

/// A rotor's moving faces are impulse walls (rebound, stick, escape): the contact law's
/// mesh walls are at rest, so a `contact` model on a patch with moving faces is an error.
pub(super) fn no_contact_on_rotors(
    m: &crate::model::SceneMeshFlow,
    models: &[crate::model::PatchModel],
    cx: &Ctx,
) -> Result<(), SceneError> {
    for z in &m.rotors {
        for (patch, _) in &z.faces {
            let i = m.flow.mesh().patches.iter().position(|p| &p.name == patch);
            if i.and_then(|i| models.get(i)).is_some_and(|pm| pm.contact) {
                return Err(cx.err(
                    "flow.patches",
                    format!(
                        "patch `{patch}` turns with the frozen-rotor zone `{}`: its model must \
                         be rebound, stick or escape (the contact law's mesh walls are at rest)",
                        z.name
                    ),
                ));
            }
        }
    }
    Ok(())
}
