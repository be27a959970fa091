//! Rerun recordings: decoded with Rerun's own decoder.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use common::{N_FRAMES, frames, meta};
use rerun::external::re_log_encoding::DecoderApp;
use rerun::log::{Chunk, LogMsg};
use rerun::{EntityPath, EntityPathPart, Points3D, StoreKind, TimelineName};
use scg_core::frame::{Frame, FrameSink};
use scg_record::layout::{
    COMPONENT_FLUCTUATION, COMPONENT_PARTICLE_ID, TIMELINE_SIM_TIME, TIMELINE_STEP,
};
use scg_record::{McapSink, RecordError, RrdSink, partial_path, read_mcap, write_rrd};

/// What an `.rrd` file holds, as decoded by Rerun.
struct Decoded {
    /// Store infos of the recording (not of the blueprint).
    store_infos: usize,
    /// Chunks of the recording.
    chunks: Vec<Chunk>,
    /// Entity paths of the blueprint's chunks.
    blueprint_entities: BTreeSet<String>,
    /// Whether a blueprint store was declared and activated (as the default).
    blueprint_activated: bool,
    /// Number of RRD manifests in the footer (0 without footer).
    manifests: usize,
}

fn decode(path: &Path) -> Decoded {
    let file = File::open(path).expect("open rrd");
    let mut messages = DecoderApp::decode_eager(BufReader::new(file)).expect("an rrd stream");
    let mut decoded = Decoded {
        store_infos: 0,
        chunks: Vec::new(),
        blueprint_entities: BTreeSet::new(),
        blueprint_activated: false,
        manifests: 0,
    };
    let mut blueprint_id = None;
    for message in messages.by_ref() {
        match message.expect("message") {
            LogMsg::SetStoreInfo(info) => {
                assert_eq!(info.info.store_id.application_id().as_str(), "scg");
                match info.info.store_id.kind() {
                    StoreKind::Recording => decoded.store_infos += 1,
                    StoreKind::Blueprint => {
                        let id = blueprint_id.get_or_insert_with(|| info.info.store_id.clone());
                        assert_eq!(id, &info.info.store_id, "one blueprint");
                    }
                }
            }
            LogMsg::ArrowMsg(store, arrow) => {
                let chunk = Chunk::from_arrow_msg(&arrow).expect("chunk");
                match store.kind() {
                    StoreKind::Recording => decoded.chunks.push(chunk),
                    StoreKind::Blueprint => {
                        decoded
                            .blueprint_entities
                            .insert(chunk.entity_path().to_string());
                    }
                }
            }
            LogMsg::BlueprintActivationCommand(cmd) => {
                assert_eq!(Some(&cmd.blueprint_id), blueprint_id.as_ref());
                decoded.blueprint_activated = cmd.make_active && cmd.make_default;
            }
        }
    }
    decoded.manifests = messages.rrd_manifests().expect("footer").len();
    decoded
}

fn entity(parent: &str, name: &str) -> EntityPath {
    EntityPath::new(vec![EntityPathPart::new(parent), EntityPathPart::new(name)])
}

/// (step, particle id) → (sim_time ns, position, radius), from the particle entities.
type Particles = BTreeMap<(i64, u32), (i64, [f32; 3], f32)>;

