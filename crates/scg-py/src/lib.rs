//! `scg._scg`: the native module of scg's Python package (`python/scg`).
//!
//! A thin layer over the library: scenes are loaded and validated by `scg_scene`, run by
//! `scg_core`, recorded by `scg_record`, and the end tables (fates, summary, erosion) are
//! scg-cli's own, so a run from Python gives what `scg run` gives, bit for bit. The
//! Python side (`python/scg/__init__.py`) turns what this module returns into numpy
//! arrays and pandas tables; no physics or analysis is written again there.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use pyo3::exceptions::{PyKeyError, PyKeyboardInterrupt, PyOSError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use scg_core::exec::{self, ExecSettings};
use scg_core::frame::{Frame, FrameSink, RunMeta};
use scg_record::McapFrames;
use scg_scene::{Scene, SceneError};

mod convert;

use convert::{frame_dict, meta_dict, toml_to_py};

/// Steps between two progress calls (and checks for Ctrl-C), as `scg run`'s bar.
const PROGRESS_EVERY: u64 = 256;

/// A `SceneError` of the Python package (`scg.SceneError`: file, key, line, message).
fn scene_error(py: Python<'_>, e: &SceneError) -> PyErr {
    let made = py
        .import("scg._errors")
        .and_then(|m| m.getattr("SceneError"))
        .and_then(|c| {
            c.call1((
                e.to_string(),
                e.file.clone(),
                e.key.clone(),
                e.line,
                e.message.clone(),
            ))
        });
    match made {
        Ok(v) => PyErr::from_value(v),
        Err(err) => err,
    }
}

/// An error of the package's own class `name` (in `scg._errors`) with `args`.
fn package_error<'py>(py: Python<'py>, name: &str, args: impl IntoPyObject<'py>) -> PyErr {
    let made = py
        .import("scg._errors")
        .and_then(|m| m.getattr(name))
        .and_then(|c| c.call1((args,)));
    match made {
        Ok(v) => PyErr::from_value(v),
        Err(err) => err,
    }
}

/// A validated scene and the `--set` edits it was loaded with.
#[pyclass(name = "NativeScene", module = "scg._scg", frozen)]
struct NativeScene {
    scene: Scene,
    sets: Vec<String>,
}

/// Load the scene file `path` with the `key=value` edits `sets` (as `--set`).
#[pyfunction]
fn load_scene(py: Python<'_>, path: PathBuf, sets: Vec<String>) -> PyResult<NativeScene> {
    let scene = scg_scene::load(&path, &sets).map_err(|e| scene_error(py, &e))?;
    Ok(NativeScene { scene, sets })
}

/// Parse scene text; `file` names it in errors and its folder resolves relative paths.
#[pyfunction]
fn parse_scene(
    py: Python<'_>,
    text: &str,
    file: &str,
    stem: &str,
    sets: Vec<String>,
) -> PyResult<NativeScene> {
    let scene = scg_scene::parse(text, file, stem, &sets).map_err(|e| scene_error(py, &e))?;
    Ok(NativeScene { scene, sets })
}

/// The embedded default scene (the paper's vortex case), as `scg run` with no file.
#[pyfunction]
fn embedded_scene(py: Python<'_>, sets: Vec<String>) -> PyResult<NativeScene> {
    let scene = Scene::embedded(&sets).map_err(|e| scene_error(py, &e))?;
    Ok(NativeScene { scene, sets })
}

/// The figures and files of a finished run.
struct Outcome {
    summary: String,
    fates_csv: String,
    erosion_csv: Option<String>,
    paths: Vec<PathBuf>,
}

/// Calls a Python callable with each recorded frame (as [`frame_dict`]).
struct CallbackSink {
    callback: Py<PyAny>,
    error: Arc<Mutex<Option<PyErr>>>,
}

impl FrameSink for CallbackSink {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), String> {
        self.write_shared(&Arc::new(frame.clone()))
    }

    fn write_shared(&mut self, frame: &Arc<Frame>) -> Result<(), String> {
        Python::attach(|py| {
            let called = frame_dict(py, frame).and_then(|d| self.callback.call1(py, (d,)));
            called.map(|_| ()).map_err(|e| {
                let msg = format!("on_frame: {e}");
                *self.error.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                msg
            })
        })
    }

    fn finish(&mut self) -> Result<(), String> {
        Ok(())
    }
}

