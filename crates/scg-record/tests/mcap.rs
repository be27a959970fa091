//! MCAP recordings: writing, reading back bit for bit, recovering truncated files.

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;

use common::{N_FRAMES, assert_frames_bit_equal, frames, meta};
use foxglove::Decode;
use foxglove::messages::PointCloud;
use mcap::{MessageStream, Summary};
use scg_core::frame::{Frame, FrameSink, RunMeta};
use scg_record::layout::{
    METADATA_NAME, POINT_FIELDS, POINT_STRIDE, SCENE_ATTACHMENT, STATS_SCHEMA_NAME,
    TOPIC_PARTICLES, TOPIC_PATCHES, TOPIC_STATS,
};
use scg_record::{McapOptions, McapSink, RecordError, partial_path, read_mcap};

/// One chunk per frame, so that a truncated file keeps every frame before the cut.
fn per_frame() -> McapOptions {
    McapOptions {
        chunk_bytes: 0,
        chunk_interval: Duration::from_secs(3600),
        ..McapOptions::default()
    }
}

fn write(path: &Path, frames: &[Frame], options: McapOptions) {
    let mut sink = McapSink::create_with_options(path, &meta(), options).expect("create");
    for frame in frames {
        sink.write_frame(frame).expect("write_frame");
    }
    sink.finish().expect("finish");
}

#[test]
fn roundtrip_is_bit_exact() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (name, options) in [
        ("default.mcap", McapOptions::default()),
        ("chunked.mcap", per_frame()),
    ] {
        let path = dir.path().join(name);
        write(&path, &frames(), options);
        assert!(path.exists());
        assert!(
            !partial_path(&path).exists(),
            "the .partial file was renamed"
        );

        let rec = read_mcap(&path).expect("read_mcap");
        assert!(rec.complete);
        assert_eq!(rec.meta, meta());
        assert_frames_bit_equal(&rec.frames, &frames());
    }
}