fn particles(decoded: &Decoded) -> (Particles, BTreeMap<EntityPath, usize>) {
    let mut out = Particles::new();
    let mut rows_per_entity = BTreeMap::new();
    let groups: BTreeSet<EntityPath> = meta()
        .groups
        .iter()
        .map(|g| entity("particles", &g.name))
        .collect();
    for chunk in &decoded.chunks {
        if !groups.contains(chunk.entity_path()) {
            continue;
        }
        assert!(!chunk.is_static());
        let timelines: BTreeSet<String> = chunk.timelines().keys().map(|t| t.to_string()).collect();
        assert_eq!(
            timelines,
            BTreeSet::from([TIMELINE_SIM_TIME.to_owned(), TIMELINE_STEP.to_owned()])
        );
        let steps = chunk.timelines()[&TimelineName::from_static_str(TIMELINE_STEP)].times_raw();
        let times =
            chunk.timelines()[&TimelineName::from_static_str(TIMELINE_SIM_TIME)].times_raw();
        let positions: Vec<&[[f32; 3]]> = chunk
            .iter_slices::<[f32; 3]>(Points3D::descriptor_positions().component)
            .collect();
        let radii: Vec<&[f32]> = chunk
            .iter_slices::<f32>(Points3D::descriptor_radii().component)
            .collect();
        let ids: Vec<&[u32]> = chunk
            .iter_slices::<u32>(COMPONENT_PARTICLE_ID.into())
            .collect();
        let rows = chunk.num_rows();
        assert_eq!(
            (
                steps.len(),
                times.len(),
                positions.len(),
                radii.len(),
                ids.len()
            ),
            (rows, rows, rows, rows, rows)
        );
        *rows_per_entity
            .entry(chunk.entity_path().clone())
            .or_insert(0) += rows;
        for row in 0..rows {
            assert_eq!(positions[row].len(), ids[row].len());
            assert_eq!(radii[row].len(), ids[row].len());
            for ((&id, &p), &r) in ids[row].iter().zip(positions[row]).zip(radii[row]) {
                let old = out.insert((steps[row], id), (times[row], p, r));
                assert!(old.is_none(), "particle {id} twice at step {}", steps[row]);
            }
        }
    }
    (out, rows_per_entity)
}

fn expected_particles(frames: &[Frame]) -> Particles {
    let mut out = Particles::new();
    for frame in frames {
        let ns = std::time::Duration::from_secs_f64(frame.time).as_nanos() as i64;
        for i in 0..frame.len() {
            let p = frame.position[i];
            out.insert(
                (frame.step as i64, frame.id[i]),
                (
                    ns,
                    [p[0] as f32, p[1] as f32, p[2] as f32],
                    (0.5 * frame.diameter[i]) as f32,
                ),
            );
        }
    }
    out
}

/// The viewer layout: a viewport, panels, a 3D view, one plot per stats family of the first
/// frame (`count`, `energy`, `height max`; `undefined` comes later and is only in the
/// viewer's tree), the warnings and the scene, with visualizer overrides for the particle
/// groups and the per-group series.
fn check_blueprint(decoded: &Decoded) {
    assert!(decoded.blueprint_activated, "blueprint activated");
    let bp = &decoded.blueprint_entities;
    for expected in [
        "/viewport",
        "/time_panel",
        "/blueprint_panel",
        "/selection_panel",
    ] {
        assert!(bp.contains(expected), "{expected} missing from {bp:?}");
    }
    let views = bp
        .iter()
        .filter(|p| p.starts_with("/view/") && p.matches('/').count() == 2)
        .count();
    assert_eq!(views, 1 + 3 + 2, "3D, three plots, warnings, scene: {bp:?}");
    let overridden = |entity: &str| {
        bp.iter()
            .any(|p| p.contains("/ViewContents/overrides/") && p.contains(entity))
    };
    assert!(overridden("/particles/large\\ grains/visualizers"));
    assert!(overridden("/stats/count/small/visualizers"));
}