#[pymethods]
impl NativeScene {
    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The file it came from (`<embedded …>`, `<string>`…).
    #[getter]
    fn file(&self) -> String {
        self.scene.file.clone()
    }

    /// Its TOML text with the edits applied.
    #[getter]
    fn source(&self) -> String {
        self.scene.source.clone()
    }

    /// The edits it was loaded with (`key=value`).
    #[getter]
    fn sets(&self) -> Vec<String> {
        self.sets.clone()
    }

    /// Time step, s (resolved when `auto`).
    #[getter]
    fn dt(&self) -> f64 {
        self.scene.dt
    }

    /// Simulated duration, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.scene.duration
    }

    /// Steps of a run.
    #[getter]
    fn steps(&self) -> u64 {
        self.scene.steps()
    }

    /// The value at a dotted key path (`groups.0.alpha`, as `--set`) of the scene's text.
    fn value<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let doc: toml::Table = self
            .scene
            .source
            .parse()
            .map_err(|e| PyRuntimeError::new_err(format!("{}: {e}", self.scene.file)))?;
        let mut at = toml::Value::Table(doc);
        for part in key.split('.') {
            let next = match &at {
                toml::Value::Table(t) => t.get(part).cloned(),
                toml::Value::Array(a) => part.parse::<usize>().ok().and_then(|i| a.get(i).cloned()),
                _ => None,
            };
            at = next.ok_or_else(|| {
                PyKeyError::new_err(format!(
                    "{}: no key `{key}` in the scene (written or set); defaults are in \
                     docs/scenes.md",
                    self.scene.file
                ))
            })?;
        }
        toml_to_py(py, &at)
    }

    /// `scg check`: the derived quantities per group, the scene's figures and findings,
    /// and the text `scg check` prints.
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = scg_scene::check::check(&self.scene);
        let d = PyDict::new(py);
        let groups = PyList::empty(py);
        for g in &r.groups {
            let row = PyDict::new(py);
            row.set_item("name", &g.name)?;
            row.set_item("law", g.law)?;
            row.set_item("alpha", g.alpha)?;
            row.set_item("count", g.count)?;
            row.set_item("diameter", g.diameter)?;
            row.set_item("density", g.density)?;
            row.set_item("tau", g.tau)?;
            row.set_item("slip", g.slip)?;
            row.set_item("reynolds", g.reynolds)?;
            row.set_item("density_ratio", g.density_ratio)?;
            row.set_item("contact_time", g.contact_time)?;
            groups.append(row)?;
        }
        d.set_item("groups", groups)?;
        d.set_item("stokes_number", r.stokes_number)?;
        d.set_item("dt", r.dt)?;
        d.set_item("steps", r.steps)?;
        let findings = PyList::empty(py);
        for f in &r.findings {
            findings.append((f.level.name(), &f.message))?;
        }
        d.set_item("findings", findings)?;
        d.set_item("text", scg_scene::check::render(&self.scene, &r))?;
        Ok(d)
    }

    /// The systems a run of this scene executes, in order (`scg run --plan`).
    fn plan(&self) -> String {
        self.scene.build(true).plan().render()
    }

    /// Run the scene: see `scg.Scene.run`. Returns the summary (JSON text, as
    /// `--summary-json`), the fates (CSV, as `--fates-csv`), the erosion table (CSV, as
    /// `--erosion-csv`) and the files written.
    #[pyo3(signature = (out, record, vtk, frames_csv, threads, progress, on_frame))]
    #[allow(clippy::too_many_arguments)]
    fn run<'py>(
        &self,
        py: Python<'py>,
        out: PathBuf,
        record: bool,
        vtk: Option<PathBuf>,
        frames_csv: Option<PathBuf>,
        threads: Option<usize>,
        progress: Option<Py<PyAny>>,
        on_frame: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let scene = &self.scene;
        let report = scg_scene::check::check(scene);
        if report.has_errors() {
            return Err(package_error(py, "CheckError", report.messages()));
        }
        if record {
            scg_cli::run::ensure_writable(&out).map_err(PyOSError::new_err)?;
        }
        let settings = ExecSettings {
            threads: threads.unwrap_or(exec::settings().threads),
            ..*exec::settings()
        };
        let frame_error = Arc::new(Mutex::new(None::<PyErr>));
        let call_error = Arc::new(Mutex::new(None::<PyErr>));
        let interrupted = std::sync::atomic::AtomicBool::new(false);
        let run = || -> Result<Outcome, String> {
            let frames = record || vtk.is_some() || frames_csv.is_some() || on_frame.is_some();
            let mut sim = scene.build(frames);
            let stem = format!(
                "{}{}",
                scg_cli::run::recording_stem(scene),
                scg_cli::run::set_suffix(&self.sets)
            );
            let mut paths = Vec::new();
            if frames {
                let meta: RunMeta = scene.run_meta(report.messages());
                let (sinks, written) =
                    scg_cli::run::frame_sinks(&meta, &out, &stem, record, &vtk, &frames_csv)
                        .map_err(|e| e.to_string())?;
                paths = written;
                if !sinks.is_empty() {
                    sim.add_recorder(Box::new(scg_record::Background::spawn(sinks)));
                }
                if let Some(cb) = &on_frame {
                    sim.add_recorder(Box::new(CallbackSink {
                        callback: Python::attach(|py| cb.clone_ref(py)),
                        error: Arc::clone(&frame_error),
                    }));
                }
            }
            let steps = scene.steps();
            let t0 = std::time::Instant::now();
            let mut result = sim.record_now().map(|_| 0);
            if result.is_ok() {
                result = sim.run(steps, |i| {
                    if i % PROGRESS_EVERY != 0 && i != steps {
                        return true;
                    }
                    Python::attach(|py| {
                        if let Err(e) = py.check_signals() {
                            interrupted.store(true, std::sync::atomic::Ordering::Relaxed);
                            *call_error.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                            return false;
                        }
                        if let Some(p) = &progress
                            && let Err(e) = p.call1(py, (i, steps))
                        {
                            *call_error.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                            return false;
                        }
                        true
                    })
                });
            }
            let wall = t0.elapsed().as_secs_f64();
            let fin = sim.finish_recorders();
            result.map_err(|e| e.to_string())?;
            fin.map_err(|e| e.to_string())?;
            let fates = scg_cli::fates::fates(scene, &mut sim);
            let by_mass = scg_cli::distribution::by_mass(scene, &fates);
            let erosion_csv =
                scg_cli::erosion::rows(scene, &sim).map(|r| scg_cli::erosion::csv(&r));
            let figures = scg_cli::run::RunFigures {
                steps: sim.step_count(),
                dt: scene.dt,
                time: sim.time(),
                particle_steps: sim.particle_steps(),
                wall_s: wall,
                threads: exec::settings().team_size(),
            };
            let summary = scg_cli::tables::summary(scene, &mut sim, &fates, &by_mass, &figures);
            Ok(Outcome {
                summary: serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?,
                fates_csv: scg_cli::fates::csv(&fates),
                erosion_csv,
                paths,
            })
        };
        let outcome = py.detach(|| exec::with_settings(settings, run));
        // A Python error raised in a callback (or Ctrl-C) wins over the run's own message.
        for slot in [&call_error, &frame_error] {
            if let Some(e) = slot.lock().unwrap_or_else(|p| p.into_inner()).take() {
                if interrupted.load(std::sync::atomic::Ordering::Relaxed) {
                    return Err(PyKeyboardInterrupt::new_err(
                        "the run was interrupted; its recordings are closed",
                    ));
                }
                return Err(e);
            }
        }
        let o = outcome.map_err(|e| package_error(py, "RunError", e))?;
        let d = PyDict::new(py);
        d.set_item("summary", o.summary)?;
        d.set_item("fates_csv", o.fates_csv)?;
        d.set_item("erosion_csv", o.erosion_csv)?;
        let paths: Vec<String> = o.paths.iter().map(|p| p.display().to_string()).collect();
        d.set_item("paths", paths)?;
        Ok(d)
    }
}

