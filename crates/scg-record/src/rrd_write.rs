//! Rerun recordings (`.rrd`): [`RrdSink`] and [`write_rrd`].
//!
//! The sink logs through an ordinary [`RecordingStream`] (which batches rows into chunks on
//! its own thread) into a small [`LogSink`] of ours that owns the `.rrd` encoder, so that
//! encoding and I/O errors reach the caller and the footer is written at a known point:
//! [`RrdSink::close`] drops the stream (which flushes it), finishes the encoder (footer),
//! syncs the file and renames `<path>.partial` to `<path>`.

use std::collections::HashMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use rerun::external::arrow::array::{
    ArrayRef, Float32Array, Float64Array, StringArray, UInt32Array, UInt64Array,
};
use rerun::external::re_build_info::CrateVersion;
use rerun::external::re_log_encoding::{Encoder, EncodingOptions};
use rerun::log::{ChunkBatcherConfig, LogMsg};
use rerun::sink::{LogSink, SinkFlushError};
use rerun::{
    AnyValues, AsComponents, Color, EntityPath, EntityPathPart, LineStrips3D, MediaType, Mesh3D,
    Points3D, RecordingInfo, RecordingStream, Scalars, TextDocument, TextLog, TextLogLevel,
    Transform3D, ViewCoordinates,
};
use scg_core::frame::{Frame, FrameSink, RunMeta, WearMap};
use scg_core::physics::wall_motion::WallMotion;

use crate::layout::{
    COMPONENT_DEPTH_RATE, COMPONENT_FLUCTUATION, COMPONENT_PARTICLE_ID, COMPONENT_SPEED,
    ENTITY_EROSION, ENTITY_GEOMETRY, ENTITY_PARTICLES, ENTITY_PATCHES, ENTITY_SCENE, ENTITY_STATS,
    ENTITY_WARNINGS, RRD_APPLICATION_ID, RRD_PROPERTY, TIMELINE_SIM_TIME, TIMELINE_STEP,
    patch_color, wear_color,
};
use crate::{RecordError, Recording, check_frame, commit_partial, partial_path};

/// The `.rrd` encoder, shared between the [`RrdSink`] and the stream's sink thread.
struct EncoderState {
    /// `None` once finished.
    encoder: Option<Encoder<BufWriter<File>>>,
    /// First encoding/I/O error, reported by the next call on the [`RrdSink`].
    error: Option<String>,
}

type SharedEncoder = Arc<Mutex<EncoderState>>;

fn lock(state: &SharedEncoder) -> std::sync::MutexGuard<'_, EncoderState> {
    state.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The [`LogSink`] the recording stream writes to: appends each message to the encoder.
struct EncoderSink(SharedEncoder);

impl LogSink for EncoderSink {
    fn send(&self, msg: LogMsg) {
        let mut state = lock(&self.0);
        if state.error.is_some() {
            return;
        }
        if let Some(encoder) = state.encoder.as_mut()
            && let Err(err) = encoder.append(&msg)
        {
            state.error = Some(format!("could not encode a message: {err}"));
        }
    }

    fn flush_blocking(&self, _timeout: Duration) -> Result<(), SinkFlushError> {
        let mut state = lock(&self.0);
        if let Some(err) = &state.error {
            return Err(SinkFlushError::failed(err.clone()));
        }
        if let Some(encoder) = state.encoder.as_mut() {
            encoder
                .flush_blocking()
                .map_err(|err| SinkFlushError::failed(format!("could not flush: {err}")))?;
        }
        Ok(())
    }

    fn defers_finalization_to_shutdown(&self) -> bool {
        // The footer (a manifest of every chunk) is written when the sink is closed.
        true
    }
}

/// Entity and colour of one particle group.
struct GroupEntity {
    path: EntityPath,
    color: Color,
}

