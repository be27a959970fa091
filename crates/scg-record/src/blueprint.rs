//! The viewer layout (a Rerun blueprint) sent with every `.rrd` recording.
//!
//! Layout (see `docs/recordings.md`):
//! * left, large: a 3D view of `particles/**` and `geometry/**`, the camera looking at the
//!   vessel (the bounding box of the outlines) from above the front right, Z up; each group's
//!   points drawn with a radius in UI points (the data keep the physical radius);
//! * right: one time-series view per stats family (`count`, `drained`, `collisions`,
//!   `mean_speed`, `kinetic_energy`, then any other), series coloured as their group;
//!   below them the warnings and the scene file as tabs;
//! * time panel on `sim_time`, following the latest frame; the blueprint and selection
//!   panels collapsed.
//!
//! The blueprint is written with the same building blocks as `rerun::blueprint` (views,
//! containers, visualizer overrides), by hand because the SDK's builder does not expose view
//! properties such as the 3D eye.

use rerun::blueprint::components::{
    ActiveTab, ColumnShare, ContainerKind, Eye3DKind, GridColumns, IncludedContent, PanelState,
    PlayState, QueryExpression, RootContainer, RowShare, TimelineName, ViewClass,
};
use rerun::blueprint::{VisualizableArchetype as _, Visualizer};
use rerun::components::{Name, Position3D, Radius, Vector3D};
use rerun::external::re_log_types::{BlueprintActivationCommand, RecordingId};
use rerun::external::re_sdk_types::blueprint::archetypes::{
    ActiveVisualizers, ContainerBlueprint, EyeControls3D, PanelBlueprint, TimePanelBlueprint,
    ViewBlueprint, ViewContents, ViewportBlueprint, VisualizerInstruction,
};
use rerun::external::uuid::Uuid;
use rerun::log::LogMsg;
use rerun::{
    AsComponents, Color, EntityPath, EntityPathPart, Points3D, RecordingStream,
    RecordingStreamBuilder, SeriesLines,
};
use scg_core::frame::RunMeta;

use crate::RecordError;
use crate::layout::{
    ENTITY_EROSION, ENTITY_GEOMETRY, ENTITY_PARTICLES, ENTITY_PATCHES, ENTITY_SCENE, ENTITY_STATS,
    ENTITY_WARNINGS, RRD_APPLICATION_ID, TIMELINE_SIM_TIME,
};

/// Radius (UI points) of the points of the group with the largest diameter; the smallest
/// gets [`MIN_UI_RADIUS`], the others in between in proportion to their diameter.
const MAX_UI_RADIUS: f32 = 3.5;
const MIN_UI_RADIUS: f32 = 1.5;

/// Smallest bounding radius (m) of the outlines for which the blueprint sets the eye.
const MIN_FRAMED_RADIUS: f64 = 0.01;

fn rerun_err(err: impl std::fmt::Display) -> RecordError {
    RecordError::Rerun(err.to_string())
}

/// A stats family: the views of the time-series column.
struct Family {
    /// First part of the scalar names (`count` for `count/<group>`).
    key: String,
    title: String,
}

/// The families of the scalars `stat_names`, known ones first in a fixed order.
fn families(stat_names: &[String]) -> Vec<Family> {
    const KNOWN: [(&str, &str); 5] = [
        ("count", "Particles in the vessel"),
        ("drained", "Drained (cumulative)"),
        ("collisions", "Contacts started (cumulative)"),
        ("mean_speed", "Mean speed (m/s)"),
        ("kinetic_energy", "Kinetic energy (J)"),
    ];
    let mut keys: Vec<&str> = Vec::new();
    for name in stat_names {
        let key = name.split('/').find(|p| !p.is_empty()).unwrap_or("");
        if !key.is_empty() && !keys.contains(&key) {
            keys.push(key);
        }
    }
    let mut out: Vec<Family> = KNOWN
        .iter()
        .filter(|(k, _)| keys.contains(k))
        .map(|(k, t)| Family {
            key: (*k).to_owned(),
            title: (*t).to_owned(),
        })
        .collect();
    for key in keys {
        if !KNOWN.iter().any(|(k, _)| *k == key) {
            out.push(Family {
                key: key.to_owned(),
                title: key.to_owned(),
            });
        }
    }
    out
}