#[test]
fn file_layout_is_as_documented() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.mcap");
    let frames = frames();
    write(&path, &frames, per_frame());
    let bytes = std::fs::read(&path).expect("read");

    // Messages, read with the mcap crate's own reader.
    let mut particles = 0;
    let mut stats = 0;
    let mut patches = 0;
    for message in MessageStream::new(&bytes).expect("stream") {
        let message = message.expect("message");
        if message.channel.topic == TOPIC_PATCHES {
            // The boundary patches: one SceneUpdate at time 0, one entity per patch.
            patches += 1;
            assert_eq!((message.sequence, message.log_time), (0, 0));
            assert_eq!(message.channel.message_encoding, "protobuf");
            let schema = message.channel.schema.as_ref().expect("schema");
            assert_eq!(schema.name, "foxglove.SceneUpdate");
            let update =
                foxglove::messages::SceneUpdate::decode(&message.data[..]).expect("update");
            let want = meta().patches;
            assert_eq!(update.entities.len(), want.len());
            for (e, p) in update.entities.iter().zip(&want) {
                assert_eq!(e.id, p.name);
                assert_eq!(e.frame_id, "world");
                assert_eq!(e.metadata[0].key, "role");
                assert_eq!(e.metadata[0].value, p.role);
                let t = &e.triangles[0];
                assert_eq!(t.indices.len(), 3 * p.triangles.len());
                assert_eq!(t.points.len(), p.vertices.len());
                assert_eq!(t.points[0].x.to_bits(), p.vertices[0][0].to_bits());
            }
            continue;
        }
        let frame = &frames[message.sequence as usize];
        let ns = (frame.time * 1e9).round() as u64;
        assert_eq!(message.log_time, ns);
        assert_eq!(message.publish_time, ns);
        let schema = message.channel.schema.as_ref().expect("schema");
        match message.channel.topic.as_str() {
            TOPIC_PARTICLES => {
                particles += 1;
                assert_eq!(message.channel.message_encoding, "protobuf");
                assert_eq!(schema.name, "foxglove.PointCloud");
                assert_eq!(schema.encoding, "protobuf");
                assert!(!schema.data.is_empty(), "FileDescriptorSet stored");
                let cloud = PointCloud::decode(&message.data[..]).expect("PointCloud");
                assert_eq!(cloud.frame_id, "world");
                assert_eq!(cloud.point_stride, POINT_STRIDE);
                let pose = cloud.pose.expect("pose");
                assert_eq!(pose.orientation.expect("orientation").w, 1.0);
                let names: Vec<_> = cloud.fields.iter().map(|f| f.name.as_str()).collect();
                let expected: Vec<_> = POINT_FIELDS.iter().map(|f| f.0).collect();
                assert_eq!(names, expected);
                assert_eq!(cloud.data.len(), frame.len() * POINT_STRIDE as usize);
                let timestamp = cloud.timestamp.expect("timestamp");
                assert_eq!(timestamp.total_nanos(), ns);
                // First point's x, bit for bit.
                let x = f64::from_le_bytes(cloud.data[0..8].try_into().expect("8 bytes"));
                assert_eq!(x.to_bits(), frame.position[0][0].to_bits());
            }
            TOPIC_STATS => {
                stats += 1;
                assert_eq!(message.channel.message_encoding, "json");
                assert_eq!(schema.name, STATS_SCHEMA_NAME);
                assert_eq!(schema.encoding, "jsonschema");
                let value: serde_json::Value = serde_json::from_slice(&message.data).expect("JSON");
                assert_eq!(value["step"], frame.step);
                assert!(value["values"].is_object());
            }
            other => panic!("unexpected topic {other}"),
        }
    }
    assert_eq!((particles, stats, patches), (N_FRAMES, N_FRAMES, 1));

    // Summary: statistics, chunk indexes, attachment and metadata indexes.
    let summary = Summary::read(&bytes)
        .expect("summary")
        .expect("has a summary");
    let stats = summary.stats.as_ref().expect("statistics");
    assert_eq!(stats.message_count, 2 * N_FRAMES as u64 + 1);
    assert_eq!(stats.channel_count, 3);
    assert_eq!(stats.attachment_count, 1);
    assert_eq!(stats.metadata_count, 1);
    // One chunk for the schemas and channels, then one per frame.
    assert_eq!(summary.chunk_indexes.len(), N_FRAMES + 1);
    assert!(
        summary
            .chunk_indexes
            .iter()
            .all(|c| c.compression == "zstd")
    );
    assert!(
        summary.chunk_indexes[1..]
            .iter()
            .all(|c| !c.message_index_offsets.is_empty())
    );

    assert_eq!(summary.attachment_indexes.len(), 1);
    let attachment =
        mcap::read::attachment(&bytes, &summary.attachment_indexes[0]).expect("attachment");
    assert_eq!(attachment.name, SCENE_ATTACHMENT);
    assert_eq!(&attachment.data[..], meta().scene_toml.as_bytes());

    assert_eq!(summary.metadata_indexes.len(), 1);
    let metadata = mcap::read::metadata(&bytes, &summary.metadata_indexes[0]).expect("metadata");
    assert_eq!(metadata.name, METADATA_NAME);
    let expected: BTreeMap<&str, String> = BTreeMap::from([
        ("format", "scg-record/1".to_owned()),
        ("case", meta().case),
        ("scg_version", meta().scg_version),
        ("seed", meta().seed.to_string()),
        ("record_every", meta().record_every.to_string()),
    ]);
    for (key, value) in expected {
        assert_eq!(metadata.metadata.get(key), Some(&value), "metadata `{key}`");
    }
    let dt: f64 = metadata.metadata["dt"].parse().expect("dt");
    assert_eq!(dt.to_bits(), meta().dt.to_bits());
    let groups: serde_json::Value =
        serde_json::from_str(&metadata.metadata["groups"]).expect("groups JSON");
    assert_eq!(groups[1]["name"], "large grains");
    assert_eq!(groups[2]["color"], serde_json::json!([20, 200, 90]));
    let warnings: Vec<String> =
        serde_json::from_str(&metadata.metadata["warnings"]).expect("warnings JSON");
    assert_eq!(warnings, meta().warnings);
}

/// The end offsets of the chunks holding frames (the first chunk holds schemas/channels).
fn frame_chunk_ends(bytes: &[u8]) -> Vec<u64> {
    let summary = Summary::read(bytes)
        .expect("summary")
        .expect("has a summary");
    summary.chunk_indexes[1..]
        .iter()
        .map(|c| c.chunk_start_offset + c.chunk_length)
        .collect()
}

