//! The scene file as written: `[forces]`, `[erosion]` and a group's `size` (the
//! sub-models of particle-laden flows beyond drag).
#![allow(missing_docs)]

use serde::Deserialize;

use super::name;

/// `[forces]`: forces besides drag and gravity, each opt-in (docs/scenes.md).
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawForces {
    pub cunningham: Option<RawCunningham>,
    /// The added-mass coefficient C_A (0.5 for a sphere).
    pub added_mass: Option<f64>,
    #[serde(default)]
    pub pressure_gradient: bool,
    #[serde(default)]
    pub saffman_mei: bool,
    #[serde(default)]
    pub rubinow_keller: bool,
}

/// `[erosion]`: wall wear on the mesh flow's wall patches (docs/scenes.md).
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawErosion {
    #[serde(deserialize_with = "name")]
    pub model: RawErosionModel,
    /// finnie: the wall's flow stress, Pa.
    pub flow_stress: Option<f64>,
    /// finnie: ψ (default 2).
    pub psi: Option<f64>,
    /// finnie: K (default 2); dnv: K (default 2e-9).
    pub k: Option<f64>,
    /// dnv: the velocity exponent (default 2.6).
    pub n: Option<f64>,
    /// dnv: the wall's density, kg/m³.
    pub wall_density: Option<f64>,
    /// The patches logged (default: every wall patch).
    pub patches: Option<Vec<String>>,
    /// The `[[walls]]` logged, by name (default: every wall that rebounds or sticks).
    pub walls: Option<Vec<String>>,
}

/// `erosion.model`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawErosionModel {
    Finnie,
    Dnv,
}

/// `forces.cunningham`: the slip correction of small particles' drag.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawCunningham {
    /// The gas's mean free path, m (air at 20 °C, 1 atm: 6.6e-8).
    pub mean_free_path: f64,
}

/// `groups[i].size`: a size distribution of the original particles.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawSize {
    #[serde(deserialize_with = "name")]
    pub distribution: RawSizeKind,
    /// `"number"` or `"mass"`: what the shares count (required: no default guessed).
    #[serde(deserialize_with = "name")]
    pub basis: RawBasis,
    /// rosin_rammler: the size below which 63.2 % lie, m.
    pub d63: Option<f64>,
    /// rosin_rammler: the spread exponent n.
    pub spread: Option<f64>,
    /// log_normal: the median, m.
    pub median: Option<f64>,
    /// log_normal: the geometric standard deviation (> 1).
    pub sigma_g: Option<f64>,
    /// table: `[[size m, cumulative share 0..1], ...]`.
    pub table: Option<Vec<[f64; 2]>>,
    /// Truncation, m (required for rosin_rammler and log_normal; a table's ends by default).
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// Report bins: a count (log-spaced between min and max) or the edges, m.
    pub bins: Option<RawBins>,
}

/// `groups[i].size.distribution`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawSizeKind {
    RosinRammler,
    LogNormal,
    Table,
}

/// `groups[i].size.basis`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawBasis {
    Number,
    Mass,
}

/// `groups[i].size.bins`: a count or the edges.
#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
pub enum RawBins {
    Count(i64),
    Edges(Vec<f64>),
}
