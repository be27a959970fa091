//! scg-scene: scene files (TOML) → a validated [`Scene`] → a runnable simulation.
//!
//! Validation happens once, up front; every rejection is a [`SceneError`] that names the
//! file, the key and (when the key is in the file) its line. Bad input never panics.
//!
//! * `raw`: the file as written (serde structs and the names it accepts);
//! * `overrides`: `--set key=value` edits of the text ([`apply_overrides`]);
//! * `validate`: text → raw model → [`Scene`] ([`load`], [`parse`]);
//! * `model`: the validated scene ([`Scene`], [`Group`], [`Feeder`], [`Outlet`], …);
//! * `build`: scene → core configuration, simulation and recording metadata (every
//!   number of steps derived from `dt` is computed there);
//! * [`check`]: derived quantities, warnings and the `auto` time step.

mod build;
pub mod check;
pub mod error;
mod model;
mod overrides;
mod raw;
pub mod stl;
mod validate;

pub use error::SceneError;
pub use model::{
    DtChoice, Feeder, FieldReader, Group, Outlet, PatchWalls, Placement, Region, RotorZone, Scene,
    SceneMeshFlow, SizeBin, Zone,
};
pub use overrides::apply_overrides;
pub use validate::{DEFAULT_SCENE, load, parse, parse_in};
