//! Frames, run descriptions and TOML values as Python objects.

use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use scg_core::frame::{Frame, RunMeta};

/// A column of a frame, as numpy reads it: its `__array_interface__` points into the
/// frame's own buffer, which the column (the array's `base`) keeps alive; no copy is made.
/// Read-only: the frame may be shared with the run's recorders.
#[pyclass(frozen, module = "scg._scg")]
pub struct Column {
    frame: Arc<Frame>,
    which: Which,
}

#[derive(Clone, Copy)]
enum Which {
    Id,
    Group,
    Position,
    Velocity,
    Diameter,
    Density,
    Fluctuation,
}

#[pymethods]
impl Column {
    /// numpy's array interface (version 3): shape, type, address, read-only.
    #[getter]
    fn __array_interface__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = &*self.frame;
        let end = if cfg!(target_endian = "little") {
            "<"
        } else {
            ">"
        };
        fn raw<T>(v: &[T]) -> (usize, usize) {
            (v.as_ptr() as usize, v.len())
        }
        let ((ptr, rows), wide, ty) = match self.which {
            Which::Id => (raw(&f.id), false, "u4"),
            Which::Group => (raw(&f.group), false, "u4"),
            Which::Position => (raw(&f.position), true, "f8"),
            Which::Velocity => (raw(&f.velocity), true, "f8"),
            Which::Diameter => (raw(&f.diameter), false, "f8"),
            Which::Density => (raw(&f.density), false, "f8"),
            Which::Fluctuation => (raw(&f.fluctuation), false, "f8"),
        };
        let d = PyDict::new(py);
        d.set_item("version", 3)?;
        if wide {
            d.set_item("shape", (rows, 3))?;
        } else {
            d.set_item("shape", (rows,))?;
        }
        d.set_item("typestr", format!("{end}{ty}"))?;
        d.set_item("data", (ptr, true))?;
        Ok(d)
    }
}

/// A frame as a dict: `step`, `time`, `n`, the per-particle columns as [`Column`]s
/// (`numpy.asarray` of each is the array, without a copy: `id`, `group`: uint32;
/// `position`, `velocity`: float64 × 3; `diameter`, `density`, `fluctuation`: float64),
/// and `stats`.
pub fn frame_dict<'py>(py: Python<'py>, f: &Arc<Frame>) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("step", f.step)?;
    d.set_item("time", f.time)?;
    d.set_item("n", f.id.len())?;
    for (name, which) in [
        ("id", Which::Id),
        ("group", Which::Group),
        ("position", Which::Position),
        ("velocity", Which::Velocity),
        ("diameter", Which::Diameter),
        ("density", Which::Density),
        ("fluctuation", Which::Fluctuation),
    ] {
        let column = Column {
            frame: Arc::clone(f),
            which,
        };
        d.set_item(name, Bound::new(py, column)?)?;
    }
    let stats = PyDict::new(py);
    for (k, v) in &f.stats {
        stats.set_item(k, v)?;
    }
    d.set_item("stats", stats)?;
    Ok(d)
}

/// A recording's run description as a dict.
pub fn meta_dict<'py>(py: Python<'py>, m: &RunMeta) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("case", &m.case)?;
    d.set_item("scg_version", &m.scg_version)?;
    d.set_item("seed", m.seed)?;
    d.set_item("dt", m.dt)?;
    d.set_item("record_every", m.record_every)?;
    let groups = PyList::empty(py);
    for g in &m.groups {
        let row = PyDict::new(py);
        row.set_item("name", &g.name)?;
        row.set_item("law", &g.law)?;
        row.set_item("alpha", g.alpha)?;
        row.set_item("original_diameter", g.original_diameter)?;
        row.set_item("color", g.color.to_vec())?;
        groups.append(row)?;
    }
    d.set_item("groups", groups)?;
    d.set_item("scene", &m.scene_toml)?;
    d.set_item("scene_dir", &m.scene_dir)?;
    d.set_item("warnings", m.warnings.clone())?;
    let patches = PyList::empty(py);
    for p in &m.patches {
        patches.append((&p.name, &p.role))?;
    }
    d.set_item("patches", patches)?;
    d.set_item("ranks", m.ranks)?;
    Ok(d)
}

/// A TOML value as the Python value `tomllib` would give (dates as their text).
pub fn toml_to_py<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::String(s) => s.into_pyobject(py)?.into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => f.into_pyobject(py)?.into_any(),
        toml::Value::Boolean(b) => b.into_pyobject(py)?.to_owned().into_any(),
        toml::Value::Datetime(t) => t.to_string().into_pyobject(py)?.into_any(),
        toml::Value::Array(a) => {
            let l = PyList::empty(py);
            for x in a {
                l.append(toml_to_py(py, x)?)?;
            }
            l.into_any()
        }
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, toml_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}