/// A [`FrameSink`] writing a Rerun recording.
///
/// Layout (see `docs/recordings.md`):
/// * timelines `sim_time` (duration, s) and `step` (sequence);
/// * `particles/<group>`: `Points3D` with positions (m, as f32), radii = diameter/2 (m, f32),
///   one colour per group, and the extra components `particle_id` (UInt32) and `speed`
///   (|v|, m/s, Float32), one per point;
///   a group without particles in a frame is logged as an empty point set;
/// * `stats/<name>`: `Scalars`, one per entry of [`Frame::stats`] (a `/` in a name nests);
/// * static: `geometry/<outline>` (`LineStrips3D`), `flow/patches/<patch>` (`Mesh3D`, a mesh
///   flow's boundary patches coloured by role), `warnings` (`TextLog`, one warning per
///   line), `scene` (`TextDocument` with the scene file), and the recording property `scg`
///   (case, scg_version, seed, dt, record_every, groups), and Z-up `ViewCoordinates` at `/`;
/// * with `[erosion]`, at the last step: `erosion/<patch>` (`Mesh3D`, faces coloured by
///   depth rate, the rate per vertex as `depth_rate`) and `erosion/deepest` (`Points3D`,
///   labelled);
/// * a blueprint (viewer layout, see the `blueprint` module), sent with the first frame.
///
/// The file is written as `<path>.partial` and renamed to `<path>` by [`RrdSink::close`]
/// (or [`FrameSink::finish`]). Dropping an unfinished sink still closes the stream and writes
/// the footer, but leaves the file under its `.partial` name.
pub struct RrdSink {
    /// `None` once closed.
    stream: Option<RecordingStream>,
    encoder: SharedEncoder,
    path: PathBuf,
    partial: PathBuf,
    groups: Vec<GroupEntity>,
    stats_paths: HashMap<String, EntityPath>,
    /// The run description until the blueprint is sent (with the first frame, whose scalars
    /// decide the plots, or when closing a recording without frames).
    pending_blueprint: Option<RunMeta>,
    /// The moving walls' entities and motions (a transform per frame).
    moving: Vec<(EntityPath, WallMotion)>,
}

fn rerun_err(err: impl std::fmt::Display) -> RecordError {
    RecordError::Rerun(err.to_string())
}

/// `parent/<name>` with `name` taken literally (escaped if needed).
fn child_path(parent: &str, name: &str) -> EntityPath {
    EntityPath::new(vec![EntityPathPart::new(parent), EntityPathPart::new(name)])
}

/// `stats/<a>/<b>…` for a scalar named `a/b…`.
fn stats_path(name: &str) -> EntityPath {
    let parts = std::iter::once(ENTITY_STATS)
        .chain(name.split('/').filter(|p| !p.is_empty()))
        .map(EntityPathPart::new)
        .collect();
    EntityPath::new(parts)
}

fn one<T>(array: T) -> ArrayRef
where
    T: rerun::external::arrow::array::Array + 'static,
{
    Arc::new(array)
}

/// How the stream groups rows into chunks.
///
/// Rerun's default (flush every 200 ms) gives every entity a chunk five times a second; with
/// a few dozen entities of small rows that is mostly per-chunk overhead (and per-chunk footer
/// entries held in memory until the end). Frames are not viewed live, so flush every 2 s or
/// 8 MiB. The usual `RERUN_FLUSH_*` environment variables still override this.
fn batcher_config() -> ChunkBatcherConfig {
    let config = ChunkBatcherConfig {
        flush_tick: Duration::from_secs(2),
        flush_num_bytes: 8 << 20,
        ..ChunkBatcherConfig::DEFAULT
    };
    config.apply_env().unwrap_or(config)
}

impl RrdSink {
    /// Creates `<path>.partial` and logs the static part of the recording (geometry, warnings,
    /// scene, run description).
    pub fn create(path: &Path, meta: &RunMeta) -> Result<Self, RecordError> {
        let partial = partial_path(path);
        let file = File::create(&partial).map_err(|e| RecordError::io(&partial, e))?;
        let result = Self::start(path, &partial, file, meta);
        if result.is_err() {
            // Best effort: do not leave an empty `.partial` behind.
            let _ = std::fs::remove_file(&partial);
        }
        result
    }

    fn start(path: &Path, partial: &Path, file: File, meta: &RunMeta) -> Result<Self, RecordError> {
        let encoder = Encoder::new_eager(
            CrateVersion::LOCAL,
            EncodingOptions::PROTOBUF_COMPRESSED,
            BufWriter::new(file),
        )
        .map_err(rerun_err)?;
        let encoder = Arc::new(Mutex::new(EncoderState {
            encoder: Some(encoder),
            error: None,
        }));

        let info = RecordingInfo::new()
            .with_name(meta.case.clone())
            .with_start_time(rerun::components::Timestamp::now());
        let stream = RecordingStream::new(
            rerun::new_store_info(RRD_APPLICATION_ID),
            Some(info),
            Some(batcher_config()),
            Default::default(),
            Box::new(EncoderSink(encoder.clone())),
        )
        .map_err(rerun_err)?;
        // Only our own timelines.
        stream.set_log_time_enabled(false);
        stream.set_log_tick_enabled(false);

        let groups = meta
            .groups
            .iter()
            .map(|g| GroupEntity {
                path: child_path(ENTITY_PARTICLES, &g.name),
                color: Color::from_rgb(g.color[0], g.color[1], g.color[2]),
            })
            .collect();

        let mut sink = Self {
            stream: Some(stream),
            encoder,
            path: path.to_path_buf(),
            partial: partial.to_path_buf(),
            groups,
            stats_paths: HashMap::new(),
            pending_blueprint: Some(meta.clone()),
            moving: meta
                .outlines
                .iter()
                .filter(|o| !o.motion.is_fixed())
                .map(|o| (child_path(ENTITY_GEOMETRY, &o.name), o.motion))
                .collect(),
        };
        sink.log_static(meta)?;
        Ok(sink)
    }