#[test]
fn truncated_files_keep_complete_frames() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.mcap");
    let frames = frames();
    write(&path, &frames, per_frame());
    let bytes = std::fs::read(&path).expect("read");
    let ends = frame_chunk_ends(&bytes);
    assert_eq!(ends.len(), N_FRAMES);
    let first_chunk_end = {
        let summary = Summary::read(&bytes).expect("summary").expect("summary");
        summary.chunk_indexes[0].chunk_start_offset + summary.chunk_indexes[0].chunk_length
    };

    let cut_path = dir.path().join("cut.mcap");
    let mut cuts: Vec<usize> = (0..bytes.len()).step_by(13).collect();
    for &end in &ends {
        let end = end as usize;
        cuts.extend([end - 1, end, end + 1]);
    }
    cuts.push(bytes.len() - 1);
    let mut recovered_some = 0;
    for cut in cuts {
        std::fs::write(&cut_path, &bytes[..cut]).expect("write cut");
        match read_mcap(&cut_path) {
            Ok(rec) => {
                assert!(
                    !rec.complete,
                    "cut at {cut} of {} is not complete",
                    bytes.len()
                );
                if cut as u64 >= first_chunk_end {
                    assert_eq!(rec.meta, meta(), "cut at {cut}");
                } else {
                    // The scene attachment may be cut off, the metadata record is there.
                    assert_eq!(rec.meta.groups, meta().groups, "cut at {cut}");
                }
                let expected = ends.iter().filter(|&&e| e as usize <= cut).count();
                assert_eq!(rec.frames.len(), expected, "frames kept for a cut at {cut}");
                assert_frames_bit_equal(&rec.frames, &frames[..expected]);
                if cut as u64 >= ends[0] {
                    assert!(!rec.frames.is_empty());
                    recovered_some += 1;
                }
            }
            Err(err) => {
                // Only a cut before the end of the first chunk (header, metadata, attachment,
                // schemas) may lose everything.
                assert!(
                    (cut as u64) < first_chunk_end,
                    "cut at {cut} (first chunk ends at {first_chunk_end}): {err}"
                );
                assert!(matches!(err, RecordError::Format { .. }), "{err}");
            }
        }
    }
    assert!(recovered_some > 10);
}

#[test]
fn a_killed_run_leaves_a_readable_partial_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.mcap");
    let frames = frames();
    let mut sink = McapSink::create_with_options(&path, &meta(), per_frame()).expect("create");
    for frame in &frames[..3] {
        sink.write_frame(frame).expect("write");
    }
    // What a SIGKILL now would leave: the .partial file as it is on disk.
    let snapshot = std::fs::read(partial_path(&path)).expect("partial exists");
    let killed = dir.path().join("killed.mcap");
    std::fs::write(&killed, &snapshot).expect("write snapshot");
    let rec = read_mcap(&killed).expect("recover");
    assert!(!rec.complete);
    assert_eq!(rec.meta, meta());
    assert_frames_bit_equal(&rec.frames, &frames[..3]);

    // Dropping without finish closes the .partial file properly but does not rename it.
    drop(sink);
    assert!(!path.exists());
    let rec = read_mcap(&partial_path(&path)).expect("read dropped");
    assert!(rec.complete);
    assert_frames_bit_equal(&rec.frames, &frames[..3]);
}

#[test]
fn bad_files_are_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("missing.mcap");
    assert!(matches!(read_mcap(&missing), Err(RecordError::Io { .. })));

    let empty = dir.path().join("empty.mcap");
    std::fs::write(&empty, b"").expect("write");
    assert!(matches!(read_mcap(&empty), Err(RecordError::Format { .. })));

    let garbage = dir.path().join("garbage.mcap");
    let bytes: Vec<u8> = (0..10_000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    std::fs::write(&garbage, &bytes).expect("write");
    assert!(matches!(
        read_mcap(&garbage),
        Err(RecordError::Format { .. })
    ));

    // The right magic followed by garbage, including huge record lengths.
    let mut magic_garbage = b"\x89MCAP0\r\n".to_vec();
    magic_garbage.extend_from_slice(&[0x01, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x7f]);
    magic_garbage.extend_from_slice(&bytes);
    std::fs::write(&garbage, &magic_garbage).expect("write");
    assert!(read_mcap(&garbage).is_err());

    // A valid MCAP file that is not an scg recording.
    let foreign = dir.path().join("foreign.mcap");
    {
        let file = std::fs::File::create(&foreign).expect("create");
        let mut writer = mcap::Writer::new(std::io::BufWriter::new(file)).expect("writer");
        writer.finish().expect("finish");
    }
    assert!(matches!(
        read_mcap(&foreign),
        Err(RecordError::Format { .. })
    ));

    // A file with a flipped byte inside a chunk: CRC mismatch, reading stops there.
    let path = dir.path().join("run.mcap");
    write(&path, &frames(), per_frame());
    let mut bytes = std::fs::read(&path).expect("read");
    let ends = frame_chunk_ends(&bytes);
    let target = (ends[1] - 20) as usize; // inside frame 1's compressed data
    bytes[target] ^= 0x55;
    let damaged = dir.path().join("damaged.mcap");
    std::fs::write(&damaged, &bytes).expect("write");
    let rec = read_mcap(&damaged).expect("recovers what precedes the damage");
    assert!(!rec.complete);
    assert_frames_bit_equal(&rec.frames, &frames()[..1]);
}

