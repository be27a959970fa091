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

/// A mesh-flow run: every boundary patch is a static `Mesh3D` at `flow/patches/<name>` in
/// the `.rrd` (also when rebuilt from the MCAP, as `scg replay --rrd` does), and the
/// MCAP's `/flow/patches` `foxglove.SceneUpdate` carries the same triangles.
#[test]
fn mesh_flow_patches_are_recorded() {
    use foxglove::Decode;
    use glam::DVec3;
    use rerun::Mesh3D;
    use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};

    let dir = tempfile::tempdir().unwrap();
    // 4 × 3 × 2 hexahedra: inlet and outlet 6 quads each, walls 2·(12 + 8) = 40 quads.
    let mesh = BoxMesh::new(DVec3::ZERO, DVec3::new(0.04, 0.03, 0.02), [4, 3, 2])
        .shape(CellShape::Hex)
        .naming(PatchNaming::InletOutletWalls { axis: 0 })
        .build()
        .unwrap();
    let field = scg_mesh::CellField {
        cells: vec![DVec3::new(1.0, 0.0, 0.0); mesh.n_cells],
        patches: vec![None; mesh.patches.len()],
    };
    scg_mesh::foam::write_case(
        dir.path().join("case"),
        &mesh,
        Some(("U", &field)),
        scg_mesh::foam::Format::Ascii,
    )
    .unwrap();
    let text = "duration = 1e-3\ndt = 1e-4\nrecord_every = 5\n[flow]\nkind = \"openfoam\"\ncase = \"case\"\n[flow.patches]\nwalls = [\"walls\"]\noutlets = [\"outlet\"]\n[[groups]]\nname = \"p\"\ndiameter = 1e-4\ndensity = 1000.0\npositions = [[0.02, 0.015, 0.01]]\n";
    let path = dir.path().join("m.toml");
    std::fs::write(&path, text).unwrap();
    let scene = scg::scene::load(&path, &[]).unwrap();
    let meta = scene.run_meta(Vec::new());
    // Quads fanned from a corner: two triangles each.
    let want: BTreeMap<String, (String, usize)> = [
        ("inlet", "lost", 12),
        ("outlet", "outlet", 12),
        ("walls", "wall", 80),
    ]
    .into_iter()
    .map(|(n, r, t)| (n.to_string(), (r.to_string(), t)))
    .collect();
    let got: BTreeMap<String, (String, usize)> = meta
        .patches
        .iter()
        .map(|p| (p.name.clone(), (p.role.clone(), p.triangles.len())))
        .collect();
    assert_eq!(got, want);

    let (rrd, mcap) = (dir.path().join("m.rrd"), dir.path().join("m.mcap"));
    let mut sim = scene.build(true);
    sim.add_recorder(Box::new(RrdSink::create(&rrd, &meta).unwrap()));
    sim.add_recorder(Box::new(McapSink::create(&mcap, &meta).unwrap()));
    sim.record_now().unwrap();
    sim.run(scene.steps(), |_| true).unwrap();
    sim.finish_recorders().unwrap();

    // MCAP: one SceneUpdate on /flow/patches, one entity per patch, read back exactly.
    let bytes = std::fs::read(&mcap).unwrap();
    let mut updates = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic == "/flow/patches" {
            let schema = m.channel.schema.as_ref().unwrap();
            assert_eq!(schema.name, "foxglove.SceneUpdate");
            assert_eq!(m.channel.message_encoding, "protobuf");
            updates.push(foxglove::messages::SceneUpdate::decode(&m.data[..]).unwrap());
        }
    }
    assert_eq!(updates.len(), 1);
    let from_mcap: BTreeMap<String, (String, usize)> = updates[0]
        .entities
        .iter()
        .map(|e| {
            assert_eq!(e.frame_id, "world");
            assert_eq!(e.triangles.len(), 1);
            let role = e.metadata.iter().find(|kv| kv.key == "role").unwrap();
            (
                e.id.clone(),
                (role.value.clone(), e.triangles[0].indices.len() / 3),
            )
        })
        .collect();
    assert_eq!(from_mcap, want);
    let rec = read_mcap(&mcap).unwrap();
    assert_eq!(rec.meta.patches, meta.patches);

    // RRD (as written, and rebuilt from the MCAP): one static Mesh3D per patch.
    let rebuilt = dir.path().join("rebuilt.rrd");
    scg::record::write_rrd(&rec, &rebuilt).unwrap();
    for file in [&rrd, &rebuilt] {
        let mut meshes = BTreeMap::<String, (usize, usize)>::new();
        let messages = DecoderApp::decode_eager(BufReader::new(File::open(file).unwrap())).unwrap();
        for msg in messages {
            if let LogMsg::ArrowMsg(_, arrow) = msg.unwrap() {
                let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
                let path = chunk.entity_path().to_string();
                let Some(name) = path.strip_prefix("/flow/patches/") else {
                    continue;
                };
                assert!(chunk.is_static(), "{path}");
                let tris: usize = chunk
                    .iter_slices::<[u32; 3]>(Mesh3D::descriptor_triangle_indices().component)
                    .map(|s| s.len())
                    .sum();
                let verts: usize = chunk
                    .iter_slices::<[f32; 3]>(Mesh3D::descriptor_vertex_positions().component)
                    .map(|s| s.len())
                    .sum();
                assert!(meshes.insert(name.to_string(), (tris, verts)).is_none());
            }
        }
        let counts: BTreeMap<String, (usize, usize)> = meta
            .patches
            .iter()
            .map(|p| (p.name.clone(), (p.triangles.len(), p.vertices.len())))
            .collect();
        assert_eq!(meshes, counts, "{}", file.display());
    }
}

