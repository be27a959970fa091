//! Names and formats shared by the writers and the reader: entity paths and timelines of the
//! Rerun recording, topics, fields and metadata keys of the MCAP file.
//!
//! `docs/recordings.md` describes the same layouts for users of other tools.

use serde::de::{MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use scg_core::frame::{GroupMeta, Outline};
use scg_core::physics::wall_motion::WallMotion;

// ---------------------------------------------------------------------------------------------
// Rerun (.rrd)

/// Application id of the Rerun recordings.
pub const RRD_APPLICATION_ID: &str = "scg";
/// Timeline holding the simulation time (a duration, s).
pub const TIMELINE_SIM_TIME: &str = "sim_time";
/// Timeline holding the step counter (a sequence).
pub const TIMELINE_STEP: &str = "step";
/// Parent entity of the particle groups: `particles/<group name>` holds a `Points3D`.
pub const ENTITY_PARTICLES: &str = "particles";
/// Parent entity of the static geometry: `geometry/<outline name>` holds a `LineStrips3D`
/// (a moving wall's at rest, with a `Transform3D` per frame that puts it where it is).
pub const ENTITY_GEOMETRY: &str = "geometry";
/// Parent entity of the scalars: `stats/<name>` holds `Scalars` (a `/` in a name nests).
pub const ENTITY_STATS: &str = "stats";
/// Parent entity of a mesh flow's boundary patches: `flow/patches/<patch name>` holds a
/// static `Mesh3D` (its faces as triangles, coloured by role, see [`patch_color`]).
pub const ENTITY_PATCHES: [&str; 2] = ["flow", "patches"];
/// Entity of the static `TextLog` holding the scene check's warnings (one line each).
pub const ENTITY_WARNINGS: &str = "warnings";
/// Entity of the static `TextDocument` holding the scene file.
pub const ENTITY_SCENE: &str = "scene";
/// Parent entity of the wear of a run with `[erosion]`: `erosion/<patch name>` holds a
/// `Mesh3D` logged once at the run's last step, each face coloured by its depth rate
/// ([`wear_color`]), with the extra component [`COMPONENT_DEPTH_RATE`] per vertex;
/// `erosion/deepest` a `Points3D` on the deepest face's centre, labelled with its rate.
pub const ENTITY_EROSION: &str = "erosion";
/// Extra component of the `erosion/<patch>` meshes: the depth rate of the face each
/// vertex belongs to (m/s, Float64, one per vertex; the faces' triangles do not share
/// vertices).
pub const COMPONENT_DEPTH_RATE: &str = "depth_rate";
/// Name of the recording property (under `/__properties`) holding the run description.
pub const RRD_PROPERTY: &str = "scg";
/// Extra component logged with each group's `Points3D`: the particle ids (UInt32, one per
/// point, in the same order as the positions).
pub const COMPONENT_PARTICLE_ID: &str = "particle_id";
/// Extra component logged with each group's `Points3D`: the particle speeds |v| (m/s,
/// Float32, one per point, in the same order as the positions).
pub const COMPONENT_SPEED: &str = "speed";
/// Extra component logged with each group's `Points3D` when the run has dispersion: the
/// magnitude |u′| of each particle's turbulent fluctuation (m/s, Float32, one per point).
pub const COMPONENT_FLUCTUATION: &str = "fluctuation";

// ---------------------------------------------------------------------------------------------
// MCAP

/// Topic of the particle state: one `foxglove.PointCloud` (protobuf) per frame.
pub const TOPIC_PARTICLES: &str = "/particles";
/// Topic of the scalars: one JSON message per frame, see [`STATS_JSON_SCHEMA`].
pub const TOPIC_STATS: &str = "/stats";
/// Topic of a mesh flow's boundary patches: one `foxglove.SceneUpdate` (protobuf) at time
/// 0, one `SceneEntity` per patch (id = patch name, metadata `role`) holding one
/// `TriangleListPrimitive` (points in m, indexed, coloured by role). Absent without a
/// mesh flow.
pub const TOPIC_PATCHES: &str = "/flow/patches";
/// Topic of the moving walls (`[[walls]] motion`): one `foxglove.SceneUpdate` per frame,
/// one `SceneEntity` per moving wall (id = its name) holding its outline's strips at rest
/// as `LinePrimitive`s (LINE_STRIP) with the pose that puts them where the wall is at the
/// frame's time. Absent without moving walls.
pub const TOPIC_WALLS: &str = "/geometry/walls";
/// `frame_id` of the point clouds.
pub const FRAME_ID: &str = "world";
/// Name of the MCAP metadata record holding the run description (see `META_*` keys).
pub const METADATA_NAME: &str = "scg";
/// Name of the attachment holding the scene file.
pub const SCENE_ATTACHMENT: &str = "scene.toml";
/// Name of the attachment holding the run's wear (`[erosion]`): the
/// [`scg_core::frame::WearMap`] as JSON, written when the run finishes.
pub const EROSION_ATTACHMENT: &str = "erosion.json";
/// Media type of the scene attachment.
pub const SCENE_MEDIA_TYPE: &str = "application/toml";
/// Bytes per point in the point clouds.
pub const POINT_STRIDE: u32 = 72;

/// Numeric type of a point field (values of `foxglove.PackedElementField.NumericType`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldType {
    /// Little-endian IEEE 754 double (`FLOAT64` = 8).
    Float64,
    /// Little-endian unsigned 32-bit integer (`UINT32` = 5).
    Uint32,
}