/// Checks everything the recording of `frames()` must hold.
fn check_recording(path: &Path) {
    let decoded = decode(path);
    assert_eq!(decoded.store_infos, 1);
    assert!(
        decoded.manifests >= 1,
        "the footer (RRD manifest) is present"
    );
    assert!(!decoded.chunks.is_empty());

    check_blueprint(&decoded);

    let (got, rows) = particles(&decoded);
    assert_eq!(got, expected_particles(&frames()));
    // One row per frame and group (empty groups are logged as empty point sets).
    for group in &meta().groups {
        assert_eq!(rows.get(&entity("particles", &group.name)), Some(&N_FRAMES));
    }

    let paths: BTreeSet<String> = decoded
        .chunks
        .iter()
        .map(|c| c.entity_path().to_string())
        .collect();
    for expected in [
        "/geometry/vessel",
        "/geometry/nozzle",
        "/warnings",
        "/scene",
        "/stats/count/small",
        "/stats/energy/kinetic",
        "/stats/height max",
        "/stats/undefined",
        "/__properties",
        "/__properties/scg",
    ] {
        let found = paths
            .iter()
            .any(|p| p == expected || p == &expected.replace(' ', "\\ "));
        assert!(found, "entity {expected} missing from {paths:?}");
    }
    for path in [
        "/geometry/vessel",
        "/warnings",
        "/scene",
        "/__properties/scg",
    ] {
        assert!(
            decoded
                .chunks
                .iter()
                .filter(|c| c.entity_path().to_string() == path)
                .all(Chunk::is_static),
            "{path} is static"
        );
    }
    let stat_rows: usize = decoded
        .chunks
        .iter()
        .filter(|c| c.entity_path().to_string() == "/stats/count/small")
        .map(Chunk::num_rows)
        .sum();
    assert_eq!(stat_rows, N_FRAMES);
}

#[test]
fn live_recording_decodes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.rrd");
    let mut sink = RrdSink::create(&path, &meta()).expect("create");
    assert!(partial_path(&path).exists());
    for frame in &frames() {
        sink.write_frame(frame).expect("write_frame");
    }
    sink.finish().expect("finish");
    assert!(path.exists());
    assert!(!partial_path(&path).exists());
    check_recording(&path);

    assert!(sink.finish().is_ok(), "finish is idempotent");
    assert!(matches!(
        sink.push(&frames()[0]),
        Err(RecordError::Finished)
    ));
}

#[test]
fn replay_from_mcap_has_the_same_layout() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mcap = dir.path().join("run.mcap");
    let mut sink = McapSink::create(&mcap, &meta()).expect("create");
    for frame in &frames() {
        sink.write_frame(frame).expect("write_frame");
    }
    sink.finish().expect("finish");

    let rec = read_mcap(&mcap).expect("read");
    let rrd = dir.path().join("replay.rrd");
    assert_eq!(write_rrd(&rec, &rrd).expect("write_rrd"), N_FRAMES);
    check_recording(&rrd);
}

#[test]
fn dropped_sink_leaves_a_readable_partial_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.rrd");
    let mut sink = RrdSink::create(&path, &meta()).expect("create");
    for frame in &frames()[..2] {
        sink.write_frame(frame).expect("write_frame");
    }
    drop(sink);
    assert!(
        !path.exists(),
        "an unfinished recording keeps its .partial name"
    );
    let decoded = decode(&partial_path(&path));
    assert!(decoded.manifests >= 1);
    let (got, _) = particles(&decoded);
    assert_eq!(got, expected_particles(&frames()[..2]));
}

#[test]
fn invalid_frames_are_rejected() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.rrd");
    let mut sink = RrdSink::create(&path, &meta()).expect("create");
    let mut bad = frames().remove(0);
    bad.group[0] = 7;
    assert!(sink.write_frame(&bad).is_err());
    bad = frames().remove(0);
    bad.position.pop();
    assert!(sink.write_frame(&bad).is_err());
    sink.finish().expect("finish");
}

#[test]
fn unwritable_path_is_an_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("no such dir").join("run.rrd");
    assert!(matches!(
        RrdSink::create(&path, &meta()),
        Err(RecordError::Io { .. })
    ));
    assert!(matches!(
        McapSink::create(&path.with_extension("mcap"), &meta()),
        Err(RecordError::Io { .. })
    ));
}

