//! `[flow] series`: an OpenFOAM case's time directories as one unsteady field
//! ([`scg_core::physics::mesh_flow::series`]).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use scg_core::physics::mesh_flow::series::{FlowSeriesSpec, SeriesClock, SnapshotLoader};
use scg_core::physics::mesh_flow::{MeshFlow, WallFunctionSpec};
use scg_mesh::PolyMesh;
use scg_mesh::foam::{self, TimeSel};

use scg_core::physics::dispersion::Turbulence;
use scg_core::physics::mesh_flow::series::Snapshot;
use scg_core::stages::carrier::Dispersion;

use super::Ctx;
use super::dispersion::{TurbulenceFields, read_turbulence};
use crate::error::SceneError;
use crate::model::{FieldReader, SceneMeshFlow, SceneSeries};
use crate::raw::{RawFlow, RawScene, RawSeries};

/// The window `[start, end]` of `s`, s of CFD time (open where not given).
fn bounds(s: &RawSeries, cx: &Ctx) -> Result<(f64, f64), SceneError> {
    let start = match s.start {
        Some(t) => cx.finite("flow.series.start", t)?,
        None => f64::NEG_INFINITY,
    };
    let end = match s.end {
        Some(t) => cx.finite("flow.series.end", t)?,
        None => f64::INFINITY,
    };
    if start >= end {
        return Err(cx.err("flow.series.end", "must be after flow.series.start"));
    }
    Ok((start, end))
}

/// The snapshots of `all` (time, folder or file) within `[start, end]` of the series `s`
/// (to rounding), at least two; `what` names them in the error (one, several), `shown`
/// where they come from.
fn in_window(
    all: Vec<(f64, PathBuf)>,
    (start, end): (f64, f64),
    s: &RawSeries,
    (shown, what): (&dyn std::fmt::Display, (&str, &str)),
    cx: &Ctx,
) -> Result<Vec<(f64, PathBuf)>, SceneError> {
    let tol = |t: f64| 1e-12 * t.abs().max(1.0);
    let steps: Vec<(f64, PathBuf)> = all
        .into_iter()
        .filter(|(t, _)| *t >= start - tol(start) && *t <= end + tol(end))
        .collect();
    if steps.len() < 2 {
        let window = format!(
            "[{}, {}]",
            s.start.map_or("first".into(), |t| t.to_string()),
            s.end.map_or("last".into(), |t| t.to_string())
        );
        return Err(cx.err(
            "flow.series",
            format!(
                "{shown}: {} {} in the window {window}: a series needs at least two",
                steps.len(),
                if steps.len() == 1 { what.0 } else { what.1 },
            ),
        ));
    }
    Ok(steps)
}

/// The time directories of `case` in the window of `s` (at least two), each holding
/// `field` and no mesh of its own.
pub(super) fn window(
    s: &RawSeries,
    case: &Path,
    field: &str,
    cx: &Ctx,
) -> Result<Vec<(f64, PathBuf)>, SceneError> {
    let shown = case.display();
    let (start, end) = bounds(s, cx)?;
    let all = foam::time_dirs(case).map_err(|e| cx.err("flow.case", format!("{shown}: {e}")))?;
    let what = ("time directory", "time directories");
    let dirs = in_window(all, (start, end), s, (&shown, what), cx)?;
    for (_, d) in &dirs {
        if d.join("polyMesh").exists() {
            return Err(cx.err(
                "flow.series",
                format!(
                    "{}: has a polyMesh of its own: the mesh changes in time, and a series \
                     needs one mesh (constant/polyMesh) for all its snapshots",
                    d.display()
                ),
            ));
        }
        let file = d.join(field);
        let gz = d.join(format!("{field}.gz"));
        if !file.is_file() && !gz.is_file() {
            return Err(cx.err(
                "flow.series",
                format!(
                    "{}: no field `{field}` in this time directory of the window",
                    d.display()
                ),
            ));
        }
    }
    Ok(dirs)
}

/// Reads snapshot k's velocity field, as its file gives it (an error names the file).
pub(super) type FieldRead = dyn Fn(usize) -> Result<scg_mesh::CellField, String> + Send + Sync;