/// Where a recording's frames come from: read as they are asked for, or (a per-rank
/// recording's index) merged from its parts first.
enum Source {
    Stream(Box<McapFrames>),
    Merged(std::collections::VecDeque<Frame>),
}

/// An MCAP recording read one frame at a time.
#[pyclass(name = "NativeRecording", module = "scg._scg", frozen)]
struct NativeRecording {
    source: Mutex<Source>,
    meta: RunMeta,
    /// Whether the file was closed properly and the wear (JSON), once known.
    end: Mutex<(bool, Option<String>)>,
}

/// Open an MCAP recording written by scg.
#[pyfunction]
fn open_recording(py: Python<'_>, path: PathBuf) -> PyResult<NativeRecording> {
    let opened = py.detach(|| -> Result<_, String> {
        let frames = McapFrames::open(&path).map_err(|e| e.to_string())?;
        if frames.meta().parts.is_empty() {
            let meta = frames.meta().clone();
            return Ok((Source::Stream(Box::new(frames)), meta, (false, None)));
        }
        let rec = scg_record::read_mcap(&path).map_err(|e| e.to_string())?;
        let wear = rec
            .wear
            .as_ref()
            .and_then(|w| serde_json::to_string(w).ok());
        Ok((
            Source::Merged(rec.frames.into()),
            rec.meta,
            (rec.complete, wear),
        ))
    });
    let (source, meta, end) = opened.map_err(|e| package_error(py, "RecordingError", e))?;
    Ok(NativeRecording {
        source: Mutex::new(source),
        meta,
        end: Mutex::new(end),
    })
}

