//! Reading an MCAP recording back: [`read_mcap`].

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::Read;
use std::path::Path;

use foxglove::Decode;
use foxglove::messages::packed_element_field::NumericType;
use foxglove::messages::{PointCloud, SceneUpdate};
use mcap::records::Record;
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use scg_core::frame::{Frame, GroupMeta, Outline, PatchSurface, RunMeta};

use crate::layout::{
    EROSION_ATTACHMENT, FORMAT_VERSION, FieldType, GroupJson, META_CASE, META_DT, META_FORMAT,
    META_GROUPS, META_OUTLINES, META_PARTS, META_RANKS, META_RECORD_EVERY, META_SCENE_DIR,
    META_SCG_VERSION, META_SEED, META_WARNINGS, METADATA_NAME, OutlineJson,
    POINT_FIELD_FLUCTUATION, POINT_FIELDS, SCENE_ATTACHMENT, StatsIn, TOPIC_PARTICLES,
    TOPIC_PATCHES, TOPIC_STATS,
};
use crate::{RecordError, Recording};

/// Largest read handed to the MCAP reader at once (the reader asks for whole records; this
/// keeps a damaged length field from allocating more than the file holds).
const READ_BLOCK: usize = 4 << 20;

/// Reads an MCAP recording written by [`crate::McapSink`].
///
/// The file is read sequentially, with every chunk's CRC checked before its messages are
/// used (and the data and summary section CRCs when present). A file cut short, e.g. by a
/// killed run (no summary, last chunk incomplete), is recovered: every complete frame is
/// returned and [`Recording::complete`] is false. Reading also stops, keeping the frames read
/// so far, at the first damaged record (bad CRC…).
///
/// Errors: the file cannot be read, is not an MCAP file, or holds no `scg` metadata record.
/// [`McapFrames`] reads the same file one frame at a time.
pub fn read_mcap(path: &Path) -> Result<Recording, RecordError> {
    let mut frames_in = McapFrames::open(path)?;
    let mut frames = Vec::new();
    for f in frames_in.by_ref() {
        frames.push(f?);
    }
    let (meta, complete, wear) = frames_in.into_parts();
    let rec = Recording {
        meta,
        frames,
        complete,
        wear,
    };
    if rec.meta.parts.is_empty() {
        Ok(rec)
    } else {
        crate::parts::merge_parts(path, rec)
    }
}

/// An MCAP recording read one frame at a time, in the order written, holding one frame
/// (one chunk) in memory: what [`read_mcap`] collects. The run description
/// ([`McapFrames::meta`]: groups, scene text, patches) is read on opening; the wear of an
/// erosion run ([`McapFrames::wear`]) and whether the file was closed properly
/// ([`McapFrames::complete`]) are known once the last frame was read. A per-rank
/// recording's index (its `parts`) holds no frames of its own: [`read_mcap`] merges them.
pub struct McapFrames {
    path: std::path::PathBuf,
    file: File,
    reader: LinearReader,
    state: ReadState,
    meta: RunMeta,
    /// `Some` once the file was read to its end or to its first damaged record.
    outcome: Option<Result<(), String>>,
    /// A frame assembled while opening (the reader stops at the first particles).
    ready: std::collections::VecDeque<Frame>,
}