/// The point fields: name, byte offset within a point, type. Units: m (x y z), m/s
/// (vx vy vz), m (diameter), kg/m³ (density); `id` is the particle id, `group` the index into
/// the `groups` metadata entry.
pub const POINT_FIELDS: [(&str, u32, FieldType); 10] = [
    ("x", 0, FieldType::Float64),
    ("y", 8, FieldType::Float64),
    ("z", 16, FieldType::Float64),
    ("vx", 24, FieldType::Float64),
    ("vy", 32, FieldType::Float64),
    ("vz", 40, FieldType::Float64),
    ("diameter", 48, FieldType::Float64),
    ("density", 56, FieldType::Float64),
    ("id", 64, FieldType::Uint32),
    ("group", 68, FieldType::Uint32),
];

/// The point field appended when the run has dispersion: |u′|, m/s (the magnitude of the
/// turbulent fluctuation the particle sees), at the end of a point of
/// [`POINT_STRIDE_FLUCTUATION`] bytes. Readers find fields by name, so a recording without
/// it reads as before.
pub const POINT_FIELD_FLUCTUATION: (&str, u32, FieldType) =
    ("fluctuation", POINT_STRIDE, FieldType::Float64);
/// Bytes per point when the points carry [`POINT_FIELD_FLUCTUATION`].
pub const POINT_STRIDE_FLUCTUATION: u32 = POINT_STRIDE + 8;

/// Schema name of the `/stats` channel.
pub const STATS_SCHEMA_NAME: &str = "scg.Stats";
/// JSON schema of the `/stats` messages.
///
/// `values` keeps the order in which the run produced the scalars; a value that is not a
/// finite number is written as `null`.
pub const STATS_JSON_SCHEMA: &str = r#"{
  "$schema": "https://json-schema.org/draft/2020-12/schema",
  "title": "scg.Stats",
  "description": "Scalars measured at one recorded frame of an scg run",
  "type": "object",
  "properties": {
    "step": {"type": "integer", "minimum": 0, "description": "step counter"},
    "time": {"type": "number", "description": "simulation time, s"},
    "values": {
      "type": "object",
      "additionalProperties": {"type": ["number", "null"]},
      "description": "scalar name -> value (SI units)"
    }
  },
  "required": ["step", "time", "values"]
}"#;

/// Metadata key: layout version of the file (currently [`FORMAT_VERSION`]).
pub const META_FORMAT: &str = "format";
/// Layout version written in [`META_FORMAT`].
pub const FORMAT_VERSION: &str = "scg-record/1";
/// Metadata key: scg version that made the recording.
pub const META_SCG_VERSION: &str = "scg_version";
/// Metadata key: case name.
pub const META_CASE: &str = "case";
/// Metadata key: random seed (decimal integer).
pub const META_SEED: &str = "seed";
/// Metadata key: time step, s (JSON number).
pub const META_DT: &str = "dt";
/// Metadata key: steps between recorded frames (decimal integer).
pub const META_RECORD_EVERY: &str = "record_every";
/// Metadata key: JSON array of `{name, law, alpha, original_diameter, color}`.
pub const META_GROUPS: &str = "groups";
/// Metadata key: JSON array of strings.
pub const META_WARNINGS: &str = "warnings";
/// Metadata key: JSON array of `{name, strips}` (strips: arrays of `[x, y, z]`, m).
pub const META_OUTLINES: &str = "outlines";
/// Metadata key: the folder the scene's relative paths are resolved from (absolute;
/// optional, absent in older recordings).
pub const META_SCENE_DIR: &str = "scene_dir";

/// Metadata key: JSON array of the part files of a recording written per MPI rank
/// (names relative to the index file's folder, in rank order); present only in such an
/// index, which holds no frame ([`scg_core::frame::RunMeta::parts`]).
pub const META_PARTS: &str = "parts";

/// Metadata key: the number of MPI ranks the run was decomposed over; present only when
/// more than one ([`scg_core::frame::RunMeta::ranks`]).
pub const META_RANKS: &str = "mpi_ranks";