/// Writes blueprint entities into a blueprint stream.
struct Builder {
    rec: RecordingStream,
    next_id: u128,
}

impl Builder {
    /// A fresh id (a version-4 UUID pattern); ids only need to be unique within one blueprint.
    fn id(&mut self) -> Uuid {
        self.next_id += 1;
        Uuid::from_u128(0x5c9e_0000_0000_4000_8000_0000_0000_0000 | self.next_id)
    }

    fn log(&self, path: impl Into<EntityPath>, arch: &dyn AsComponents) -> Result<(), RecordError> {
        self.rec.log(path, arch).map_err(rerun_err)
    }

    /// Logs a view; returns its id (for properties and overrides).
    fn view(
        &mut self,
        class: &str,
        name: &str,
        origin: &EntityPath,
        contents: &[String],
    ) -> Result<Uuid, RecordError> {
        let id = self.id();
        let path = format!("view/{id}");
        self.log(
            format!("{path}/ViewContents"),
            &ViewContents::new(contents.iter().map(|q| QueryExpression(q.clone().into()))),
        )?;
        self.log(
            path,
            &ViewBlueprint::new(ViewClass(class.into()))
                .with_display_name(Name(name.into()))
                .with_space_origin(origin.to_string()),
        )?;
        Ok(id)
    }

    /// Logs a property archetype of a view (`EyeControls3D`, …).
    fn property(&self, view: Uuid, name: &str, arch: &dyn AsComponents) -> Result<(), RecordError> {
        self.log(format!("view/{view}/{name}"), arch)
    }

    /// Replaces the visualizers of `entity` in `view` by `visualizer` (with its overrides).
    fn override_visualizer(
        &self,
        view: Uuid,
        entity: &EntityPath,
        visualizer: &Visualizer,
    ) -> Result<(), RecordError> {
        let base = ViewContents::blueprint_base_visualizer_path_for_entity(view, entity);
        let path = base.join(&EntityPath::from_single_string(visualizer.id.0.to_string()));
        self.log(
            path.clone(),
            &VisualizerInstruction::new(visualizer.visualizer_type.clone()),
        )?;
        if !visualizer.overrides.is_empty() {
            self.rec
                .log_serialized_batches(path, false, visualizer.overrides.iter().cloned())
                .map_err(rerun_err)?;
        }
        self.log(base, &ActiveVisualizers::new([visualizer.id]))
    }

    /// Logs a container of `children` (paths of views or containers); returns its path.
    fn container(
        &mut self,
        kind: ContainerKind,
        children: &[String],
        shares: &[f32],
        grid_columns: Option<u32>,
        active_tab: Option<&str>,
    ) -> Result<String, RecordError> {
        let path = format!("container/{}", self.id());
        let mut arch = ContainerBlueprint::new(kind)
            .with_contents(children.iter().map(|c| IncludedContent(c.as_str().into())));
        if !shares.is_empty() {
            match kind {
                ContainerKind::Horizontal => {
                    arch = arch.with_col_shares(shares.iter().map(|&s| ColumnShare(s.into())));
                }
                _ => arch = arch.with_row_shares(shares.iter().map(|&s| RowShare(s.into()))),
            }
        }
        if let Some(n) = grid_columns {
            arch = arch.with_grid_columns(GridColumns(n.into()));
        }
        if let Some(tab) = active_tab {
            arch = arch.with_active_tab(ActiveTab(tab.into()));
        }
        self.log(path.as_str(), &arch)?;
        Ok(path)
    }
}

fn view_path(id: Uuid) -> String {
    format!("view/{id}")
}

fn child(parent: &str, name: &str) -> EntityPath {
    EntityPath::new(vec![EntityPathPart::new(parent), EntityPathPart::new(name)])
}