impl McapFrames {
    /// Open `path` and read its run description (up to its first frame).
    ///
    /// Errors: the file cannot be read, is not an MCAP file, or holds no `scg` metadata
    /// record.
    pub fn open(path: &Path) -> Result<Self, RecordError> {
        let io = |e| RecordError::io(path, e);
        let file = File::open(path).map_err(io)?;
        let file_len = file.metadata().map_err(io)?.len();
        // A record can't be longer than the file; a chunk can decompress to more, but not
        // absurdly more.
        let limit =
            usize::try_from(file_len.saturating_mul(100).max(64 << 20)).unwrap_or(usize::MAX);
        let reader = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_emit_chunks(false)
                .with_validate_chunk_crcs(true)
                .with_prevalidate_chunk_crcs(true)
                .with_validate_data_section_crc(true)
                .with_validate_summary_section_crc(true)
                .with_record_length_limit(limit),
        );
        let mut frames = McapFrames {
            path: path.to_path_buf(),
            file,
            reader,
            state: ReadState::default(),
            meta: RunMeta::default(),
            outcome: None,
            ready: Default::default(),
        };
        while frames.outcome.is_none() && frames.state.pending.is_empty() {
            frames.advance()?;
        }
        let format = |reason: String| RecordError::Format {
            path: path.to_path_buf(),
            reason,
        };
        if !frames.state.saw_header {
            return Err(format(match &frames.outcome {
                Some(Err(err)) => format!("not an MCAP file ({err})"),
                _ => "not an MCAP file".to_owned(),
            }));
        }
        let Some(mut meta) = frames.state.meta.take() else {
            let why = match &frames.outcome {
                Some(Err(e)) => format!(" ({e})"),
                _ => String::new(),
            };
            return Err(format(format!("no `{METADATA_NAME}` metadata record{why}")));
        };
        meta.scene_toml = frames.state.scene_toml.take().unwrap_or_default();
        meta.patches = std::mem::take(&mut frames.state.patches);
        frames.meta = meta;
        frames.collect_ready();
        Ok(frames)
    }

    /// The run description: groups, dt, the scene's text, the patches (a per-rank
    /// index's `parts`).
    pub fn meta(&self) -> &RunMeta {
        &self.meta
    }

    /// True once the file was read to its end and was closed properly (summary and
    /// footer present and valid); false before, and for a file cut short.
    pub fn complete(&self) -> bool {
        matches!(self.outcome, Some(Ok(()))) && self.state.saw_footer
    }

    /// The wear of the walls at the end of a run with `[erosion]`, once read (`None`
    /// without, or before the last frame was read).
    pub fn wear(&self) -> Option<&scg_core::frame::WearMap> {
        self.state.wear.as_ref()
    }

    /// The run description, whether the file was closed properly and the wear.
    pub fn into_parts(mut self) -> (RunMeta, bool, Option<scg_core::frame::WearMap>) {
        let complete = self.complete();
        (self.meta, complete, self.state.wear.take())
    }

    /// Read one record (or a block of the file); sets `outcome` at the end.
    fn advance(&mut self) -> Result<(), RecordError> {
        match self.reader.next_event() {
            None => self.outcome = Some(Ok(())),
            Some(Err(err)) => self.outcome = Some(Err(err.to_string())),
            Some(Ok(LinearReadEvent::ReadRequest(need))) => {
                let buf = self.reader.insert(need.clamp(1, READ_BLOCK));
                let got = loop {
                    match self.file.read(buf) {
                        Ok(n) => break n,
                        Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                        Err(e) => return Err(RecordError::io(&self.path, e)),
                    }
                };
                self.reader.notify_read(got);
            }
            Some(Ok(LinearReadEvent::Record { opcode, data })) => {
                let handled = mcap::parse_record(opcode, data)
                    .map_err(|e| e.to_string())
                    .and_then(|record| self.state.handle(record));
                if let Err(err) = handled {
                    self.outcome = Some(Err(err));
                }
            }
        }
        Ok(())
    }

    /// Move the frames whose two halves arrived (in order of sequence) to `ready`.
    fn collect_ready(&mut self) {
        while let Some(entry) = self.state.pending.first_entry() {
            let p = entry.get();
            if p.particles.is_none() || p.stats.is_none() {
                break;
            }
            if let Pending {
                particles: Some(frame),
                stats: Some(stats),
            } = entry.remove()
            {
                self.ready.push_back(assemble(frame, stats));
            }
        }
    }
}

/// A frame's particles with its step, time and stats.
fn assemble(mut frame: Frame, stats: StatsIn) -> Frame {
    frame.step = stats.step;
    frame.time = stats.time;
    frame.stats = stats.values.0;
    frame
}