/// Snapshot k's field of an OpenFOAM series: `field` in the time folder of `times[k]` of
/// `case`, on `read_mesh` (the mesh as the case gives it).
pub(super) fn foam_read(
    case: &Path,
    field: &str,
    read_mesh: Arc<PolyMesh>,
    times: Vec<f64>,
) -> Arc<FieldRead> {
    let (case, field) = (case.to_path_buf(), field.to_string());
    Arc::new(move |k: usize| {
        foam::read_vector_field(&case, &read_mesh, TimeSel::Time(times[k]), &field).map_err(|e| {
            let dir = case.join(format!("{}", times[k]));
            format!("{}: field `{field}`: {e}", dir.display())
        })
    })
}

/// Snapshot k's field of a VTK series: `field` of `files[k]`, whose mesh must be
/// `read_mesh` (the first file's) point for point and face for face.
pub(super) fn vtk_read(
    files: Vec<PathBuf>,
    field: &str,
    read_mesh: Arc<PolyMesh>,
) -> Arc<FieldRead> {
    let field = field.to_string();
    Arc::new(move |k: usize| {
        let file = &files[k];
        let (mesh, u) = scg_mesh::vtk::read(file, &field)
            .map_err(|e| format!("{}: field `{field}`: {e}", file.display()))?;
        if mesh != *read_mesh {
            return Err(format!(
                "{}: its mesh is not the series' first file's ({} cells and {} points \
                 against {} and {}, or moved points): a series needs one mesh for all its \
                 snapshots",
                file.display(),
                mesh.n_cells,
                mesh.points.len(),
                read_mesh.n_cells,
                read_mesh.points.len()
            ));
        }
        Ok(u)
    })
}

/// The time steps of the collection `pvd` in the window of `s` (at least two).
pub(super) fn vtk_window(
    s: &RawSeries,
    pvd: &Path,
    cx: &Ctx,
) -> Result<Vec<(f64, PathBuf)>, SceneError> {
    let shown = pvd.display();
    let all = scg_mesh::vtk::read_pvd(pvd).map_err(|e| cx.err("flow.file", e.to_string()))?;
    let bounds = bounds(s, cx)?;
    let steps = in_window(all, bounds, s, (&shown, ("time step", "time steps")), cx)?;
    if let Some((_, f)) = steps.iter().find(|(_, f)| !f.is_file()) {
        return Err(cx.err(
            "flow.file",
            format!("{shown}: lists {}, which is not a file", f.display()),
        ));
    }
    Ok(steps)
}

/// The series of the snapshots `steps` (time, folder or file) read by `read` on the flow
/// `first` (snapshot 0): its clock, its loader (each snapshot's field built on `first`'s
/// mesh with `wall`) and snapshot 1, read now.
pub(super) fn series(
    s: &RawSeries,
    steps: Vec<(f64, PathBuf)>,
    read: Arc<FieldRead>,
    first: &Arc<MeshFlow>,
    wall: Option<WallFunctionSpec>,
    cx: &Ctx,
) -> Result<SceneSeries, SceneError> {
    let times: Vec<f64> = steps.iter().map(|(t, _)| *t).collect();
    let clock = SeriesClock::new(&times, s.cycle).map_err(|e| cx.err("flow.series", e))?;
    // the change across the seam of a cycling window, relative to the field's rms (the
    // last snapshot's cells only: no flow is built for it)
    let seam = match s.cycle {
        true => {
            let last = read(times.len() - 1).map_err(|e| cx.err("flow.series", e))?;
            Some(seam_change(first.cell_values(), &last.cells))
        }
        false => None,
    };
    let base = Arc::clone(first);
    let load: Arc<SnapshotLoader> = Arc::new(move |k: usize| {
        let u = read(k)?;
        let flow = base
            .snapshot(&u, wall.as_ref())
            .map_err(|e| format!("snapshot {k} of the series: {e}"))?;
        Ok(Snapshot {
            flow: Arc::new(flow),
            turbulence: None,
        })
    });
    let second = load(1).map_err(|e| cx.err("flow.series", e))?;
    Ok(SceneSeries {
        spec: FlowSeriesSpec {
            clock,
            load,
            second,
            first_turbulence: None,
        },
        times,
        dirs: steps.into_iter().map(|(_, d)| d).collect(),
        seam,
    })
}

