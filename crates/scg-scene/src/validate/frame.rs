//! `[frame]` (a rotating frame) and whether it matches the OpenFOAM case the flow comes
//! from: an SRF solution (`constant/SRFProperties`, field `Urel`) is relative to its
//! frame, so it is tracked only in that frame; any other case's `U` is absolute (an MRF
//! case's too: its zones are read by [`super::mrf`]).

use glam::DVec3;
use scg_core::physics::drag::DragLaw;
use scg_core::physics::flow::{rad_per_s_to_rpm, rpm_to_rad_per_s};
use scg_mesh::foam;

use super::Ctx;
use crate::error::SceneError;
use crate::raw::{RawFlowKind, RawScene};

/// `[frame]`: Ω = axis·rpm·2π/60 about `center`; the particles move through the fluid, so
/// it needs `[drag]`, and gravity (constant in the absolute frame) must lie along the
/// axis to stay constant in the rotating one.
pub(super) fn frame(
    raw: &RawScene,
    drag: Option<DragLaw>,
    cx: &Ctx,
) -> Result<Option<scg_core::physics::forces::RotatingFrame>, SceneError> {
    let Some(f) = &raw.frame else {
        return Ok(None);
    };
    if drag.is_none() {
        return Err(cx.err(
            "frame",
            "tracks particles through a rotating flow: the scene needs [fluid] and [drag]",
        ));
    }
    let (axis, omega, centre) = declared(f, cx)?;
    if let Some(g) = &raw.gravity {
        let g = DVec3::from_array(g.acceleration);
        if g.cross(axis).length() > 1e-12 * g.length() {
            return Err(cx.err(
                "frame.axis",
                "gravity must lie along the frame's axis (in a frame turning about another \
                 axis it would turn too)",
            ));
        }
    }
    Ok(Some(scg_core::physics::forces::RotatingFrame {
        omega,
        centre,
    }))
}

/// The unit axis, the angular velocity (rad/s) and the centre (m) `[frame]` declares.
fn declared(f: &crate::raw::RawFrame, cx: &Ctx) -> Result<(DVec3, DVec3, DVec3), SceneError> {
    let axis = cx.unit("frame.axis", f.axis)?;
    let omega = axis * rpm_to_rad_per_s(cx.finite("frame.rpm", f.rpm)?);
    let centre = cx.vec3("frame.center", f.center.unwrap_or([0.0; 3]))?;
    Ok((axis, omega, centre))
}

/// Relative tolerance of the match between `[frame]` and the case's `SRFProperties`.
const MATCH: f64 = 1e-9;

/// The `[frame]` and the OpenFOAM case of `[flow]` must agree on which frame the velocity
/// is in:
/// * a case with `constant/SRFProperties` (a single-rotating-frame solution) is read
///   through its relative velocity (`Urel`, or a field named from it such as the time
///   average `UrelMean`) in a `[frame]` equal to the case's (rate, axis,
///   and an axis through the case's origin placed by `flow.scale`/`flow.translate`);
/// * a case with `constant/MRFProperties` (frozen rotor) is read in the absolute frame (no
///   `[frame]`) through its absolute `U`; its active zones are returned, origins placed,
///   for [`super::mrf::rotor_faces`];
/// * `[frame]` with any other OpenFOAM case is an error (its `U` is absolute).
///
/// Run before the mesh is read, so that `field = "U"` in an SRF case is named as such
/// rather than as a missing file.
pub(super) fn case_frame(raw: &RawScene, cx: &Ctx) -> Result<Vec<foam::MrfZone>, SceneError> {
    let Some(flow) = &raw.flow else {
        return Ok(Vec::new());
    };
    if flow.kind != RawFlowKind::Openfoam {
        return Ok(Vec::new());
    }
    let Some(case) = &flow.case else {
        return Ok(Vec::new());
    };
    let dir = cx.base.join(case);
    if !dir.is_dir() {
        return Ok(Vec::new()); // the mesh reader names it
    }
    let shown = dir.display().to_string();
    let srf = foam::read_srf(&dir).map_err(|e| cx.err("flow.case", e.to_string()))?;
    let mrf = foam::read_mrf(&dir).map_err(|e| cx.err("flow.case", e.to_string()))?;
    let field = flow.field.as_deref().unwrap_or("U");
    let scale = flow.scale.unwrap_or(1.0);
    let translate = DVec3::from_array(flow.translate.unwrap_or([0.0; 3]));
    let zones: Vec<foam::MrfZone> = mrf
        .unwrap_or_default()
        .into_iter()
        .filter(|z| z.active)
        .map(|z| foam::MrfZone {
            origin: translate + scale * z.origin,
            ..z
        })
        .collect();
    if let Some(z) = zones.first() {
        if srf.is_some() {
            return Err(cx.err(
                "flow.case",
                format!("{shown} has both constant/SRFProperties and constant/MRFProperties"),
            ));
        }
        if raw.frame.is_some() {
            return Err(cx.err(
                "frame",
                format!(
                    "{shown} is a frozen-rotor (MRF) solution (constant/MRFProperties zone \
                     `{}`): its `{field}` is absolute, so the particles are tracked in the \
                     absolute frame; remove [frame]",
                    z.name
                ),
            ));
        }
        return Ok(zones);
    }
    match (srf, &raw.frame) {
        (Some(s), frame) => {
            let origin = translate + scale * s.origin;
            let declare = format!(
                "[frame] rpm = {}, axis = [{}, {}, {}], center = [{}, {}, {}]",
                s.rpm, s.axis.x, s.axis.y, s.axis.z, origin.x, origin.y, origin.z
            );
            if !field.starts_with("Urel") {
                return Err(cx.err(
                    "flow.field",
                    format!(
                        "{shown} is a single-rotating-frame solution (constant/SRFProperties): \
                         its velocity is `Urel` (or its time average `UrelMean`), relative to \
                         the frame (an absolute `{field}` of a rotating geometry is not \
                         steady); set field = \"Urel\" and {declare}"
                    ),
                ));
            }
            let Some(f) = frame else {
                return Err(cx.err(
                    "frame",
                    format!(
                        "missing: {shown}'s Urel is relative to its rotating frame \
                         (constant/SRFProperties); declare {declare}"
                    ),
                ));
            };
            let (axis, omega, centre) = declared(f, cx)?;
            let want = s.omega();
            let off_axis = (centre - origin).cross(s.axis).length();
            if (omega - want).length() > MATCH * want.length().max(f64::MIN_POSITIVE)
                || off_axis > MATCH * origin.length().max(scale)
            {
                return Err(cx.err(
                    "frame",
                    format!(
                        "differs from {shown}'s constant/SRFProperties (the frame its Urel \
                         is relative to): the scene says {} rpm about {:?} through {:?}; \
                         the case says {declare}",
                        rad_per_s_to_rpm(omega.length()),
                        axis,
                        centre
                    ),
                ));
            }
            Ok(Vec::new())
        }
        (None, Some(_)) => Err(cx.err(
            "frame",
            format!(
                "{shown} has no constant/SRFProperties: its `{field}` is in the absolute \
                 frame, so it cannot be tracked in a rotating [frame] (remove [frame], or \
                 read an SRFSimpleFoam case's Urel)"
            ),
        )),
        (None, None) => Ok(Vec::new()),
    }
}