impl Iterator for McapFrames {
    type Item = Result<Frame, RecordError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(f) = self.ready.pop_front() {
                return Some(Ok(f));
            }
            if self.outcome.is_some() {
                break;
            }
            if let Err(e) = self.advance() {
                self.outcome = Some(Err(e.to_string()));
                return Some(Err(e));
            }
            self.collect_ready();
        }
        // The end: the frames left whole (after a half one, in a file cut short) in order;
        // a half frame in a file closed properly is an error.
        let complete = self.complete();
        while let Some((sequence, p)) = self.state.pending.pop_first() {
            match p {
                Pending {
                    particles: Some(frame),
                    stats: Some(stats),
                } => return Some(Ok(assemble(frame, stats))),
                // A killed run can't separate the two messages of a frame (they share a
                // chunk), so this is damage; in a file that was closed properly it is an
                // error.
                _ if complete => {
                    return Some(Err(RecordError::Format {
                        path: self.path.clone(),
                        reason: format!(
                            "frame {sequence} lacks its `{TOPIC_PARTICLES}` or `{TOPIC_STATS}` message"
                        ),
                    }));
                }
                _ => {}
            }
        }
        None
    }
}

/// What a channel carries.
#[derive(Clone, Copy, PartialEq, Eq)]
enum ChannelKind {
    Particles,
    Stats,
    Patches,
    Other,
}

/// The two halves of a frame, matched by sequence number.
#[derive(Default)]
struct Pending {
    particles: Option<Frame>,
    stats: Option<StatsIn>,
}

#[derive(Default)]
struct ReadState {
    saw_header: bool,
    saw_footer: bool,
    /// Schema id → (name, encoding).
    schemas: HashMap<u16, (String, String)>,
    channels: HashMap<u16, ChannelKind>,
    meta: Option<RunMeta>,
    scene_toml: Option<String>,
    wear: Option<scg_core::frame::WearMap>,
    patches: Vec<PatchSurface>,
    pending: BTreeMap<u32, Pending>,
}

impl ReadState {
    fn handle(&mut self, record: Record<'_>) -> Result<(), String> {
        match record {
            Record::Header(_) => self.saw_header = true,
            Record::Footer(_) => self.saw_footer = true,
            Record::Schema { header, .. } => {
                self.schemas
                    .insert(header.id, (header.name, header.encoding));
            }
            Record::Channel(channel) => {
                let kind = match channel.topic.as_str() {
                    TOPIC_PARTICLES => ChannelKind::Particles,
                    TOPIC_STATS => ChannelKind::Stats,
                    TOPIC_PATCHES => ChannelKind::Patches,
                    _ => ChannelKind::Other,
                };
                let schema = self.schemas.get(&channel.schema_id);
                let expected = match kind {
                    ChannelKind::Particles => Some(("protobuf", "foxglove.PointCloud")),
                    ChannelKind::Stats => Some(("json", "")),
                    ChannelKind::Patches => Some(("protobuf", "foxglove.SceneUpdate")),
                    ChannelKind::Other => None,
                };
                if let Some((encoding, schema_name)) = expected {
                    let schema_ok = schema_name.is_empty()
                        || schema.is_some_and(|(name, _)| name == schema_name);
                    if channel.message_encoding != encoding || !schema_ok {
                        return Err(format!(
                            "channel `{}` has encoding `{}` (schema {:?}), expected `{encoding}` {schema_name}",
                            channel.topic,
                            channel.message_encoding,
                            schema.map(|(name, _)| name)
                        ));
                    }
                }
                self.channels.insert(channel.id, kind);
            }
            Record::Message { header, data } => {
                let kind = self
                    .channels
                    .get(&header.channel_id)
                    .copied()
                    .ok_or_else(|| format!("message on unknown channel {}", header.channel_id))?;
                match kind {
                    ChannelKind::Particles => {
                        let frame = decode_particles(&data)
                            .map_err(|e| format!("frame {}: {e}", header.sequence))?;
                        self.pending.entry(header.sequence).or_default().particles = Some(frame);
                    }
                    ChannelKind::Stats => {
                        let stats: StatsIn = serde_json::from_slice(&data).map_err(|e| {
                            format!(
                                "frame {}: bad `{TOPIC_STATS}` message: {e}",
                                header.sequence
                            )
                        })?;
                        self.pending.entry(header.sequence).or_default().stats = Some(stats);
                    }
                    ChannelKind::Patches => {
                        self.patches =
                            decode_patches(&data).map_err(|e| format!("`{TOPIC_PATCHES}`: {e}"))?;
                    }
                    ChannelKind::Other => {}
                }
            }
            Record::Metadata(metadata) if metadata.name == METADATA_NAME => {
                self.meta = Some(parse_meta(&metadata.metadata)?);
            }
            Record::Attachment { header, data, .. } if header.name == EROSION_ATTACHMENT => {
                self.wear = Some(
                    serde_json::from_slice(&data)
                        .map_err(|e| format!("attachment `{EROSION_ATTACHMENT}`: {e}"))?,
                );
            }
            Record::Attachment { header, data, .. } if header.name == SCENE_ATTACHMENT => {
                let text = String::from_utf8(data.into_owned())
                    .map_err(|_| format!("attachment `{SCENE_ATTACHMENT}` is not UTF-8"))?;
                self.scene_toml = Some(text);
            }
            _ => {}
        }
        Ok(())
    }
}

