//! The scene file as written (serde structs, every key documented in docs/scenes.md).
#![allow(missing_docs)]

use serde::Deserialize;

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawScene {
    pub name: Option<String>,
    pub description: Option<String>,
    pub duration: f64,
    pub dt: RawDt,
    pub record_every: Option<i64>,
    pub seed: Option<i64>,
    pub integrator: Option<String>,
    pub fluid: Option<RawFluid>,
    pub flow: Option<RawFlow>,
    pub drag: Option<RawDrag>,
    pub gravity: Option<RawGravity>,
    pub material: Option<RawMaterial>,
    pub contacts: Option<RawContacts>,
    #[serde(default)]
    pub walls: Vec<RawWall>,
    #[serde(default)]
    pub groups: Vec<RawGroup>,
    pub coarse_grain: Option<RawCoarseGrain>,
    pub feed_scale: Option<f64>,
    #[serde(default)]
    pub feeders: Vec<RawFeeder>,
    pub outlet: Option<RawOutlet>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawCoarseGrain {
    pub alpha: Option<f64>,
    pub law: Option<String>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawFeeder {
    pub group: String,
    pub rate: Option<f64>,
    pub volume_rate: Option<f64>,
    pub region: RawRegion,
    pub velocity: Option<[f64; 3]>,
    pub swirl: Option<f64>,
    pub start: Option<f64>,
    pub stop: Option<f64>,
    pub interval: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawOutlet {
    pub center: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub nozzle_radius: f64,
    pub plane: f64,
    pub domain_radius: f64,
    pub domain_height: [f64; 2],
    pub interval: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
pub enum RawDt {
    Fixed(f64),
    Word(String),
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawFluid {
    pub density: f64,
    pub viscosity: f64,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawFlow {
    pub kind: String,
    pub velocity: Option<[f64; 3]>,
    pub center: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub rpm: Option<f64>,
    pub inflow_ratio: Option<f64>,
    pub nozzle_radius: Option<f64>,
    pub axial_speed: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawDrag {
    pub law: String,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawGravity {
    pub acceleration: [f64; 3],
    #[serde(default)]
    pub buoyancy: bool,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawMaterial {
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub restitution: f64,
    #[serde(default)]
    pub friction: f64,
    pub normal_model: Option<String>,
    pub linear_stiffness: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawWall {
    pub name: Option<String>,
    pub kind: String,
    pub point: Option<[f64; 3]>,
    pub normal: Option<[f64; 3]>,
    pub center: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub radius: Option<f64>,
    pub extent: Option<[f64; 2]>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawGroup {
    pub name: String,
    pub diameter: f64,
    pub density: f64,
    pub alpha: Option<f64>,
    pub law: Option<String>,
    pub color: Option<[i64; 3]>,
    pub positions: Option<Vec<[f64; 3]>>,
    pub velocities: Option<Vec<[f64; 3]>>,
    pub velocity: Option<[f64; 3]>,
    pub count: Option<i64>,
    pub region: Option<RawRegion>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawRegion {
    pub kind: String,
    pub min: Option<[f64; 3]>,
    pub max: Option<[f64; 3]>,
    pub center: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub radius_min: Option<f64>,
    pub radius_max: Option<f64>,
    pub height: Option<[f64; 2]>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawContacts {
    pub skin: Option<f64>,
    #[serde(default)]
    pub rolling_friction: f64,
    pub periodic: Option<[f64; 3]>,
    pub tangential_stiffness_ratio: Option<f64>,
}
