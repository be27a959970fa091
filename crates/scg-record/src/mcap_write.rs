//! MCAP recordings: [`McapSink`].

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use foxglove::Encode;
use foxglove::bytes::Bytes;
use foxglove::messages::packed_element_field::NumericType;
use foxglove::messages::{PackedElementField, PointCloud, SceneUpdate, Timestamp};
use mcap::records::{MessageHeader, Metadata};
use mcap::{Attachment, Compression, WriteOptions, Writer};
use scg_core::frame::{Frame, FrameSink, Outline, RunMeta, WearMap};

use crate::mcap_scene::{identity, patches_update, walls_update};

use crate::layout::{
    EROSION_ATTACHMENT, FORMAT_VERSION, FRAME_ID, FieldType, GroupJson, META_CASE, META_DT,
    META_FORMAT, META_GROUPS, META_OUTLINES, META_PARTS, META_RANKS, META_RECORD_EVERY,
    META_SCENE_DIR, META_SCG_VERSION, META_SEED, META_WARNINGS, METADATA_NAME, OrderedValues,
    OutlineJson, POINT_FIELD_FLUCTUATION, POINT_FIELDS, POINT_STRIDE, POINT_STRIDE_FLUCTUATION,
    SCENE_ATTACHMENT, SCENE_MEDIA_TYPE, STATS_JSON_SCHEMA, STATS_SCHEMA_NAME, StatsOut,
    TOPIC_PARTICLES, TOPIC_PATCHES, TOPIC_STATS, TOPIC_WALLS,
};
use crate::{RecordError, check_frame, commit_partial, partial_path};

/// When [`McapSink`] closes a chunk (making everything before it safe from a crash).
///
/// A chunk is closed, and the file's buffer handed to the OS, after the first frame that
/// brings the chunk to `chunk_bytes` uncompressed bytes or that comes `chunk_interval` or
/// more after the previous close. A run killed by SIGKILL thus loses at most the frames of
/// the last `chunk_interval` (or `chunk_bytes`), and [`crate::read_mcap`] recovers the rest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct McapOptions {
    /// Target uncompressed chunk size, bytes (0: one chunk per frame). Default 1 MiB.
    pub chunk_bytes: usize,
    /// Close the chunk at the first frame written this long (wall clock) or longer after the
    /// previous close. Default 1 s.
    pub chunk_interval: Duration,
    /// zstd compression level (0: zstd default, 3). Default 1: particle data is mostly float
    /// noise, and level 1 keeps the writer far cheaper than the simulation.
    pub compression_level: u32,
}

impl Default for McapOptions {
    fn default() -> Self {
        Self {
            chunk_bytes: 1 << 20,
            chunk_interval: Duration::from_secs(1),
            compression_level: 1,
        }
    }
}

/// A [`FrameSink`] writing an MCAP file.
///
/// Layout (see `docs/recordings.md`):
/// * `/particles`: one `foxglove.PointCloud` (protobuf) per frame, `frame_id` `world`, identity
///   pose, timestamp = simulation time; packed little-endian fields `x y z vx vy vz diameter
///   density` (FLOAT64, SI units) then `id group` (UINT32), 72 bytes per point;
/// * `/stats`: one JSON message per frame, `{"step", "time", "values": {name: value}}`
///   (schema [`crate::layout::STATS_JSON_SCHEMA`]);
/// * both messages of frame *k* have sequence *k* and log/publish time = simulation time in
///   ns (rounded);
/// * metadata record `scg` with the run description, attachment `scene.toml` with the scene
///   file, both written first so that a truncated file keeps them;
/// * with a mesh flow, `/flow/patches`: one `foxglove.SceneUpdate` at time 0 with every
///   boundary patch as a triangle list ([`TOPIC_PATCHES`]), in the first chunk;
/// * with moving walls, `/geometry/walls`: one `foxglove.SceneUpdate` per frame posing
///   each moving wall's outline ([`TOPIC_WALLS`]);
/// * with `[erosion]`, attachment `erosion.json` ([`EROSION_ATTACHMENT`]): the wear of
///   the walls per face, written when the run finishes;
/// * zstd-compressed chunks (see [`McapOptions`]), message and chunk indexes, statistics,
///   summary and CRCs.
///
/// The file is written as `<path>.partial` and renamed to `<path>` by [`McapSink::close`] (or
/// [`FrameSink::finish`]). Dropping an unfinished sink still writes the summary, but leaves
/// the file under its `.partial` name.
pub struct McapSink {
    /// `None` once closed. (In a mutex only to make the sink `Sync`: the compressor isn't.)
    writer: Mutex<Option<Writer<BufWriter<File>>>>,
    path: PathBuf,
    partial: PathBuf,
    options: McapOptions,
    n_groups: usize,
    particles_channel: u16,
    stats_channel: u16,
    /// The moving walls' channel and outlines (`None`, empty: no wall moves).
    walls_channel: Option<u16>,
    moving: Vec<Outline>,
    /// Sequence number of the next frame.
    sequence: u32,
    /// Uncompressed bytes written since the last chunk was closed.
    pending_bytes: usize,
    last_close: Instant,
    fields: Vec<PackedElementField>,
    /// `fields` and the fluctuation's (frames of a run with dispersion).
    fields_fluctuation: Vec<PackedElementField>,
    message: Vec<u8>,
}