/// Rebuilds a [`RunMeta`] (without its scene text) from the `scg` metadata record.
fn parse_meta(entries: &BTreeMap<String, String>) -> Result<RunMeta, String> {
    let get = |key: &str| {
        entries
            .get(key)
            .ok_or_else(|| format!("metadata key `{key}` missing"))
    };
    let bad = |key: &str, err: &dyn std::fmt::Display| format!("metadata key `{key}`: {err}");
    if let Some(format) = entries.get(META_FORMAT)
        && format != FORMAT_VERSION
    {
        return Err(format!(
            "unsupported layout `{format}` (this reader knows `{FORMAT_VERSION}`)"
        ));
    }
    let groups: Vec<GroupJson> =
        serde_json::from_str(get(META_GROUPS)?).map_err(|e| bad(META_GROUPS, &e))?;
    let warnings: Vec<String> = match entries.get(META_WARNINGS) {
        Some(text) => serde_json::from_str(text).map_err(|e| bad(META_WARNINGS, &e))?,
        None => Vec::new(),
    };
    let outlines: Vec<OutlineJson> = match entries.get(META_OUTLINES) {
        Some(text) => serde_json::from_str(text).map_err(|e| bad(META_OUTLINES, &e))?,
        None => Vec::new(),
    };
    Ok(RunMeta {
        case: get(META_CASE)?.clone(),
        scg_version: get(META_SCG_VERSION)?.clone(),
        seed: get(META_SEED)?.parse().map_err(|e| bad(META_SEED, &e))?,
        dt: get(META_DT)?.parse().map_err(|e| bad(META_DT, &e))?,
        record_every: get(META_RECORD_EVERY)?
            .parse()
            .map_err(|e| bad(META_RECORD_EVERY, &e))?,
        groups: groups.into_iter().map(GroupMeta::from).collect(),
        scene_toml: String::new(),
        scene_dir: entries.get(META_SCENE_DIR).cloned().unwrap_or_default(),
        outlines: outlines.into_iter().map(Outline::from).collect(),
        patches: Vec::new(),
        warnings,
        parts: match entries.get(META_PARTS) {
            Some(text) => serde_json::from_str(text).map_err(|e| bad(META_PARTS, &e))?,
            None => Vec::new(),
        },
        ranks: match entries.get(META_RANKS) {
            Some(text) => text.parse().map_err(|e| bad(META_RANKS, &e))?,
            None => 1,
        },
    })
}