#[test]
fn invalid_frames_are_rejected() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.mcap");
    let mut sink = McapSink::create(&path, &meta()).expect("create");
    let good = frames().remove(0);

    let mut short = good.clone();
    short.density.pop();
    assert!(sink.write_frame(&short).is_err());

    let mut bad_group = good.clone();
    bad_group.group[3] = 3;
    assert!(sink.write_frame(&bad_group).is_err());

    let mut bad_time = good.clone();
    bad_time.time = f64::NAN;
    assert!(sink.write_frame(&bad_time).is_err());

    sink.write_frame(&good)
        .expect("a good frame still goes through");
    sink.finish().expect("finish");
    assert!(sink.finish().is_ok(), "finish is idempotent");
    assert!(matches!(sink.push(&good), Err(RecordError::Finished)));

    let rec = read_mcap(&path).expect("read");
    assert_frames_bit_equal(&rec.frames, &[good]);
}

#[test]
fn empty_run() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.mcap");
    write(&path, &[], McapOptions::default());
    let rec = read_mcap(&path).expect("read");
    assert!(rec.complete);
    assert!(rec.frames.is_empty());
    assert_eq!(rec.meta, meta());
}

/// A recording written per rank: three parts (each a rank's particles and counts of every
/// frame) and an index naming them read as one recording, bit for bit the frames one rank
/// writes (stats recomputed in id order, counts summed); an index with frames, parts at
/// different steps and a missing part are errors naming the file.
#[test]
fn parts_named_by_an_index_read_as_one_recording() {
    use scg_core::stages::recording::{FrameRow, RecordingParams, frame_from_rows, rows_of_frame};
    use scg_core::state::Tally;
    let dir = tempfile::tempdir().expect("tempdir");
    let m = meta();
    let params = RecordingParams {
        every: m.record_every,
        groups: m.groups.iter().map(|g| g.name.clone()).collect(),
    };
    let ng = params.groups.len();
    let tally = |k: u64, part: Option<u64>| {
        let mut t = Tally::new(ng);
        t.collisions = vec![0; ng];
        for g in 0..ng as u64 {
            // part p of 3 holds a third of each count
            let (d, c) = (10 * k + g, 3 * k + g);
            t.drained[g as usize] = part.map_or(3 * d, |_| d);
            t.collisions[g as usize] = part.map_or(3 * c, |_| c);
        }
        t
    };
    let mut whole = Vec::new();
    let mut parts: Vec<Vec<Frame>> = vec![Vec::new(); 3];
    for (k, f) in frames().iter().enumerate() {
        let rows = rows_of_frame(f);
        whole.push(frame_from_rows(
            f.step,
            f.time,
            &params,
            &tally(k as u64, None),
            rows.clone(),
        ));
        for (p, part) in parts.iter_mut().enumerate() {
            // a rank's rows in table order (reversed here), not sorted
            let mine: Vec<FrameRow> = rows
                .iter()
                .rev()
                .filter(|r| r.id % 3 == p as u32)
                .cloned()
                .collect();
            part.push(frame_from_rows(
                f.step,
                f.time,
                &params,
                &tally(k as u64, Some(p as u64)),
                mine,
            ));
        }
    }
    let names: Vec<String> = (0..3).map(|p| format!("run.rank{p}.mcap")).collect();
    for (p, part) in parts.iter().enumerate() {
        write(&dir.path().join(&names[p]), part, McapOptions::default());
    }
    let index = dir.path().join("run.mcap");
    let idx_meta = RunMeta {
        parts: names.clone(),
        ..m.clone()
    };
    McapSink::create(&index, &idx_meta)
        .and_then(|mut s| s.close())
        .expect("index");
    let rec = read_mcap(&index).expect("read the set");
    assert!(rec.complete);
    assert_eq!(rec.meta.parts, names);
    assert_frames_bit_equal(&rec.frames, &whole);
    assert!(whole.iter().any(|f| {
        f.stats
            .iter()
            .any(|(k, v)| k.starts_with("collisions") && *v > 0.0)
    }));

    // A part at another step: an error naming the index.
    let mut shifted = parts[1].clone();
    shifted[2].step += 1;
    write(
        &dir.path().join(&names[1]),
        &shifted,
        McapOptions::default(),
    );
    let err = read_mcap(&index).expect_err("steps differ").to_string();
    assert!(err.contains("run.mcap") && err.contains("step"), "{err}");
    // A missing part: the reader's error names it.
    std::fs::remove_file(dir.path().join(&names[1])).unwrap();
    let err = read_mcap(&index).expect_err("part missing").to_string();
    assert!(err.contains(&names[1]), "{err}");
    // An index that holds frames.
    let mut sink = McapSink::create(&index, &idx_meta).expect("index");
    sink.write_frame(&whole[0]).expect("frame");
    sink.finish().expect("finish");
    let err = read_mcap(&index)
        .expect_err("index with frames")
        .to_string();
    assert!(err.contains("holds frames"), "{err}");
}