/// ‖U_last − U_first‖ / ‖U_first‖ over the cells (rms of each).
fn seam_change(a: &[glam::DVec3], b: &[glam::DVec3]) -> f64 {
    let d: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*y - *x).length_squared())
        .sum();
    let n: f64 = a.iter().map(|x| x.length_squared()).sum();
    if n > 0.0 { (d / n).sqrt() } else { 0.0 }
}

/// A series under `[dispersion]` by the CFD's fields: each snapshot reads the same k and
/// ε (or ω) fields from its own time folder (or file), snapshot 0's being the dispersion's.
pub(super) fn with_turbulence(
    m: &mut SceneMeshFlow,
    d: &Dispersion,
    fields: TurbulenceFields,
    cx: &Ctx,
) -> Result<(), SceneError> {
    let (Some(first_reader), Some(s)) = (m.reader.clone(), m.series.as_mut()) else {
        return Ok(());
    };
    let Turbulence::Cells(first) = &d.turbulence else {
        return Ok(());
    };
    let base = Arc::clone(&m.flow);
    let (times, sources) = (s.times.clone(), s.dirs.clone());
    // snapshot k's fields: the same names in its time folder, or in its file
    let read = move |k: usize| {
        let reader = match &first_reader {
            FieldReader::Foam { case, .. } => FieldReader::Foam {
                case: case.clone(),
                time: TimeSel::Time(times[k]),
            },
            FieldReader::Vtk { .. } => FieldReader::Vtk {
                file: sources[k].clone(),
            },
        };
        read_turbulence(&fields, &reader, base.mesh(), base.geometry()).map(Arc::new)
    };
    let second = read(1).map_err(|(key, e)| cx.err(key, format!("series snapshot 1: {e}")))?;
    let flows = Arc::clone(&s.spec.load);
    s.spec.load = Arc::new(move |k: usize| {
        let mut snap = flows(k)?;
        snap.turbulence = Some(read(k).map_err(|(key, e)| format!("{key}: {e}"))?);
        Ok(snap)
    });
    s.spec.second.turbulence = Some(second);
    s.spec.first_turbulence = Some(Arc::clone(first));
    Ok(())
}

/// What a series does not carry yet, refused by name; a run past the end of a window
/// that does not cycle.
pub(super) fn supported(
    raw: &RawScene,
    series: &SceneSeries,
    duration: f64,
    cx: &Ctx,
) -> Result<(), SceneError> {
    let no = |key: &str, why: &str| -> Result<(), SceneError> {
        Err(cx.err(
            key,
            format!("cannot be combined with flow.series yet: {why}"),
        ))
    };
    if let Some(f) = &raw.forces {
        for (key, on) in [
            ("forces.pressure_gradient", f.pressure_gradient),
            ("forces.added_mass", f.added_mass.is_some()),
            ("forces.rubinow_keller", f.rubinow_keller),
        ] {
            if on {
                return no(
                    key,
                    "it needs Du/Dt (or the fluid's spin) with the field's change in time",
                );
            }
        }
    }
    let span = series.spec.clock.span();
    if !series.spec.clock.cycles() && duration > span * (1.0 + 1e-12) {
        return Err(cx.err(
            "duration",
            format!(
                "{duration} s runs past the series' window ({span} s from t = {}): set \
                 flow.series.cycle = true to repeat it, or shorten the run",
                series.start()
            ),
        ));
    }
    Ok(())
}

/// The keys of `[flow]` a series refuses (`flow.time` picks one snapshot).
pub(super) fn no_time(f: &RawFlow, cx: &Ctx) -> Result<(), SceneError> {
    if f.time.is_some() {
        return Err(cx.err(
            "flow.time",
            "picks one snapshot; flow.series reads a window of them (give one or the other)",
        ));
    }
    Ok(())
}