fn mcap_err(err: mcap::McapError) -> RecordError {
    RecordError::Mcap(err)
}

/// A channel on `topic` for the foxglove message type `M`, with its schema.
fn foxglove_channel<M: Encode, W: std::io::Write + std::io::Seek>(
    writer: &mut Writer<W>,
    topic: &str,
) -> Result<u16, RecordError> {
    let schema = M::get_schema()
        .ok_or_else(|| RecordError::Encode(format!("{topic}: the message type has no schema")))?;
    let id = writer
        .add_schema(&schema.name, &schema.encoding, &schema.data)
        .map_err(mcap_err)?;
    writer
        .add_channel(id, topic, &M::get_message_encoding(), &BTreeMap::new())
        .map_err(mcap_err)
}

/// `value` as JSON.
fn to_json<T: serde::Serialize + ?Sized>(value: &T) -> Result<String, RecordError> {
    serde_json::to_string(value).map_err(|e| RecordError::Encode(e.to_string()))
}

/// Metadata entries describing a run (see `META_*` in [`crate::layout`]).
fn meta_entries(meta: &RunMeta) -> Result<BTreeMap<String, String>, RecordError> {
    let groups: Vec<GroupJson> = meta.groups.iter().map(GroupJson::from).collect();
    let outlines: Vec<OutlineJson> = meta.outlines.iter().map(OutlineJson::from).collect();
    let mut entries = BTreeMap::from([
        (META_FORMAT.to_owned(), FORMAT_VERSION.to_owned()),
        (META_SCG_VERSION.to_owned(), meta.scg_version.clone()),
        (META_CASE.to_owned(), meta.case.clone()),
        (META_SEED.to_owned(), meta.seed.to_string()),
        // `{:?}` is the shortest representation that parses back to the same f64.
        (META_DT.to_owned(), format!("{:?}", meta.dt)),
        (META_RECORD_EVERY.to_owned(), meta.record_every.to_string()),
        (META_GROUPS.to_owned(), to_json(&groups)?),
        (META_WARNINGS.to_owned(), to_json(&meta.warnings)?),
        (META_OUTLINES.to_owned(), to_json(&outlines)?),
        (META_SCENE_DIR.to_owned(), meta.scene_dir.clone()),
    ]);
    if !meta.parts.is_empty() {
        entries.insert(META_PARTS.to_owned(), to_json(&meta.parts)?);
    }
    if meta.ranks > 1 {
        entries.insert(META_RANKS.to_owned(), meta.ranks.to_string());
    }
    Ok(entries)
}

fn field((name, offset, ty): (&str, u32, FieldType)) -> PackedElementField {
    PackedElementField {
        name: name.to_owned(),
        offset,
        r#type: match ty {
            FieldType::Float64 => NumericType::Float64,
            FieldType::Uint32 => NumericType::Uint32,
        } as i32,
    }
}

fn point_fields() -> Vec<PackedElementField> {
    POINT_FIELDS.iter().map(|&f| field(f)).collect()
}

/// Simulation time in ns, as MCAP log/publish time.
fn time_ns(frame: &Frame) -> Result<u64, RecordError> {
    let ns = (frame.time * 1e9).round();
    // `check_frame` guarantees a finite, non-negative time.
    if ns >= u64::MAX as f64 {
        return Err(RecordError::InvalidFrame {
            step: frame.step,
            reason: format!("time {} s does not fit in u64 nanoseconds", frame.time),
        });
    }
    Ok(ns as u64)
}

impl McapSink {
    /// Creates `<path>.partial` with default [`McapOptions`] and writes the run description.
    pub fn create(path: &Path, meta: &RunMeta) -> Result<Self, RecordError> {
        Self::create_with_options(path, meta, McapOptions::default())
    }