/// Where the camera looks from and at: the bounding box of the outlines and the flow
/// mesh's patches seen from above the front right, far enough for the whole box to fit
/// the view. `None` without either.
///
/// `None` also for a vessel smaller than [`MIN_FRAMED_RADIUS`]: an eye set in the blueprint
/// gets a fixed near clipping plane of about 1 cm in Rerun 0.36, which would cut such a
/// vessel away, while the viewer's default eye (fitted to the scene bounds) shows it whole.
fn eye(meta: &RunMeta) -> Option<([f32; 3], [f32; 3])> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let strips = meta.outlines.iter().flat_map(|o| o.strips.iter().flatten());
    let patches = meta.patches.iter().flat_map(|p| p.vertices.iter());
    for p in strips.chain(patches) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if !lo.iter().chain(&hi).all(|v| v.is_finite()) {
        return None;
    }
    let center: [f64; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let radius = (0..3)
        .map(|k| (0.5 * (hi[k] - lo[k])).powi(2))
        .sum::<f64>()
        .sqrt();
    if radius < MIN_FRAMED_RADIUS {
        return None;
    }
    // Direction from the target to the eye: front right, 25° above the horizon.
    let dir = [0.55_f64, -0.75, 0.45];
    let norm = dir.iter().map(|d| d * d).sum::<f64>().sqrt();
    let distance = 2.6 * radius;
    let position: [f64; 3] = std::array::from_fn(|k| center[k] + distance * dir[k] / norm);
    Some((position.map(|v| v as f32), center.map(|v| v as f32)))
}

/// Point radius (UI points) of each group, from its diameter relative to the others.
fn ui_radii(meta: &RunMeta) -> Vec<f32> {
    let d: Vec<f64> = meta.groups.iter().map(|g| g.original_diameter).collect();
    let (lo, hi) = d.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    });
    d.iter()
        .map(|&v| {
            if hi > lo && v.is_finite() {
                MIN_UI_RADIUS + (MAX_UI_RADIUS - MIN_UI_RADIUS) * ((v - lo) / (hi - lo)) as f32
            } else {
                0.5 * (MIN_UI_RADIUS + MAX_UI_RADIUS)
            }
        })
        .collect()
}

/// Builds the blueprint of a recording of `meta` whose frames carry the scalars `stat_names`
/// and sends it to `rec` (as the default and active blueprint of the application).
pub(crate) fn send(
    rec: &RecordingStream,
    meta: &RunMeta,
    stat_names: &[String],
) -> Result<(), RecordError> {
    let msgs = build(meta, stat_names)?;
    let blueprint_id = match msgs.first() {
        Some(LogMsg::SetStoreInfo(info)) => info.info.store_id.clone(),
        _ => return Err(RecordError::Rerun("blueprint without store info".into())),
    };
    rec.send_blueprint(
        msgs,
        BlueprintActivationCommand {
            blueprint_id,
            make_active: true,
            make_default: true,
        },
    );
    Ok(())
}

