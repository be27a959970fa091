//! Frames, run descriptions and TOML values as Python objects.

use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyDict, PyList};

use scg_core::frame::{Frame, RunMeta};

/// A frame as a dict: `step`, `time`, the per-particle arrays as `bytearray`s in the
/// machine's byte order (`id`, `group`: uint32; `position`, `velocity`: float64 × 3;
/// `diameter`, `density`, `fluctuation`: float64) for `numpy.frombuffer`, and `stats`.
pub fn frame_dict<'py>(py: Python<'py>, f: &Frame) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("step", f.step)?;
    d.set_item("time", f.time)?;
    d.set_item("n", f.id.len())?;
    let bytes = |b: &[u8]| PyByteArray::new(py, b);
    d.set_item("id", bytes(bytemuck::cast_slice(&f.id)))?;
    d.set_item("group", bytes(bytemuck::cast_slice(&f.group)))?;
    d.set_item("position", bytes(bytemuck::cast_slice(&f.position)))?;
    d.set_item("velocity", bytes(bytemuck::cast_slice(&f.velocity)))?;
    d.set_item("diameter", bytes(bytemuck::cast_slice(&f.diameter)))?;
    d.set_item("density", bytes(bytemuck::cast_slice(&f.density)))?;
    d.set_item("fluctuation", bytes(bytemuck::cast_slice(&f.fluctuation)))?;
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