    /// Creates `<path>.partial` and writes the run description.
    pub fn create_with_options(
        path: &Path,
        meta: &RunMeta,
        options: McapOptions,
    ) -> Result<Self, RecordError> {
        let partial = partial_path(path);
        let file = File::create(&partial).map_err(|e| RecordError::io(&partial, e))?;
        let result = Self::start(path, &partial, file, meta, options);
        if result.is_err() {
            // Best effort: do not leave a useless `.partial` behind.
            let _ = std::fs::remove_file(&partial);
        }
        result
    }

    fn start(
        path: &Path,
        partial: &Path,
        file: File,
        meta: &RunMeta,
        options: McapOptions,
    ) -> Result<Self, RecordError> {
        let write_options = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .compression_level(options.compression_level)
            // Compress on the calling thread: the simulation uses the other cores.
            .compression_threads(0)
            .library(format!("scg-record {}", env!("CARGO_PKG_VERSION")))
            // We close chunks ourselves (see `McapOptions`).
            .chunk_size(None)
            // Build each chunk in memory and write it in one go: a killed run never leaves a
            // chunk with a placeholder header in the file, only a cut-off tail.
            .disable_seeking(true);
        let mut writer = write_options
            .create(BufWriter::new(file))
            .map_err(mcap_err)?;

        // Run description first, outside chunks, so that a truncated file keeps it.
        writer
            .write_metadata(&Metadata {
                name: METADATA_NAME.to_owned(),
                metadata: meta_entries(meta)?,
            })
            .map_err(mcap_err)?;
        let now_ns = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
        writer
            .attach(&Attachment {
                log_time: 0,
                create_time: now_ns,
                name: SCENE_ATTACHMENT.to_owned(),
                media_type: SCENE_MEDIA_TYPE.to_owned(),
                data: Cow::Borrowed(meta.scene_toml.as_bytes()),
            })
            .map_err(mcap_err)?;

        let particles_channel = foxglove_channel::<PointCloud, _>(&mut writer, TOPIC_PARTICLES)?;
        let stats_schema = writer
            .add_schema(
                STATS_SCHEMA_NAME,
                "jsonschema",
                STATS_JSON_SCHEMA.as_bytes(),
            )
            .map_err(mcap_err)?;
        let stats_channel = writer
            .add_channel(stats_schema, TOPIC_STATS, "json", &BTreeMap::new())
            .map_err(mcap_err)?;
        if !meta.patches.is_empty() {
            let channel = foxglove_channel::<SceneUpdate, _>(&mut writer, TOPIC_PATCHES)?;
            let mut data = Vec::new();
            patches_update(meta)
                .encode(&mut data)
                .map_err(|e| RecordError::Encode(e.to_string()))?;
            writer
                .write_to_known_channel(
                    &MessageHeader {
                        channel_id: channel,
                        sequence: 0,
                        log_time: 0,
                        publish_time: 0,
                    },
                    &data,
                )
                .map_err(mcap_err)?;
        }
        let moving: Vec<Outline> = meta
            .outlines
            .iter()
            .filter(|o| !o.motion.is_fixed())
            .cloned()
            .collect();
        let walls_channel = if moving.is_empty() {
            None
        } else {
            Some(foxglove_channel::<SceneUpdate, _>(
                &mut writer,
                TOPIC_WALLS,
            )?)
        };
        // Close the chunk holding the schemas and channels, and write everything so far.
        writer.flush().map_err(mcap_err)?;

        Ok(Self {
            writer: Mutex::new(Some(writer)),
            path: path.to_path_buf(),
            partial: partial.to_path_buf(),
            options,
            n_groups: meta.groups.len(),
            particles_channel,
            stats_channel,
            walls_channel,
            moving,
            sequence: 0,
            pending_bytes: 0,
            last_close: Instant::now(),
            fields: point_fields(),
            fields_fluctuation: {
                let mut f = point_fields();
                f.push(field(POINT_FIELD_FLUCTUATION));
                f
            },
            message: Vec::new(),
        })
    }

    /// The final path of the recording (valid once closed).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes one frame (a `/particles` and a `/stats` message).
    pub fn push(&mut self, frame: &Frame) -> Result<(), RecordError> {
        check_frame(frame, self.n_groups)?;
        let log_time = time_ns(frame)?;
        let writer = self
            .writer
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner);
        let Some(writer) = writer.as_mut() else {
            return Err(RecordError::Finished);
        };