fn build(meta: &RunMeta, stat_names: &[String]) -> Result<Vec<LogMsg>, RecordError> {
    let (rec, storage) = RecordingStreamBuilder::new(RRD_APPLICATION_ID)
        .recording_id(RecordingId::random())
        .blueprint()
        .memory()
        .map_err(rerun_err)?;
    // The viewer reads blueprints on this timeline.
    rec.set_time_sequence("blueprint", 0);
    let mut b = Builder { rec, next_id: 0 };

    // 3D view of particles and geometry (and, at the end of a run with erosion, the wear).
    let scene3d = b.view(
        "3D",
        &meta.case,
        &EntityPath::root(),
        &[
            format!("+ /{ENTITY_PARTICLES}/**"),
            format!("+ /{ENTITY_GEOMETRY}/**"),
            format!("+ /{}/**", ENTITY_PATCHES.join("/")),
            format!("+ /{ENTITY_EROSION}/**"),
        ],
    )?;
    if let Some((position, target)) = eye(meta) {
        b.property(
            scene3d,
            "EyeControls3D",
            &EyeControls3D::new()
                .with_kind(Eye3DKind::Orbital)
                .with_position(Position3D::from(position))
                .with_look_target(Position3D::from(target))
                .with_eye_up(Vector3D::from([0.0, 0.0, 1.0])),
        )?;
    }
    for (group, radius) in meta.groups.iter().zip(ui_radii(meta)) {
        let points = Points3D::update_fields().with_radii([Radius::new_ui_points(radius)]);
        b.override_visualizer(
            scene3d,
            &child(ENTITY_PARTICLES, &group.name),
            &points.visualizer(),
        )?;
    }

    // Time series, one view per family; per-group series in the group's colour.
    let mut plots = Vec::new();
    for family in families(stat_names) {
        let origin = child(ENTITY_STATS, &family.key);
        let view = b.view(
            "TimeSeries",
            &family.title,
            &origin,
            &["+ $origin/**".to_owned()],
        )?;
        for group in &meta.groups {
            let stat = format!("{}/{}", family.key, group.name);
            if !stat_names.contains(&stat) {
                continue;
            }
            let [r, g, bl] = group.color;
            let lines = SeriesLines::update_fields()
                .with_colors([Color::from_rgb(r, g, bl)])
                .with_names([group.name.as_str()]);
            let entity = EntityPath::new(vec![
                EntityPathPart::new(ENTITY_STATS),
                EntityPathPart::new(family.key.as_str()),
                EntityPathPart::new(group.name.as_str()),
            ]);
            b.override_visualizer(view, &entity, &lines.visualizer())?;
        }
        plots.push(view_path(view));
    }

    // Warnings and scene file.
    let mut texts = Vec::new();
    if !meta.warnings.is_empty() {
        let view = b.view(
            "TextLog",
            "Warnings",
            &EntityPath::from_single_string(ENTITY_WARNINGS),
            &["+ $origin".to_owned()],
        )?;
        texts.push(view_path(view));
    }
    if !meta.scene_toml.is_empty() {
        let view = b.view(
            "TextDocument",
            "Scene",
            &EntityPath::from_single_string(ENTITY_SCENE),
            &["+ $origin".to_owned()],
        )?;
        texts.push(view_path(view));
    }

    // Right column: plots above, texts below.
    let mut right = Vec::new();
    let mut right_shares = Vec::new();
    if !plots.is_empty() {
        let columns = if plots.len() > 3 { 2 } else { 1 };
        right.push(b.container(ContainerKind::Grid, &plots, &[], Some(columns), None)?);
        right_shares.push(2.0);
    }
    if !texts.is_empty() {
        let first = texts[0].clone();
        right.push(b.container(ContainerKind::Tabs, &texts, &[], None, Some(&first))?);
        right_shares.push(1.0);
    }
    let mut root_children = vec![view_path(scene3d)];
    let mut root_shares = vec![3.0];
    if !right.is_empty() {
        root_children.push(b.container(
            ContainerKind::Vertical,
            &right,
            &right_shares,
            None,
            None,
        )?);
        root_shares.push(2.0);
    }
    let root = b.container(
        ContainerKind::Horizontal,
        &root_children,
        &root_shares,
        None,
        None,
    )?;
    let root_id: Uuid = root
        .trim_start_matches("container/")
        .parse()
        .map_err(rerun_err)?;

    b.log(
        "viewport",
        &ViewportBlueprint::new()
            .with_root_container(RootContainer(root_id.into()))
            .with_auto_layout(false)
            .with_auto_views(false),
    )?;
    b.log(
        "blueprint_panel",
        &PanelBlueprint::new().with_state(PanelState::Collapsed),
    )?;
    b.log(
        "selection_panel",
        &PanelBlueprint::new().with_state(PanelState::Collapsed),
    )?;
    b.log(
        "time_panel",
        &TimePanelBlueprint::new()
            .with_state(PanelState::Collapsed)
            .with_timeline(TimelineName(TIMELINE_SIM_TIME.into()))
            .with_play_state(PlayState::Following),
    )?;

    let Builder { rec, .. } = b;
    rec.flush_blocking().map_err(rerun_err)?;
    drop(rec);
    Ok(storage.take())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn families_known_first_then_others() {
        let names: Vec<String> = [
            "kinetic_energy",
            "height max",
            "count/a",
            "count/b",
            "mean_speed",
            "energy/kinetic",
            "drained/a",
        ]
        .map(String::from)
        .to_vec();
        let keys: Vec<String> = families(&names).into_iter().map(|f| f.key).collect();
        assert_eq!(
            keys,
            [
                "count",
                "drained",
                "mean_speed",
                "kinetic_energy",
                "height max",
                "energy"
            ]
        );
    }
}