/// Colour (sRGB and alpha, 0–255) a boundary patch is drawn in, by role: walls grey and
/// most translucent, outlets green, inlets blue, lost patches red.
pub fn patch_color(role: &str) -> [u8; 4] {
    match role {
        "wall" => [160, 160, 160, 60],
        "outlet" => [60, 190, 90, 120],
        "inlet" => [70, 130, 235, 120],
        _ => [225, 95, 80, 100],
    }
}

/// A group as stored in the [`META_GROUPS`] metadata entry.
#[derive(Serialize, Deserialize)]
pub(crate) struct GroupJson {
    pub name: String,
    pub law: String,
    pub alpha: f64,
    pub original_diameter: f64,
    pub color: [u8; 3],
}

impl From<&GroupMeta> for GroupJson {
    fn from(g: &GroupMeta) -> Self {
        Self {
            name: g.name.clone(),
            law: g.law.clone(),
            alpha: g.alpha,
            original_diameter: g.original_diameter,
            color: g.color,
        }
    }
}

impl From<GroupJson> for GroupMeta {
    fn from(g: GroupJson) -> Self {
        Self {
            name: g.name,
            law: g.law,
            alpha: g.alpha,
            original_diameter: g.original_diameter,
            color: g.color,
        }
    }
}

/// An outline as stored in the [`META_OUTLINES`] metadata entry.
#[derive(Serialize, Deserialize)]
pub(crate) struct OutlineJson {
    pub name: String,
    pub strips: Vec<Vec<[f64; 3]>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub vertices: Vec<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub triangles: Vec<[u32; 3]>,
    /// A moving wall's motion: `{"velocity", "angular_velocity", "center"}` (m/s, rad/s, m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub motion: Option<MotionJson>,
}

/// A wall's motion in the `outlines` metadata.
#[derive(Serialize, Deserialize)]
pub(crate) struct MotionJson {
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
    pub center: [f64; 3],
}

impl From<&Outline> for OutlineJson {
    fn from(o: &Outline) -> Self {
        let m = &o.motion;
        Self {
            name: o.name.clone(),
            strips: o.strips.clone(),
            vertices: o.vertices.clone(),
            triangles: o.triangles.clone(),
            motion: (!m.is_fixed()).then(|| MotionJson {
                velocity: m.velocity.to_array(),
                angular_velocity: m.angular_velocity.to_array(),
                center: m.centre.to_array(),
            }),
        }
    }
}

impl From<OutlineJson> for Outline {
    fn from(o: OutlineJson) -> Self {
        Self {
            name: o.name,
            strips: o.strips,
            vertices: o.vertices,
            triangles: o.triangles,
            motion: o.motion.map_or(WallMotion::FIXED, |m| WallMotion {
                velocity: m.velocity.into(),
                angular_velocity: m.angular_velocity.into(),
                centre: m.center.into(),
            }),
        }
    }
}

/// A `/stats` message being written.
#[derive(Serialize)]
pub(crate) struct StatsOut<'a> {
    pub step: u64,
    pub time: f64,
    pub values: OrderedValues<'a>,
}

/// Scalars serialized as a JSON object in their original order.
pub(crate) struct OrderedValues<'a>(pub &'a [(String, f64)]);

impl Serialize for OrderedValues<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (name, value) in self.0 {
            // serde_json writes a non-finite number as `null`.
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
}

/// A `/stats` message being read.
#[derive(Deserialize)]
pub(crate) struct StatsIn {
    pub step: u64,
    pub time: f64,
    pub values: OrderedValuesIn,
}

/// Scalars read from a JSON object, in file order (`null` reads as NaN).
pub(crate) struct OrderedValuesIn(pub Vec<(String, f64)>);

impl<'de> Deserialize<'de> for OrderedValuesIn {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = OrderedValuesIn;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object of scalar values")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::with_capacity(map.size_hint().unwrap_or(0));
                while let Some((name, value)) = map.next_entry::<String, Option<f64>>()? {
                    out.push((name, value.unwrap_or(f64::NAN)));
                }
                Ok(OrderedValuesIn(out))
            }
        }
        deserializer.deserialize_map(V)
    }
}

/// The colour of a face worn at `rate` (m/s) when the deepest face wears at `max`: a log
/// scale over three decades below `max`, dark blue to yellow (viridis' ends and middle,
/// interpolated); faces that wore nothing grey. RGBA.
pub fn wear_color(rate: f64, max: f64) -> [u8; 4] {
    if !(rate > 0.0 && max > 0.0) {
        return [150, 150, 150, 255];
    }
    let x = ((rate / max).log10() / 3.0 + 1.0).clamp(0.0, 1.0);
    // viridis at 0, 1/4, 1/2, 3/4, 1
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [253.0, 231.0, 37.0],
    ];
    let f = x * 4.0;
    let i = (f.floor() as usize).min(3);
    let t = f - i as f64;
    let c = |k: usize| (STOPS[i][k] + t * (STOPS[i + 1][k] - STOPS[i][k])).round() as u8;
    [c(0), c(1), c(2), 255]
}