        let mut data = Vec::with_capacity(frame.len() * POINT_STRIDE as usize);
        for i in 0..frame.len() {
            let (p, v) = (frame.position[i], frame.velocity[i]);
            for x in [
                p[0],
                p[1],
                p[2],
                v[0],
                v[1],
                v[2],
                frame.diameter[i],
                frame.density[i],
            ] {
                data.extend_from_slice(&x.to_le_bytes());
            }
            data.extend_from_slice(&frame.id[i].to_le_bytes());
            data.extend_from_slice(&frame.group[i].to_le_bytes());
            if let Some(u) = frame.fluctuation.get(i) {
                data.extend_from_slice(&u.to_le_bytes());
            }
        }
        let turbulent = !frame.fluctuation.is_empty();
        let timestamp = u32::try_from(log_time / 1_000_000_000)
            .ok()
            .and_then(|sec| Timestamp::new_checked(sec, (log_time % 1_000_000_000) as u32))
            .ok_or_else(|| RecordError::InvalidFrame {
                step: frame.step,
                reason: format!("time {} s out of range for a timestamp", frame.time),
            })?;
        let cloud = PointCloud {
            timestamp: Some(timestamp),
            frame_id: FRAME_ID.to_owned(),
            pose: Some(identity()),
            point_stride: if turbulent {
                POINT_STRIDE_FLUCTUATION
            } else {
                POINT_STRIDE
            },
            fields: if turbulent {
                self.fields_fluctuation.clone()
            } else {
                self.fields.clone()
            },
            data: Bytes::from(data),
        };
        self.message.clear();
        cloud
            .encode(&mut self.message)
            .map_err(|e| RecordError::Encode(e.to_string()))?;
        let header = |channel_id| MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time,
            publish_time: log_time,
        };
        writer
            .write_to_known_channel(&header(self.particles_channel), &self.message)
            .map_err(mcap_err)?;
        let mut bytes = self.message.len();

        let stats = serde_json::to_vec(&StatsOut {
            step: frame.step,
            time: frame.time,
            values: OrderedValues(&frame.stats),
        })
        .map_err(|e| RecordError::Encode(e.to_string()))?;
        writer
            .write_to_known_channel(&header(self.stats_channel), &stats)
            .map_err(mcap_err)?;
        bytes += stats.len();
        if let Some(channel) = self.walls_channel {
            let mut data = Vec::new();
            walls_update(&self.moving, frame.time, timestamp)
                .encode(&mut data)
                .map_err(|e| RecordError::Encode(e.to_string()))?;
            writer
                .write_to_known_channel(&header(channel), &data)
                .map_err(mcap_err)?;
            bytes += data.len();
        }

        self.sequence = self
            .sequence
            .checked_add(1)
            .ok_or_else(|| RecordError::Encode("more than 2³² frames".to_owned()))?;
        self.pending_bytes += bytes;
        if self.pending_bytes >= self.options.chunk_bytes
            || self.last_close.elapsed() >= self.options.chunk_interval
        {
            // Close the chunk and hand the bytes to the OS.
            writer.flush().map_err(mcap_err)?;
            self.pending_bytes = 0;
            self.last_close = Instant::now();
        }
        Ok(())
    }

    /// Attaches the wear of the walls ([`EROSION_ATTACHMENT`], JSON; f64 values round-trip
    /// exactly), logged at its time.
    pub fn push_wear(&mut self, wear: &WearMap) -> Result<(), RecordError> {
        let json = to_json(wear)?;
        let time = (wear.time * 1e9).round() as u64;
        let writer = self
            .writer
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner);
        let writer = writer.as_mut().ok_or(RecordError::Finished)?;
        writer
            .attach(&Attachment {
                log_time: time,
                create_time: time,
                name: EROSION_ATTACHMENT.to_owned(),
                media_type: "application/json".to_owned(),
                data: Cow::Owned(json.into_bytes()),
            })
            .map_err(mcap_err)
    }

    /// Writes the summary and footer, syncs the file and renames `<path>.partial` to `<path>`.
    /// Idempotent.
    pub fn close(&mut self) -> Result<(), RecordError> {
        let writer = self
            .writer
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner);
        let Some(mut writer) = writer.take() else {
            return Ok(());
        };
        writer.finish().map_err(mcap_err)?;
        let file = writer
            .into_inner()
            .into_inner()
            .map_err(|e| RecordError::io(&self.partial, e.into_error()))?;
        file.sync_all()
            .map_err(|e| RecordError::io(&self.partial, e))?;
        commit_partial(&self.partial, &self.path)
    }
}

impl FrameSink for McapSink {
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

impl Drop for McapSink {
    fn drop(&mut self) {
        let writer = self
            .writer
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner);
        if let Some(mut writer) = writer.take() {
            // Not finished: still write a complete file, left as `.partial`.
            let _ = writer.finish();
        }
    }
}