/// A run with `[erosion]` (the elbow, briefly): its recorders get the wear map once, at
/// the end. The MCAP carries it (read back exactly, also what `scg replay` rebuilds the
/// `.rrd` from); the `.rrd` has `erosion/<patch>` as a `Mesh3D` with one colour and one
/// `depth_rate` per vertex (three vertices per triangle, the face's rate) at the last
/// step, and `erosion/deepest`; the VTK folder `<case>_erosion.vtu` with the cell data.
#[test]
fn the_wear_map_is_recorded_at_the_end() {
    use rerun::Mesh3D;
    use scg::core::stages::erosion::ErosionLog;
    use scg::record::VtkSink;
    use scg::record::layout::COMPONENT_DEPTH_RATE;

    let scene = common::case("elbow", &["duration=0.02", "feed_scale=0.05"]);
    let dir = tempfile::tempdir().unwrap();
    let (rrd, mcap, vtk) = (
        dir.path().join("e.rrd"),
        dir.path().join("e.mcap"),
        dir.path().join("vtk"),
    );
    let meta = scene.run_meta(Vec::new());
    let mut sim = scene.build(true);
    let mem = MemorySink::default();
    let wear = mem.wear.clone();
    sim.add_recorder(Box::new(mem));
    sim.add_recorder(Box::new(Background::spawn(vec![
        Box::new(RrdSink::create(&rrd, &meta).unwrap()),
        Box::new(McapSink::create(&mcap, &meta).unwrap()),
        Box::new(VtkSink::create(&vtk, &meta).unwrap()),
    ])));
    sim.record_now().unwrap();
    sim.run(scene.steps(), |_| true).unwrap();
    let total = sim.world.resource::<ErosionLog>().total_volume();
    sim.finish_recorders().unwrap();
    let w = wear.lock().unwrap().clone().expect("the wear map");
    assert_eq!((w.model.as_str(), w.step), ("finnie", scene.steps()));
    assert_eq!(w.patches.len(), 1);
    let p = &w.patches[0];
    assert_eq!((p.name.as_str(), p.faces.len()), ("walls", 2688));
    assert_eq!(p.triangles.len(), 2 * 2688); // quads
    let sum: f64 = p.volume.iter().sum();
    assert!(
        total > 0.0 && (sum - total).abs() <= 1e-12 * total,
        "{sum} {total}"
    );
    let (_, _, rate) = w.deepest().unwrap();
    assert_eq!(rate, p.depth_rate.iter().cloned().fold(0.0, f64::max));

    // MCAP: the map read back bit for bit, and an .rrd rebuilt from it
    let rec = read_mcap(&mcap).unwrap();
    assert_eq!(rec.wear.as_ref(), Some(&w));
    let rebuilt = dir.path().join("r.rrd");
    scg::record::write_rrd(&rec, &rebuilt).unwrap();

    for file in [&rrd, &rebuilt] {
        let mut seen = BTreeMap::new();
        for msg in DecoderApp::decode_eager(BufReader::new(File::open(file).unwrap())).unwrap() {
            let LogMsg::ArrowMsg(_, arrow) = msg.unwrap() else {
                continue;
            };
            let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
            let path = chunk.entity_path().to_string();
            if !path.starts_with("/erosion/") {
                continue;
            }
            let steps =
                chunk.timelines()[&TimelineName::from_static_str(TIMELINE_STEP)].times_raw();
            assert!(steps.iter().all(|&s| s == w.step as i64), "{path}");
            if path == "/erosion/walls" {
                let pos: Vec<&[[f32; 3]]> = chunk
                    .iter_slices::<[f32; 3]>(Mesh3D::descriptor_vertex_positions().component)
                    .collect();
                let rates: Vec<&[f64]> = chunk
                    .iter_slices::<f64>(COMPONENT_DEPTH_RATE.into())
                    .collect();
                assert_eq!(pos[0].len(), 3 * p.triangles.len());
                let want: Vec<f64> = p
                    .triangle_face
                    .iter()
                    .flat_map(|&f| [p.depth_rate[f as usize]; 3])
                    .collect();
                assert_eq!(rates[0], &want[..]);
            }
            seen.insert(path, chunk.num_rows());
        }
        assert_eq!(
            seen.keys().cloned().collect::<Vec<_>>(),
            ["/erosion/deepest", "/erosion/walls"],
            "{}",
            file.display()
        );
    }
    let text = std::fs::read_to_string(vtk.join(format!("{}_erosion.vtu", meta.case))).unwrap();
    assert!(text.contains(&format!("NumberOfCells=\"{}\"", p.triangles.len())));
    assert!(text.contains("Name=\"depth_rate_m_per_s\""));
}

