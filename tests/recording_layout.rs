//! A short real scene recorded to .rrd and .mcap, decoded with Rerun's own decoder and the
//! mcap crate's reader: frame count, particle count and values equal the in-memory state.

mod common;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufReader;

use rerun::external::re_log_encoding::DecoderApp;
use rerun::log::{Chunk, LogMsg};
use rerun::{Points3D, TimelineName};
use scg::core::frame::{Frame, MemorySink};
use scg::record::layout::{COMPONENT_PARTICLE_ID, TIMELINE_STEP};
use scg::record::{Background, McapSink, RrdSink, read_mcap};

#[test]
fn vortex_recordings_equal_the_in_memory_frames() {
    let scene = common::case("vortex", &["duration=0.01", "record_every=250"]);
    let dir = tempfile::tempdir().unwrap();
    let (rrd, mcap) = (dir.path().join("v.rrd"), dir.path().join("v.mcap"));
    let meta = scene.run_meta(vec!["a warning".into()]);
    let mut sim = scene.build(true);
    let mem = MemorySink::default();
    let frames = mem.frames.clone();
    sim.add_recorder(Box::new(mem));
    sim.add_recorder(Box::new(Background::spawn(vec![
        Box::new(RrdSink::create(&rrd, &meta).unwrap()),
        Box::new(McapSink::create(&mcap, &meta).unwrap()),
    ])));
    sim.record_now().unwrap();
    sim.run(scene.steps(), |_| true).unwrap();
    sim.finish_recorders().unwrap();
    let want: Vec<Frame> = frames.lock().unwrap().clone();
    assert_eq!(want.len(), 21);
    assert!(want.iter().all(|f| f.len() == 7));

    // MCAP through scg's reader: every value bit for bit.
    let rec = read_mcap(&mcap).unwrap();
    assert!(rec.complete);
    assert_eq!(rec.frames, want);
    // MCAP through the mcap crate: one /particles message per frame, 72-byte points.
    let bytes = std::fs::read(&mcap).unwrap();
    let mut per_topic = BTreeMap::<String, usize>::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        *per_topic.entry(m.channel.topic.clone()).or_default() += 1;
    }
    assert_eq!(per_topic.get("/particles"), Some(&want.len()));
    assert_eq!(per_topic.get("/stats"), Some(&want.len()));

    // RRD through Rerun's decoder: (step, id) → position, as float32.
    let mut got = BTreeMap::<(i64, u32), [f32; 3]>::new();
    let mut messages = DecoderApp::decode_eager(BufReader::new(File::open(&rrd).unwrap())).unwrap();
    for msg in messages.by_ref() {
        if let LogMsg::ArrowMsg(_, arrow) = msg.unwrap() {
            let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
            if !chunk.entity_path().to_string().starts_with("/particles/") {
                continue;
            }
            let steps =
                chunk.timelines()[&TimelineName::from_static_str(TIMELINE_STEP)].times_raw();
            let pos: Vec<&[[f32; 3]]> = chunk
                .iter_slices::<[f32; 3]>(Points3D::descriptor_positions().component)
                .collect();
            let ids: Vec<&[u32]> = chunk
                .iter_slices::<u32>(COMPONENT_PARTICLE_ID.into())
                .collect();
            for row in 0..chunk.num_rows() {
                for (id, p) in ids[row].iter().zip(pos[row]) {
                    assert!(got.insert((steps[row], *id), *p).is_none());
                }
            }
        }
    }
    assert!(
        !messages.rrd_manifests().unwrap().is_empty(),
        "footer written"
    );
    let mut expected = BTreeMap::new();
    for f in &want {
        for i in 0..f.len() {
            let p = f.position[i];
            expected.insert(
                (f.step as i64, f.id[i]),
                [p[0] as f32, p[1] as f32, p[2] as f32],
            );
        }
    }
    assert_eq!(got, expected);
}