    /// The final path of the recording (valid once closed).
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn stream(&self) -> Result<&RecordingStream, RecordError> {
        self.stream.as_ref().ok_or(RecordError::Finished)
    }

    /// Reports the first encoding/I/O error of the sink thread, if any.
    fn check_encoder(&self) -> Result<(), RecordError> {
        match &lock(&self.encoder).error {
            Some(err) => Err(RecordError::Rerun(err.clone())),
            None => Ok(()),
        }
    }

    fn log_static(&mut self, meta: &RunMeta) -> Result<(), RecordError> {
        let rec = self.stream()?;

        // Z up, as the scenes are.
        rec.log_static("/", &ViewCoordinates::RIGHT_HAND_Z_UP())
            .map_err(rerun_err)?;

        let group_names: Vec<&str> = meta.groups.iter().map(|g| g.name.as_str()).collect();
        let properties = AnyValues::default()
            .with_component_from_data("case", one(StringArray::from(vec![meta.case.as_str()])))
            .with_component_from_data(
                "scg_version",
                one(StringArray::from(vec![meta.scg_version.as_str()])),
            )
            .with_component_from_data("seed", one(UInt64Array::from(vec![meta.seed])))
            .with_component_from_data("dt", one(Float64Array::from(vec![meta.dt])))
            .with_component_from_data(
                "record_every",
                one(UInt64Array::from(vec![meta.record_every])),
            )
            .with_component_from_data("groups", one(StringArray::from(group_names)));
        rec.send_property(RRD_PROPERTY, &properties)
            .map_err(rerun_err)?;

        for outline in &meta.outlines {
            let strips = outline.strips.iter().map(|strip| {
                strip
                    .iter()
                    .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
                    .collect::<Vec<_>>()
            });
            rec.log_static(
                child_path(ENTITY_GEOMETRY, &outline.name),
                &LineStrips3D::new(strips).with_colors([Color::from_rgb(160, 160, 160)]),
            )
            .map_err(rerun_err)?;
            if !outline.triangles.is_empty() {
                // A mesh wall's triangles, translucent, under its feature edges.
                let path = EntityPath::new(
                    [ENTITY_GEOMETRY, outline.name.as_str(), "surface"]
                        .map(EntityPathPart::new)
                        .to_vec(),
                );
                let positions = outline
                    .vertices
                    .iter()
                    .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]);
                rec.log_static(
                    path,
                    &Mesh3D::new(positions)
                        .with_triangle_indices(outline.triangles.clone())
                        .with_albedo_factor(rerun::datatypes::Rgba32::from_unmultiplied_rgba(
                            160, 160, 160, 80,
                        )),
                )
                .map_err(rerun_err)?;
            }
        }

        for patch in &meta.patches {
            // A mesh flow's boundary patch: its triangles, translucent, coloured by role.
            let path = EntityPath::new(
                ENTITY_PATCHES
                    .iter()
                    .chain([&patch.name.as_str()])
                    .map(|p| EntityPathPart::new(*p))
                    .collect(),
            );
            let positions = patch
                .vertices
                .iter()
                .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]);
            let [r, g, b, a] = patch_color(&patch.role);
            rec.log_static(
                path,
                &Mesh3D::new(positions)
                    .with_triangle_indices(patch.triangles.clone())
                    .with_albedo_factor(rerun::datatypes::Rgba32::from_unmultiplied_rgba(
                        r, g, b, a,
                    )),
            )
            .map_err(rerun_err)?;
        }

        if !meta.warnings.is_empty() {
            rec.log_static(
                ENTITY_WARNINGS,
                &TextLog::new(meta.warnings.join("\n")).with_level(TextLogLevel::WARN),
            )
            .map_err(rerun_err)?;
        }

        if !meta.scene_toml.is_empty() {
            rec.log_static(
                ENTITY_SCENE,
                &TextDocument::new(meta.scene_toml.clone())
                    .with_media_type(MediaType::plain_text()),
            )
            .map_err(rerun_err)?;
        }
        Ok(())
    }

    /// Logs one frame at `step` / `sim_time`.
    pub fn push(&mut self, frame: &Frame) -> Result<(), RecordError> {
        check_frame(frame, self.groups.len())?;
        self.check_encoder()?;
        let step = i64::try_from(frame.step).map_err(|_| RecordError::InvalidFrame {
            step: frame.step,
            reason: "step does not fit in an i64".into(),
        })?;
        let rec = self.stream.as_ref().ok_or(RecordError::Finished)?;
        rec.set_time_sequence(TIMELINE_STEP, step);
        rec.set_duration_secs(TIMELINE_SIM_TIME, frame.time);

        // Split the particles by group in one pass.
        let mut positions: Vec<Vec<[f32; 3]>> = vec![Vec::new(); self.groups.len()];
        let mut radii: Vec<Vec<f32>> = vec![Vec::new(); self.groups.len()];
        let mut ids: Vec<Vec<u32>> = vec![Vec::new(); self.groups.len()];
        let mut speeds: Vec<Vec<f32>> = vec![Vec::new(); self.groups.len()];
        let mut fluct: Vec<Vec<f32>> = vec![Vec::new(); self.groups.len()];
        for i in 0..frame.len() {
            let g = frame.group[i] as usize;
            let p = frame.position[i];
            let v = frame.velocity[i];
            positions[g].push([p[0] as f32, p[1] as f32, p[2] as f32]);
            radii[g].push((0.5 * frame.diameter[i]) as f32);
            ids[g].push(frame.id[i]);
            speeds[g].push((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt() as f32);
            if let Some(u) = frame.fluctuation.get(i) {
                fluct[g].push(*u as f32);
            }
        }
        let turbulent = !frame.fluctuation.is_empty();
        for (((((group, positions), radii), ids), speeds), fluct) in self
            .groups
            .iter()
            .zip(positions)
            .zip(radii)
            .zip(ids)
            .zip(speeds)
            .zip(fluct)
        {
            let points = Points3D::new(positions)
                .with_radii(radii)
                .with_colors([group.color]);
            let mut extra = AnyValues::default()
                .with_component_from_data(COMPONENT_PARTICLE_ID, one(UInt32Array::from(ids)))
                .with_component_from_data(COMPONENT_SPEED, one(Float32Array::from(speeds)));
            if turbulent {
                extra = extra.with_component_from_data(
                    COMPONENT_FLUCTUATION,
                    one(Float32Array::from(fluct)),
                );
            }
            rec.log(group.path.clone(), &[&points as &dyn AsComponents, &extra])
                .map_err(rerun_err)?;
        }

        for (path, motion) in &self.moving {
            // rest frame → world: x ↦ R·(x − c₀) + c(t)
            let p = motion.pose(frame.time);
            let m = p.rotation.to_cols_array_2d().map(|c| c.map(|x| x as f32));
            rec.log(
                path.clone(),
                &Transform3D::from_translation_mat3x3(p.translation().as_vec3().to_array(), m),
            )
            .map_err(rerun_err)?;
        }

        for (name, value) in &frame.stats {
            let path = self
                .stats_paths
                .entry(name.clone())
                .or_insert_with(|| stats_path(name));
            rec.log(path.clone(), &Scalars::single(*value))
                .map_err(rerun_err)?;
        }

        if let Some(meta) = self.pending_blueprint.take() {
            let names: Vec<String> = frame.stats.iter().map(|(n, _)| n.clone()).collect();
            crate::blueprint::send(rec, &meta, &names)?;
        }
        Ok(())
    }

    /// Logs the wear of the walls at its step / time: per patch a `Mesh3D` whose faces are
    /// coloured by depth rate (their triangles do not share vertices, so each face keeps
    /// its own colour) with the rate per vertex, and the deepest face's centre labelled.
    pub fn push_wear(&mut self, wear: &WearMap) -> Result<(), RecordError> {
        self.check_encoder()?;
        let rec = self.stream.as_ref().ok_or(RecordError::Finished)?;
        let step = i64::try_from(wear.step).map_err(|_| RecordError::InvalidFrame {
            step: wear.step,
            reason: "step does not fit in an i64".into(),
        })?;
        rec.set_time_sequence(TIMELINE_STEP, step);
        rec.set_duration_secs(TIMELINE_SIM_TIME, wear.time);
        let deepest = wear.deepest();
        let max = deepest.map_or(0.0, |d| d.2);
        for p in &wear.patches {
            let n = 3 * p.triangles.len();
            let (mut positions, mut colors, mut rates) = (
                Vec::with_capacity(n),
                Vec::with_capacity(n),
                Vec::with_capacity(n),
            );
            for (t, &f) in p.triangles.iter().zip(&p.triangle_face) {
                let rate = p.depth_rate[f as usize];
                let [r, g, b, a] = wear_color(rate, max);
                for &v in t {
                    let q = p.vertices[v as usize];
                    positions.push([q[0] as f32, q[1] as f32, q[2] as f32]);
                    colors.push(Color::from_unmultiplied_rgba(r, g, b, a));
                    rates.push(rate);
                }
            }
            let mesh = Mesh3D::new(positions).with_vertex_colors(colors);
            let extra = AnyValues::default()
                .with_component_from_data(COMPONENT_DEPTH_RATE, one(Float64Array::from(rates)));
            rec.log(
                child_path(ENTITY_EROSION, &p.name),
                &[&mesh as &dyn AsComponents, &extra],
            )
            .map_err(rerun_err)?;
        }
        if let Some((pi, fi, rate)) = deepest {
            let p = &wear.patches[pi];
            let (mut c, mut k) = ([0.0f64; 3], 0.0);
            for (t, &f) in p.triangles.iter().zip(&p.triangle_face) {
                if f as usize == fi {
                    for &v in t {
                        let q = p.vertices[v as usize];
                        (0..3).for_each(|i| c[i] += q[i]);
                        k += 1.0;
                    }
                }
            }
            let label = format!(
                "deepest ({}): {:.3e} m/s = {:.3e} mm/year, {} impacts",
                wear.model,
                rate,
                rate * 365.25 * 86_400.0 * 1e3,
                p.impacts[fi]
            );
            rec.log(
                child_path(ENTITY_EROSION, "deepest"),
                &Points3D::new([[(c[0] / k) as f32, (c[1] / k) as f32, (c[2] / k) as f32]])
                    .with_labels([label])
                    .with_colors([Color::from_rgb(255, 60, 60)])
                    .with_radii([rerun::Radius::new_ui_points(6.0)]),
            )
            .map_err(rerun_err)?;
        }
        Ok(())
    }

    /// Flushes the stream, writes the footer, syncs the file and renames `<path>.partial` to
    /// `<path>`. Idempotent.
    pub fn close(&mut self) -> Result<(), RecordError> {
        let Some(stream) = self.stream.take() else {
            return Ok(());
        };
        // A recording without frames still gets a layout.
        let blueprint = match self.pending_blueprint.take() {
            Some(meta) => crate::blueprint::send(&stream, &meta, &[]),
            None => Ok(()),
        };
        let flushed = stream.flush_blocking().map_err(rerun_err);
        // Dropping the last handle joins the stream's threads: every message is encoded.
        drop(stream);
        let closed = close_encoder(&self.encoder, &self.partial);
        blueprint?;
        flushed?;
        closed?;
        commit_partial(&self.partial, &self.path)
    }
}

