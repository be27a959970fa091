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

/// Why a cyclic patch is refused.
const CYCLIC: &str = "a cyclic (periodic) patch: particles would have to cross to its partner \
     patch, which scg does not do; mesh the full domain, or make the patches walls, inlets or \
     outlets";
/// Why a cyclicAMI patch is refused.
const CYCLIC_AMI: &str = "a cyclicAMI patch (periodic or sliding interface): particles would \
     have to cross to its partner patch, which scg does not do";
/// Why a cyclicACMI patch is refused.
const CYCLIC_ACMI: &str = "a cyclicACMI patch: particles would have to cross to its partner \
     patch, which scg does not do";
/// Why a cyclicSlip patch is refused.
const CYCLIC_SLIP: &str = "a cyclicSlip patch: particles would have to cross to its partner \
     patch, which scg does not do";
/// Why a processor patch is refused.
const PROCESSOR: &str = "a processor patch: this is one piece of a decomposed case; run \
     reconstructPar and read the whole case";

/// Every boundary-condition type scg reads for a velocity, and what its face values are.
pub const TABLE: &[(&str, FaceValue)] = &[
    ("noSlip", FaceValue::Zero),
    ("fixedValue", FaceValue::Written),
    ("uniformFixedValue", FaceValue::Written),
    ("movingWallVelocity", FaceValue::Written),
    ("rotatingWallVelocity", FaceValue::Written),
    ("translatingWallVelocity", FaceValue::Written),
    // A single rotating frame's Urel (SRFSimpleFoam): the written values are relative to
    // the frame (`relative no` inlets and walls at rest in the absolute frame included).
    ("SRFVelocity", FaceValue::Written),
    ("SRFFreestreamVelocity", FaceValue::Written),
    ("SRFWallVelocity", FaceValue::Written),
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
    ("cyclic", FaceValue::Unsupported(CYCLIC)),
    ("cyclicAMI", FaceValue::Unsupported(CYCLIC_AMI)),
    ("cyclicACMI", FaceValue::Unsupported(CYCLIC_ACMI)),
    ("cyclicSlip", FaceValue::Unsupported(CYCLIC_SLIP)),
    ("processor", FaceValue::Unsupported(PROCESSOR)),
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
            None => return Err(missing_value(kind)),
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

/// Every boundary-condition type scg reads for a scalar (`volScalarField`: turbulence `k`,
/// `epsilon`, `omega`, `nut`, also `p` and the like), and what its face values are, as
/// OpenFOAM (Foundation dev and ESI) defines the type. Only four kinds occur:
///
/// * [`FaceValue::Written`]: the type writes its evaluated face values as `value`
///   (required): `fixedValue` and everything derived from it (the wall functions
///   `epsilonWallFunction` and `omegaWallFunction`, which set the wall cells' values and
///   the faces to them, `kLowReWallFunction`, the `nut…WallFunction`s, `v2WallFunction`,
///   `fWallFunction`, `totalPressure`, `timeVaryingMappedFixedValue`, `mapped`, …), the mixed types
///   (`inletOutlet`, `outletInlet`, the turbulence inlets `turbulentIntensityKinetic
///   EnergyInlet`, `turbulentMixingLengthDissipationRateInlet`,
///   `turbulentMixingLengthFrequencyInlet` and their newer names `turbulentKineticEnergy`,
///   `turbulentEpsilon`, `turbulentOmega`, `freestream`, `advective`, …), the fixed
///   gradients (`fixedGradient`, `fixedFluxPressure`) and `calculated`.
/// * [`FaceValue::Owner`]: the owner cell's value, stored as `None`, whatever `value` the
///   file writes: `zeroGradient`, and `kqRWallFunction`, which derives from zeroGradient
///   (it writes a `value`, equal to the owner's once evaluated). A scalar has no normal
///   component, so `slip`, `symmetry`, `symmetryPlane` and `wedge`, which mirror a
///   vector, leave a scalar at its owner's value.
/// * [`FaceValue::Empty`]: `empty`, as for a velocity.
/// * [`FaceValue::Unsupported`]: `cyclic`, `cyclicAMI`, `cyclicACMI`, `cyclicSlip`,
///   `processor`, refused for the reasons [`TABLE`] gives.
///
/// A type not listed is an error naming the file, `boundaryField/<patch>/type` and the type
/// ([`scalar_face_values`]).
pub const SCALAR_TABLE: &[(&str, FaceValue)] = &[
    ("fixedValue", FaceValue::Written),
    ("uniformFixedValue", FaceValue::Written),
    ("fixedMean", FaceValue::Written),
    ("fixedProfile", FaceValue::Written),
    ("timeVaryingMappedFixedValue", FaceValue::Written),
    ("turbulentInlet", FaceValue::Written),
    ("totalPressure", FaceValue::Written),
    ("uniformTotalPressure", FaceValue::Written),
    ("calculated", FaceValue::Written),
    ("inletOutlet", FaceValue::Written),
    ("outletInlet", FaceValue::Written),
    ("uniformInletOutlet", FaceValue::Written),
    ("fixedMeanOutletInlet", FaceValue::Written),
    ("freestream", FaceValue::Written),
    ("freestreamPressure", FaceValue::Written),
    ("advective", FaceValue::Written),
    ("waveTransmissive", FaceValue::Written),
    ("fixedGradient", FaceValue::Written),
    ("fixedFluxPressure", FaceValue::Written),
    ("turbulentIntensityKineticEnergyInlet", FaceValue::Written),
    (
        "turbulentMixingLengthDissipationRateInlet",
        FaceValue::Written,
    ),
    ("turbulentMixingLengthFrequencyInlet", FaceValue::Written),
    ("turbulentKineticEnergy", FaceValue::Written),
    ("turbulentEpsilon", FaceValue::Written),
    ("turbulentOmega", FaceValue::Written),
    ("atmBoundaryLayerInletK", FaceValue::Written),
    ("atmBoundaryLayerInletEpsilon", FaceValue::Written),
    ("epsilonWallFunction", FaceValue::Written),
    ("omegaWallFunction", FaceValue::Written),
    ("kLowReWallFunction", FaceValue::Written),
    ("v2WallFunction", FaceValue::Written),
    ("fWallFunction", FaceValue::Written),
    ("nutkWallFunction", FaceValue::Written),
    ("nutkRoughWallFunction", FaceValue::Written),
    ("nutUWallFunction", FaceValue::Written),
    ("nutURoughWallFunction", FaceValue::Written),
    ("nutUSpaldingWallFunction", FaceValue::Written),
    ("nutLowReWallFunction", FaceValue::Written),
    ("nutUBlendedWallFunction", FaceValue::Written),
    ("nutkFilmWallFunction", FaceValue::Written),
    ("nutkAtmRoughWallFunction", FaceValue::Written),
    ("mapped", FaceValue::Written),
    ("mappedValue", FaceValue::Written),
    ("zeroGradient", FaceValue::Owner),
    ("kqRWallFunction", FaceValue::Owner),
    ("slip", FaceValue::Owner),
    ("symmetry", FaceValue::Owner),
    ("symmetryPlane", FaceValue::Owner),
    ("wedge", FaceValue::Owner),
    ("empty", FaceValue::Empty),
    ("cyclic", FaceValue::Unsupported(CYCLIC)),
    ("cyclicAMI", FaceValue::Unsupported(CYCLIC_AMI)),
    ("cyclicACMI", FaceValue::Unsupported(CYCLIC_ACMI)),
    ("cyclicSlip", FaceValue::Unsupported(CYCLIC_SLIP)),
    ("processor", FaceValue::Unsupported(PROCESSOR)),
];

/// What scalar type `kind` means, `None` when it is not in [`SCALAR_TABLE`].
pub fn lookup_scalar(kind: &str) -> Option<FaceValue> {
    SCALAR_TABLE
        .iter()
        .find(|(k, _)| *k == kind)
        .map(|&(_, v)| v)
}

/// The names of [`SCALAR_TABLE`], comma-separated (for messages).
pub fn known_scalar_types() -> String {
    SCALAR_TABLE
        .iter()
        .map(|(k, _)| *k)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The face values of `patch` of a scalar field for boundary-condition type `kind`:
/// `Ok(None)` for the owner's values, `Ok(Some(v))` with one value per face (the
/// `written` values of the entry's `value`), `Err(message)` for a type not in
/// [`SCALAR_TABLE`], a refused one, or a `Written` type without its values.
pub fn scalar_face_values(
    kind: &str,
    written: Option<Vec<f64>>,
) -> Result<Option<Vec<f64>>, String> {
    let Some(meaning) = lookup_scalar(kind) else {
        return Err(format!(
            "unknown boundary condition type '{kind}' for a scalar (scg reads: {})",
            known_scalar_types()
        ));
    };
    match meaning {
        FaceValue::Written => match written {
            Some(v) => Ok(Some(v)),
            None => Err(missing_value(kind)),
        },
        FaceValue::Unsupported(why) => Err(format!("type '{kind}' is not supported: {why}")),
        // Zero and Tangential are vector kinds, not in the scalar table.
        FaceValue::Owner | FaceValue::Empty | FaceValue::Zero | FaceValue::Tangential => Ok(None),
    }
}

/// The message for a `Written` type without a `value` entry.
fn missing_value(kind: &str) -> String {
    format!(
        "type '{kind}' without a `value` entry (OpenFOAM writes the evaluated face values \
         there; run the solver or foamFormatConvert to write them)"
    )
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
        for (i, (k, v)) in SCALAR_TABLE.iter().enumerate() {
            assert!(
                SCALAR_TABLE[i + 1..].iter().all(|(j, _)| j != k),
                "{k} listed twice"
            );
            assert!(!matches!(v, FaceValue::Zero | FaceValue::Tangential), "{k}");
            // A type both tables list means the same for both, but for the mirror types.
            if let Some(u) = lookup(k)
                && u != FaceValue::Tangential
            {
                assert_eq!(u, *v, "{k}");
            }
        }
        assert_eq!(lookup_scalar("kqRWallFunction"), Some(FaceValue::Owner));
        assert_eq!(lookup_scalar("noSlip"), None);
        assert!(known_scalar_types().contains("nutkWallFunction"));
    }
}