/// Decodes the `/flow/patches` scene update into the patches (name = entity id, role =
/// metadata `role`, vertices and triangles of its first triangle list).
fn decode_patches(data: &[u8]) -> Result<Vec<PatchSurface>, String> {
    let update = SceneUpdate::decode(data).map_err(|e| format!("bad scene update: {e}"))?;
    update
        .entities
        .into_iter()
        .map(|e| {
            let role = e
                .metadata
                .iter()
                .find(|kv| kv.key == "role")
                .map_or_else(|| "lost".to_owned(), |kv| kv.value.clone());
            let list = e.triangles.into_iter().next().unwrap_or_default();
            let n = list.points.len();
            if list.indices.len() % 3 != 0 || list.indices.iter().any(|&i| i as usize >= n) {
                return Err(format!(
                    "patch `{}`: {} indices for {n} points",
                    e.id,
                    list.indices.len()
                ));
            }
            Ok(PatchSurface {
                name: e.id,
                role,
                vertices: list.points.iter().map(|p| [p.x, p.y, p.z]).collect(),
                triangles: list
                    .indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect(),
            })
        })
        .collect()
}

/// Decodes a `/particles` point cloud into a frame (step, time and stats left empty).
///
/// Fields are looked up by name, so any stride and field order is accepted as long as the
/// ten fields of [`POINT_FIELDS`] are there with their types.
fn decode_particles(data: &[u8]) -> Result<Frame, String> {
    let cloud = PointCloud::decode(data).map_err(|e| format!("bad point cloud: {e}"))?;
    let stride = cloud.point_stride as usize;
    let mut offsets = [0usize; POINT_FIELDS.len()];
    for (slot, &(name, _, ty)) in offsets.iter_mut().zip(POINT_FIELDS.iter()) {
        let (expected, size) = match ty {
            FieldType::Float64 => (NumericType::Float64, 8),
            FieldType::Uint32 => (NumericType::Uint32, 4),
        };
        let field = cloud
            .fields
            .iter()
            .find(|f| f.name == name)
            .ok_or_else(|| format!("point field `{name}` missing"))?;
        if field.r#type != expected as i32 {
            return Err(format!("point field `{name}` has type {}", field.r#type));
        }
        let offset = field.offset as usize;
        if offset + size > stride {
            return Err(format!("point field `{name}` overruns the stride {stride}"));
        }
        *slot = offset;
    }
    // The optional fluctuation (runs with dispersion), by name as the others.
    let (fname, _, _) = POINT_FIELD_FLUCTUATION;
    let fluct = match cloud.fields.iter().find(|f| f.name == fname) {
        None => None,
        Some(f) if f.r#type != NumericType::Float64 as i32 => {
            return Err(format!("point field `{fname}` has type {}", f.r#type));
        }
        Some(f) if f.offset as usize + 8 > stride => {
            return Err(format!(
                "point field `{fname}` overruns the stride {stride}"
            ));
        }
        Some(f) => Some(f.offset as usize),
    };
    let bytes = cloud.data.as_ref();
    if stride == 0 || bytes.len() % stride != 0 {
        return Err(format!(
            "{} data bytes are not a whole number of {stride}-byte points",
            bytes.len()
        ));
    }

    let n = bytes.len() / stride;
    let mut frame = Frame::with_capacity(0, 0.0, n);
    let [x, y, z, vx, vy, vz, d, rho, id, group] = offsets;
    for point in bytes.chunks_exact(stride) {
        let f = |at: usize| {
            let mut b = [0u8; 8];
            b.copy_from_slice(&point[at..at + 8]);
            f64::from_le_bytes(b)
        };
        let u = |at: usize| {
            let mut b = [0u8; 4];
            b.copy_from_slice(&point[at..at + 4]);
            u32::from_le_bytes(b)
        };
        frame.position.push([f(x), f(y), f(z)]);
        frame.velocity.push([f(vx), f(vy), f(vz)]);
        frame.diameter.push(f(d));
        frame.density.push(f(rho));
        frame.id.push(u(id));
        frame.group.push(u(group));
        if let Some(at) = fluct {
            frame.fluctuation.push(f(at));
        }
    }
    Ok(frame)
}