/// A moving wall (`[[walls]] motion`): its outline is recorded at rest, with a
/// `Transform3D` per frame on `geometry/<wall>` that puts it where it is (translation
/// c(t) − R·c₀, R the rotation: here a lift of 0.1 m/s along z with a turn about z); the
/// MCAP keeps the motion in the outline, so a rebuilt .rrd moves it the same.
#[test]
fn a_moving_wall_is_drawn_where_it_is() {
    use rerun::Transform3D;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lift.toml");
    std::fs::write(
        &path,
        "duration = 0.01\ndt = 1.0e-4\nrecord_every = 25\n[[walls]]\nname = \"floor\"\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmodel = \"rebound\"\nmotion = { velocity = [0.0, 0.0, 0.1], rpm = 60.0, axis = [0.0, 0.0, 1.0], center = [0.01, 0.0, 0.0] }\n[[groups]]\nname = \"a\"\ndiameter = 1.0e-3\ndensity = 2500.0\npositions = [[0.0, 0.0, 0.01]]\n",
    )
    .unwrap();
    let scene = scg::scene::load(&path, &[]).unwrap();
    let meta = scene.run_meta(Vec::new());
    let motion = meta.outlines[0].motion;
    assert!(!motion.is_fixed());
    let (rrd, mcap) = (dir.path().join("l.rrd"), dir.path().join("l.mcap"));
    let vtk = dir.path().join("vtk");
    let mut sim = scene.build(true);
    sim.add_recorder(Box::new(RrdSink::create(&rrd, &meta).unwrap()));
    sim.add_recorder(Box::new(McapSink::create(&mcap, &meta).unwrap()));
    sim.add_recorder(Box::new(scg::record::VtkSink::create(&vtk, &meta).unwrap()));
    sim.record_now().unwrap();
    sim.run(scene.steps(), |_| true).unwrap();
    sim.finish_recorders().unwrap();
    let rec = read_mcap(&mcap).unwrap();
    assert_eq!(rec.meta.outlines[0].motion, motion);
    // MCAP: a SceneUpdate per frame on /geometry/walls posing the floor (Foxglove)
    {
        use foxglove::Decode;
        let bytes = std::fs::read(&mcap).unwrap();
        let mut poses = Vec::new();
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            if m.channel.topic == "/geometry/walls" {
                let u = foxglove::messages::SceneUpdate::decode(&m.data[..]).unwrap();
                let pos = u.entities[0].lines[0].pose.unwrap().position.unwrap();
                poses.push((m.log_time, pos.z));
            }
        }
        assert_eq!(poses.len(), 5);
        for (ns, z) in poses {
            assert!((z - 0.1 * ns as f64 * 1e-9).abs() < 1e-12, "{ns} {z}");
        }
    }
    // VTK: the floor per frame where it is (<case>_walls_<step>.vtu in <case>_walls.pvd)
    let pvd = std::fs::read_to_string(vtk.join(format!("{}_walls.pvd", meta.case))).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 5);
    assert!(!vtk.join(format!("{}_geometry.vtu", meta.case)).exists());
    let rebuilt = dir.path().join("r.rrd");
    scg::record::write_rrd(&rec, &rebuilt).unwrap();
    for file in [&rrd, &rebuilt] {
        let mut got = BTreeMap::new();
        for msg in DecoderApp::decode_eager(BufReader::new(File::open(file).unwrap())).unwrap() {
            let LogMsg::ArrowMsg(_, arrow) = msg.unwrap() else {
                continue;
            };
            let chunk = Chunk::from_arrow_msg(&arrow).unwrap();
            if chunk.entity_path().to_string() != "/geometry/floor" || chunk.is_static() {
                continue;
            }
            let steps =
                chunk.timelines()[&TimelineName::from_static_str(TIMELINE_STEP)].times_raw();
            let tr: Vec<&[[f32; 3]]> = chunk
                .iter_slices::<[f32; 3]>(Transform3D::descriptor_translation().component)
                .collect();
            for (s, t) in steps.iter().zip(tr) {
                got.insert(*s, t[0]);
            }
        }
        assert_eq!(got.len(), 5, "{}: one transform per frame", file.display());
        for (step, t) in got {
            let time = step as f64 * 1e-4;
            let p = motion.pose(time);
            let want = p.centre - p.rotation * p.rest_centre;
            let t = glam::DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64);
            assert!((t - want).length() < 1e-7, "step {step}: {t} vs {want}");
            assert!((t.z - 0.1 * time).abs() < 1e-7);
        }
    }
}