#[pymethods]
impl NativeRecording {
    /// The run description: case, version, seed, dt, groups, scene text, warnings.
    fn meta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        meta_dict(py, &self.meta)
    }

    /// The next frame (a dict of arrays as bytes), or `None` after the last.
    fn next_frame<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let mut source = self.source.lock().unwrap_or_else(|p| p.into_inner());
        let next = match &mut *source {
            Source::Merged(frames) => frames.pop_front().map(Ok),
            Source::Stream(frames) => {
                let n = py.detach(|| frames.next());
                if n.is_none() {
                    let wear = frames.wear().and_then(|w| serde_json::to_string(w).ok());
                    *self.end.lock().unwrap_or_else(|p| p.into_inner()) = (frames.complete(), wear);
                }
                n.map(|r| r.map_err(|e| e.to_string()))
            }
        };
        match next {
            None => Ok(None),
            Some(Ok(f)) => frame_dict(py, &Arc::new(f)).map(Some),
            Some(Err(e)) => Err(package_error(py, "RecordingError", e)),
        }
    }

    /// Whether the file was closed properly (known once every frame was read) and the
    /// wear of an erosion run as JSON.
    fn end(&self) -> (bool, Option<String>) {
        self.end.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }
}

/// Run a study (`scg study NAME`) into `out`; returns `scg study`'s exit status.
#[pyfunction]
#[pyo3(signature = (name, quick, out, sets, record, threads))]
fn study(
    py: Python<'_>,
    name: String,
    quick: bool,
    out: PathBuf,
    sets: Vec<String>,
    record: bool,
    threads: Option<usize>,
) -> i32 {
    let settings = ExecSettings {
        threads: threads.unwrap_or(exec::settings().threads),
        ..*exec::settings()
    };
    let args = scg_cli::study::StudyArgs {
        quick,
        out: Some(out),
        no_record: !record,
        set: sets,
        ..scg_cli::study::StudyArgs::new(&name)
    };
    py.detach(|| {
        exec::with_settings(settings, || {
            scg_cli::study::study(args, &scg_cli::points::Local)
        })
    })
}

/// The version of the scg engine.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _scg(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<NativeScene>()?;
    m.add_class::<NativeRecording>()?;
    m.add_class::<convert::Column>()?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(parse_scene, m)?)?;
    m.add_function(wrap_pyfunction!(embedded_scene, m)?)?;
    m.add_function(wrap_pyfunction!(open_recording, m)?)?;
    m.add_function(wrap_pyfunction!(study, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    Ok(())
}