/// Writes `interop.rrd`, `interop.mcap` and `replay.rrd` (rebuilt from the MCAP file) into
/// `$SCG_INTEROP_DIR` for `tests/interop/check.py`, or into a temporary directory.
#[test]
fn write_interop_files() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = std::env::var_os("SCG_INTEROP_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| tmp.path().to_path_buf());
    std::fs::create_dir_all(&dir).expect("create SCG_INTEROP_DIR");
    let (rrd, mcap) = (dir.join("interop.rrd"), dir.join("interop.mcap"));
    let mut rrd_sink = RrdSink::create(&rrd, &meta()).expect("create rrd");
    let mut mcap_sink = McapSink::create(&mcap, &meta()).expect("create mcap");
    for frame in &frames() {
        rrd_sink.write_frame(frame).expect("rrd frame");
        mcap_sink.write_frame(frame).expect("mcap frame");
    }
    rrd_sink.finish().expect("finish rrd");
    mcap_sink.finish().expect("finish mcap");
    let rec = read_mcap(&mcap).expect("read");
    write_rrd(&rec, &dir.join("replay.rrd")).expect("write_rrd");
    check_recording(&rrd);
}

/// Frames with the dispersion's |u′| (`Frame::fluctuation`): the `.rrd` carries it as the
/// `fluctuation` component of each group's points, in the positions' order, and an MCAP
/// written and replayed to `.rrd` the same; frames without it carry no such component.
#[test]
fn fluctuation_is_a_component_when_frames_carry_it() {
    let with: Vec<Frame> = frames()
        .into_iter()
        .map(|mut f| {
            f.fluctuation = f.id.iter().map(|&id| 1e-3 * id as f64 + 0.25).collect();
            f
        })
        .collect();
    let dir = tempfile::tempdir().expect("tempdir");
    let fluct_of = |path: &Path| {
        let decoded = decode(path);
        let mut seen = BTreeMap::new();
        for chunk in &decoded.chunks {
            if !chunk.entity_path().to_string().starts_with("/particles") {
                continue;
            }
            let ids: Vec<&[u32]> = chunk
                .iter_slices::<u32>(COMPONENT_PARTICLE_ID.into())
                .collect();
            let u: Vec<&[f32]> = chunk
                .iter_slices::<f32>(COMPONENT_FLUCTUATION.into())
                .collect();
            for (ids, u) in ids.iter().zip(&u) {
                assert_eq!(ids.len(), u.len());
                for (id, u) in ids.iter().zip(*u) {
                    seen.insert(*id, *u);
                }
            }
        }
        seen
    };
    let live = dir.path().join("live.rrd");
    let mut sink = RrdSink::create(&live, &meta()).expect("create");
    let mcap = dir.path().join("run.mcap");
    let mut m = McapSink::create(&mcap, &meta()).expect("create");
    for frame in &with {
        sink.write_frame(frame).expect("write_frame");
        m.write_frame(frame).expect("write_frame");
    }
    sink.finish().expect("finish");
    m.finish().expect("finish");
    let rec = read_mcap(&mcap).expect("read");
    // (the frames' stats hold a NaN: compare the fluctuation and ids, bit for bit)
    assert_eq!(rec.frames.len(), with.len());
    for (a, b) in rec.frames.iter().zip(&with) {
        assert_eq!(a.id, b.id);
        let bits = |f: &Frame| {
            f.fluctuation
                .iter()
                .map(|u| u.to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(a), bits(b), "MCAP round trip of frame {}", a.step);
    }
    let replay = dir.path().join("replay.rrd");
    write_rrd(&rec, &replay).expect("write_rrd");
    for path in [&live, &replay] {
        let seen = fluct_of(path);
        assert!(seen.len() > 10);
        for (id, u) in &seen {
            assert_eq!(*u, (1e-3 * *id as f64 + 0.25) as f32, "particle {id}");
        }
    }
    let plain = dir.path().join("plain.rrd");
    let mut sink = RrdSink::create(&plain, &meta()).expect("create");
    for frame in &frames() {
        sink.write_frame(frame).expect("write_frame");
    }
    sink.finish().expect("finish");
    assert!(fluct_of(&plain).is_empty());
    // A frame whose fluctuation does not match its particles is refused.
    let mut bad = with[1].clone();
    bad.fluctuation.pop();
    let mut sink = RrdSink::create(&dir.path().join("bad.rrd"), &meta()).expect("create");
    assert!(matches!(
        sink.push(&bad),
        Err(RecordError::InvalidFrame { .. })
    ));
}