/// Writes the footer, flushes and syncs the file.
fn close_encoder(state: &SharedEncoder, partial: &Path) -> Result<(), RecordError> {
    let mut state = lock(state);
    if let Some(err) = state.error.take() {
        return Err(RecordError::Rerun(err));
    }
    let Some(mut encoder) = state.encoder.take() else {
        return Ok(());
    };
    encoder.finish().map_err(rerun_err)?;
    let writer = encoder.into_inner().map_err(rerun_err)?;
    let file = writer
        .into_inner()
        .map_err(|e| RecordError::io(partial, e.into_error()))?;
    file.sync_all().map_err(|e| RecordError::io(partial, e))
}

impl FrameSink for RrdSink {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), String> {
        self.push(frame).map_err(|e| e.to_string())
    }

    fn write_wear(&mut self, wear: &WearMap) -> Result<(), String> {
        self.push_wear(wear).map_err(|e| e.to_string())
    }

    fn finish(&mut self) -> Result<(), String> {
        self.close().map_err(|e| e.to_string())
    }
}

impl Drop for RrdSink {
    fn drop(&mut self) {
        if let Some(stream) = self.stream.take() {
            // Not finished: still produce a readable file (with footer), left as `.partial`.
            drop(stream);
            let _ = close_encoder(&self.encoder, &self.partial);
        }
    }
}

/// Rebuilds a Rerun recording from a [`Recording`] (e.g. read by [`crate::read_mcap`]), with
/// the same layout as a live run. Returns the number of frames written.
pub fn write_rrd(rec: &Recording, path: &Path) -> Result<usize, RecordError> {
    let mut sink = RrdSink::create(path, &rec.meta)?;
    for frame in &rec.frames {
        sink.push(frame)?;
    }
    if let Some(w) = &rec.wear {
        sink.push_wear(w)?;
    }
    sink.close()?;
    Ok(rec.frames.len())
}
