//! OpenFOAM velocity boundary conditions → the value each wall face carries.
//!
//! A `volVectorField`'s `boundaryField` names a patch-field *type* per patch. What the face
//! value is depends on that type, not on whether the file happens to write a `value`:
//! `noSlip` writes none and means zero; `zeroGradient` writes none and means the owner
//! cell's value; `slip` writes none and means the owner's value without its normal
//! component. [`TABLE`] lists every type scg understands, with what it means; a type not in
//! it is an error naming the file, the patch and the type ([`face_values`]), never a guess.

use glam::DVec3;

use crate::{Patch, PolyMesh};

/// What the face values of a patch are, by its boundary-condition type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceValue {
    /// Zero on every face (`noSlip`).
    Zero,
    /// The `value` entry the file writes (required): the face values OpenFOAM evaluated
    /// (`fixedValue`, `movingWallVelocity`, `inletOutlet`, …).
    Written,
    /// The owner cell's value (`zeroGradient`); no values are stored (`None`), which the
    /// interpolation reads as the owner's.
    Owner,
    /// The owner cell's value with its component along the face normal removed, u − (u·n)n
    /// (`slip`, `symmetry`, `symmetryPlane`, and `wedge`, whose two faces are mirror
    /// images to within the wedge angle).
    Tangential,
    /// A constraint with no face values (`empty`: the direction of a 2-D case); the
    /// interpolation reads the owner's value, exact for a field that does not vary across it.
    Empty,
    /// Refused: scg cannot honour it (the message says why).
    Unsupported(&'static str),
}

/// Every boundary-condition type scg reads for a velocity, and what its face values are.
pub const TABLE: &[(&str, FaceValue)] = &[
    ("noSlip", FaceValue::Zero),
    ("fixedValue", FaceValue::Written),
    ("uniformFixedValue", FaceValue::Written),
    ("movingWallVelocity", FaceValue::Written),
    ("rotatingWallVelocity", FaceValue::Written),
    ("translatingWallVelocity", FaceValue::Written),
    ("inletOutlet", FaceValue::Written),
    ("outletInlet", FaceValue::Written),
    ("uniformInletOutlet", FaceValue::Written),
    ("pressureInletOutletVelocity", FaceValue::Written),
    ("pressureInletVelocity", FaceValue::Written),
    ("pressureInletUniformVelocity", FaceValue::Written),
    ("pressureDirectedInletVelocity", FaceValue::Written),
    ("pressureDirectedInletOutletVelocity", FaceValue::Written),
    ("flowRateInletVelocity", FaceValue::Written),
    ("flowRateOutletVelocity", FaceValue::Written),
    ("surfaceNormalFixedValue", FaceValue::Written),
    ("cylindricalInletVelocity", FaceValue::Written),
    ("swirlFlowRateInletVelocity", FaceValue::Written),
    ("turbulentInlet", FaceValue::Written),
    ("timeVaryingMappedFixedValue", FaceValue::Written),
    ("fixedMean", FaceValue::Written),
    ("freestream", FaceValue::Written),
    ("freestreamVelocity", FaceValue::Written),
    ("partialSlip", FaceValue::Written),
    ("fixedNormalSlip", FaceValue::Written),
    ("fixedGradient", FaceValue::Written),
    ("advective", FaceValue::Written),
    ("waveTransmissive", FaceValue::Written),
    ("calculated", FaceValue::Written),
    ("zeroGradient", FaceValue::Owner),
    ("slip", FaceValue::Tangential),
    ("symmetry", FaceValue::Tangential),
    ("symmetryPlane", FaceValue::Tangential),
    ("wedge", FaceValue::Tangential),
    ("empty", FaceValue::Empty),
    (
        "cyclic",
        FaceValue::Unsupported(
            "a cyclic (periodic) patch: particles would have to cross to its partner patch, \
             which scg does not do; mesh the full domain, or make the patches walls, inlets \
             or outlets",
        ),
    ),
    (
        "cyclicAMI",
        FaceValue::Unsupported(
            "a cyclicAMI patch (periodic or sliding interface): particles would have to cross \
             to its partner patch, which scg does not do",
        ),
    ),
    (
        "cyclicACMI",
        FaceValue::Unsupported(
            "a cyclicACMI patch: particles would have to cross to its partner patch, which \
             scg does not do",
        ),
    ),
    (
        "cyclicSlip",
        FaceValue::Unsupported(
            "a cyclicSlip patch: particles would have to cross to its partner patch, which \
             scg does not do",
        ),
    ),
    (
        "processor",
        FaceValue::Unsupported(
            "a processor patch: this is one piece of a decomposed case; run reconstructPar \
             and read the whole case",
        ),
    ),
];

/// What type `kind` means, `None` when it is not in [`TABLE`].
pub fn lookup(kind: &str) -> Option<FaceValue> {
    TABLE.iter().find(|(k, _)| *k == kind).map(|&(_, v)| v)
}

/// The names of [`TABLE`], comma-separated (for messages).
pub fn known_types() -> String {
    TABLE.iter().map(|(k, _)| *k).collect::<Vec<_>>().join(", ")
}

/// Unit normal of face `f` of `mesh` (Newell's area vector, pointing out of the owner).
pub fn face_normal(mesh: &PolyMesh, f: usize) -> DVec3 {
    let pts = mesh.face(f);
    let mut a = DVec3::ZERO;
    for (i, &p) in pts.iter().enumerate() {
        let q = pts[(i + 1) % pts.len()];
        a += mesh.points[p as usize].cross(mesh.points[q as usize]);
    }
    a.normalize_or_zero()
}

/// The face values of `patch` for boundary-condition type `kind`: `Ok(None)` for the
/// owner's values, `Ok(Some(v))` with one value per face, `Err(message)` for a type not in
/// [`TABLE`], a refused one, or a `Written` type without its values (`written`: what the
/// entry's `value` gave, if anything). `cells` are the cell values.
pub fn face_values(
    kind: &str,
    written: Option<Vec<DVec3>>,
    mesh: &PolyMesh,
    patch: &Patch,
    cells: &[DVec3],
) -> Result<Option<Vec<DVec3>>, String> {
    let Some(meaning) = lookup(kind) else {
        return Err(format!(
            "unknown boundary condition type '{kind}' (scg reads: {})",
            known_types()
        ));
    };
    let faces = patch.start..patch.start + patch.size;
    Ok(match meaning {
        FaceValue::Zero => Some(vec![DVec3::ZERO; patch.size]),
        FaceValue::Written => match written {
            Some(v) => Some(v),
            None => {
                return Err(format!(
                    "type '{kind}' without a `value` entry (OpenFOAM writes the evaluated face \
                     values there; run the solver or foamFormatConvert to write them)"
                ));
            }
        },
        FaceValue::Owner | FaceValue::Empty => None,
        FaceValue::Tangential => Some(
            faces
                .map(|f| {
                    let u = cells[mesh.owner[f] as usize];
                    let n = face_normal(mesh, f);
                    u - u.dot(n) * n
                })
                .collect(),
        ),
        FaceValue::Unsupported(why) => {
            return Err(format!("type '{kind}' is not supported: {why}"));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_type_is_listed_once() {
        for (i, (k, _)) in TABLE.iter().enumerate() {
            assert!(
                TABLE[i + 1..].iter().all(|(j, _)| j != k),
                "{k} listed twice"
            );
        }
        assert_eq!(lookup("noSlip"), Some(FaceValue::Zero));
        assert_eq!(lookup("noslip"), None);
        assert!(known_types().contains("symmetryPlane"));
    }
}
