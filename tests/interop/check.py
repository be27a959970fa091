#!/usr/bin/env python3
"""Check that an scg recording pair opens in the reference tools.

Usage:
    .venv-interop/bin/python tests/interop/check.py REC.rrd REC.mcap

REC.rrd and REC.mcap must hold the same run (e.g. both written by one `scg run`, or the
.rrd rebuilt from the .mcap). Checks, each printed as PASS or FAIL:

1. `rerun rrd verify REC.rrd` reports "1 file verified without error";
2. the particle positions read with `rerun.experimental.RrdReader` equal the MCAP's positions
   (same steps, same particle ids) to float32 precision;
3. the MCAP file reads with `mcap.reader.make_reader(..., validate_crcs=True)`, every
   `/particles` message decodes as `foxglove.PointCloud`, and its summary, metadata and
   attachment are present;
4. `rerun mcap convert REC.mcap -o OUT.rrd` succeeds and `rerun rrd verify OUT.rrd` passes;
5. the `.rrd` carries a blueprint (`RrdReader.blueprints()`): a viewport, a 3D view,
   time-series views on `/stats/...`, the time panel on `sim_time`; and every particle
   chunk has the `speed` component;
6. a mesh flow's boundary patches: the MCAP's `/flow/patches` message decodes as
   `foxglove.SceneUpdate` (one entity per patch, a `role`, one indexed triangle list) and
   the `.rrd` holds one static `Mesh3D` per patch at `/flow/patches/<name>` with the same
   triangles and (as float32) vertices; passes trivially when neither has patches;
7. with `--vtk DIR` (the output of `scg replay REC.mcap --vtk DIR`): meshio reads the
   `.pvd`'s every `.vtu` frame, and its points, velocities, diameters and ids equal the
   MCAP's bit for bit; the geometry file reads as line cells.

Exits with status 1 if any check fails. Set up the environment with tests/interop/setup.sh.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import traceback
from pathlib import Path

import numpy as np

VERIFIED = "1 file verified without error"
POINT_FIELDS = ["x", "y", "z", "vx", "vy", "vz", "diameter", "density", "id", "group"]
POINT_STRIDE = 72
# a run with turbulent dispersion adds |u'| (FLOAT64) after `group`
POINT_LAYOUTS = [(POINT_FIELDS, POINT_STRIDE), (POINT_FIELDS + ["fluctuation"], POINT_STRIDE + 8)]
FLOAT64, UINT32 = 8, 5  # foxglove.PackedElementField.NumericType


def rerun_cli() -> str:
    """The `rerun` executable of this Python environment (or the one on PATH)."""
    beside = Path(sys.executable).parent / "rerun"
    if beside.exists():
        return str(beside)
    found = shutil.which("rerun")
    if found is None:
        raise RuntimeError("no `rerun` executable (install rerun-sdk, see tests/interop/setup.sh)")
    return found


def run(args: list[str]) -> str:
    """Runs a command and returns its stdout+stderr; raises if it exits non-zero."""
    proc = subprocess.run(args, capture_output=True, text=True, check=False)
    output = proc.stdout + proc.stderr
    if proc.returncode != 0:
        raise RuntimeError(f"`{' '.join(args)}` exited with {proc.returncode}:\n{output}")
    return output


def rrd_verify(path: Path) -> str:
    """`rerun rrd verify PATH`; its exit status is 0 even on garbage, so read what it says."""
    output = run([rerun_cli(), "rrd", "verify", str(path)])
    if VERIFIED not in output:
        raise RuntimeError(f"`rerun rrd verify {path}` did not report {VERIFIED!r}:\n{output}")
    return output.strip().splitlines()[-1]


def point_dtype(cloud) -> np.dtype:
    """A numpy dtype for the packed points of a foxglove PointCloud."""
    names, formats, offsets = [], [], []
    for field in cloud.fields:
        if field.type == FLOAT64:
            fmt = "<f8"
        elif field.type == UINT32:
            fmt = "<u4"
        else:
            raise ValueError(f"unexpected type {field.type} of point field {field.name!r}")
        names.append(field.name)
        formats.append(fmt)
        offsets.append(field.offset)
    return np.dtype({"names": names, "formats": formats, "offsets": offsets,
                     "itemsize": cloud.point_stride})


def read_mcap(path: Path, validate_crcs: bool) -> dict:
    """Reads an scg MCAP file: frames (by sequence), metadata, attachment, summary."""
    from foxglove_schemas_protobuf.PointCloud_pb2 import PointCloud
    from mcap.reader import make_reader

    from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate

    clouds: dict[int, np.ndarray] = {}
    patches: list = []
    stats: dict[int, dict] = {}
    log_times: dict[int, int] = {}
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=validate_crcs)
        summary = reader.get_summary()
        metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        attachments = {a.name: bytes(a.data) for a in reader.iter_attachments()}
        for schema, channel, message in reader.iter_messages():
            if channel.topic == "/particles":
                if schema.name != "foxglove.PointCloud" or channel.message_encoding != "protobuf":
                    raise ValueError(f"/particles: schema {schema.name}, "
                                     f"encoding {channel.message_encoding}")
                cloud = PointCloud()
                cloud.ParseFromString(message.data)
                names = [field.name for field in cloud.fields]
                if (names, cloud.point_stride) not in POINT_LAYOUTS:
                    raise ValueError(f"unexpected point layout {names}, stride {cloud.point_stride}")
                if cloud.frame_id != "world" or cloud.pose.orientation.w != 1.0:
                    raise ValueError("unexpected frame_id or pose")
                if len(cloud.data) % cloud.point_stride:
                    raise ValueError("point data is not a whole number of points")
                stamp = cloud.timestamp.seconds * 1_000_000_000 + cloud.timestamp.nanos
                if stamp != message.log_time:
                    raise ValueError(f"timestamp {stamp} != log_time {message.log_time}")
                clouds[message.sequence] = np.frombuffer(cloud.data, dtype=point_dtype(cloud))
                log_times[message.sequence] = message.log_time
            elif channel.topic == "/stats":
                stats[message.sequence] = json.loads(message.data)
            elif channel.topic == "/flow/patches":
                if schema.name != "foxglove.SceneUpdate" or channel.message_encoding != "protobuf":
                    raise ValueError(f"/flow/patches: schema {schema.name}, "
                                     f"encoding {channel.message_encoding}")
                update = SceneUpdate()
                update.ParseFromString(message.data)
                patches.append(update)
    if clouds.keys() != stats.keys():
        raise ValueError("/particles and /stats messages do not pair up")
    return {"clouds": clouds, "stats": stats, "log_times": log_times, "summary": summary,
            "metadata": metadata, "attachments": attachments, "patches": patches}


def mcap_positions(mcap: dict) -> dict[tuple[int, int], np.ndarray]:
    """(step, particle id) -> position (float64) from a read MCAP file."""
    out = {}
    for sequence, points in mcap["clouds"].items():
        step = int(mcap["stats"][sequence]["step"])
        xyz = np.stack([points["x"], points["y"], points["z"]], axis=1)
        for pid, p in zip(points["id"].tolist(), xyz):
            out[(step, pid)] = p
    return out


def rrd_positions(path: Path) -> dict[tuple[int, int], np.ndarray]:
    """(step, particle id) -> position (float32) from the `/particles/*` entities."""
    from rerun.experimental import RrdReader

    out = {}
    for chunk in RrdReader(path).stream():
        if not chunk.entity_path.startswith("/particles/") or chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        steps = batch.column("step").to_numpy()
        positions = batch.column("Points3D:positions")
        ids = batch.column("particle_id")
        for row in range(batch.num_rows):
            row_ids = ids[row].values.to_numpy(zero_copy_only=False)
            row_pos = np.asarray(positions[row].values.flatten(), dtype=np.float32).reshape(-1, 3)
            if len(row_ids) != len(row_pos):
                raise ValueError(f"{chunk.entity_path}: {len(row_ids)} ids, {len(row_pos)} points")
            for pid, p in zip(row_ids.tolist(), row_pos):
                key = (int(steps[row]), pid)
                if key in out:
                    raise ValueError(f"particle {pid} twice at step {key[0]}")
                out[key] = p
    return out


def check_verify(rrd: Path, mcap: Path) -> str:
    return rrd_verify(rrd)


def check_positions(rrd: Path, mcap: Path) -> str:
    want = mcap_positions(read_mcap(mcap, validate_crcs=False))
    got = rrd_positions(rrd)
    if got.keys() != want.keys():
        missing = sorted(want.keys() - got.keys())[:5]
        extra = sorted(got.keys() - want.keys())[:5]
        raise ValueError(f"(step, id) sets differ: missing from rrd {missing}, extra {extra}")
    keys = sorted(want)
    a = np.array([got[k] for k in keys], dtype=np.float32)
    with np.errstate(over="ignore"):  # |x| > 3.4e38 is inf in float32, in Rerun too
        b = np.array([want[k] for k in keys], dtype=np.float64).astype(np.float32)
    if not np.array_equal(a, b):
        bad = np.argwhere(a != b)[:5]
        raise ValueError(f"positions differ, e.g. {[(keys[i], a[i], b[i]) for i, _ in bad]}")
    steps = len({k[0] for k in keys})
    return f"{len(keys)} positions over {steps} frames match"


def check_mcap(rrd: Path, mcap: Path) -> str:
    data = read_mcap(mcap, validate_crcs=True)
    summary = data["summary"]
    if summary is None or summary.statistics is None or not summary.chunk_indexes:
        raise ValueError("no summary, statistics or chunk indexes")
    meta = data["metadata"].get("scg")
    if meta is None:
        raise ValueError("no `scg` metadata record")
    groups = json.loads(meta["groups"])
    for key in ("scg_version", "case", "seed", "dt", "record_every", "warnings"):
        if key not in meta:
            raise ValueError(f"metadata key {key!r} missing")
    if "scene.toml" not in data["attachments"]:
        raise ValueError("no scene.toml attachment")
    for points in data["clouds"].values():
        if len(points) and points["group"].max() >= len(groups):
            raise ValueError("group index out of range")
    n_points = sum(len(p) for p in data["clouds"].values())
    return (f"{len(data['clouds'])} point clouds ({n_points} points), "
            f"{summary.statistics.message_count} messages in {len(summary.chunk_indexes)} chunks, "
            f"{len(groups)} groups, case {meta['case']!r}")


def check_convert(rrd: Path, mcap: Path) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "converted.rrd"
        run([rerun_cli(), "mcap", "convert", str(mcap), "-o", str(out)])
        verdict = rrd_verify(out)
        from rerun.experimental import RrdReader

        paths = {chunk.entity_path for chunk in RrdReader(out).stream()}
        if not any("particles" in p for p in paths):
            raise ValueError(f"no /particles entity in the converted recording: {sorted(paths)}")
        return f"{verdict}; {len(paths)} entities"


def check_blueprint(rrd: Path, mcap: Path) -> str:
    from rerun.experimental import RrdReader

    reader = RrdReader(rrd)
    blueprints = reader.blueprints()
    if len(blueprints) != 1:
        raise ValueError(f"expected one blueprint store, found {blueprints}")
    views, entities, timeline = [], set(), None
    for chunk in reader.stream(store=blueprints[0]):
        entities.add(chunk.entity_path)
        batch = chunk.to_record_batch()
        names = batch.schema.names
        if "ViewBlueprint:class_identifier" in names:
            for cls, origin in zip(batch.column("ViewBlueprint:class_identifier").to_pylist(),
                                   batch.column("ViewBlueprint:space_origin").to_pylist()):
                views.append((cls[0], origin[0] if origin else None))
        if "TimePanelBlueprint:timeline" in names:
            timeline = batch.column("TimePanelBlueprint:timeline").to_pylist()[-1][0]
    if "/viewport" not in entities:
        raise ValueError(f"no /viewport in the blueprint: {sorted(entities)[:10]}")
    classes = [cls for cls, _ in views]
    if classes.count("3D") != 1:
        raise ValueError(f"expected one 3D view, found {views}")
    plots = [origin for cls, origin in views if cls == "TimeSeries"]
    if not plots or not all(o.startswith("/stats/") for o in plots):
        raise ValueError(f"time-series views missing or not on /stats: {views}")
    if timeline != "sim_time":
        raise ValueError(f"time panel on {timeline!r}, not sim_time")
    speed_chunks = 0
    for chunk in reader.stream():
        if chunk.entity_path.startswith("/particles/") and not chunk.is_static:
            if "speed" not in chunk.to_record_batch().schema.names:
                raise ValueError(f"{chunk.entity_path}: no speed component")
            speed_chunks += 1
    return (f"{len(views)} views ({', '.join(sorted(set(classes)))}), plots {plots}, "
            f"time panel on {timeline}; speed in {speed_chunks} particle chunks")


def check_patches(rrd: Path, mcap: Path) -> str:
    from rerun.experimental import RrdReader

    updates = read_mcap(mcap, validate_crcs=False)["patches"]
    if len(updates) > 1:
        raise ValueError(f"{len(updates)} /flow/patches messages, expected at most one")
    want = {}
    for entity in (updates[0].entities if updates else []):
        roles = [kv.value for kv in entity.metadata if kv.key == "role"]
        if entity.frame_id != "world" or len(entity.triangles) != 1 or len(roles) != 1:
            raise ValueError(f"patch {entity.id!r}: frame {entity.frame_id!r}, "
                             f"{len(entity.triangles)} triangle lists, roles {roles}")
        tri = entity.triangles[0]
        points = np.array([[p.x, p.y, p.z] for p in tri.points], dtype=np.float64)
        indices = np.array(tri.indices, dtype=np.uint32)
        if len(indices) % 3 or (len(indices) and indices.max() >= len(points)):
            raise ValueError(f"patch {entity.id!r}: bad indices")
        want[entity.id] = (roles[0], points.astype(np.float32), indices.reshape(-1, 3))
    got = {}
    for chunk in RrdReader(rrd).stream():
        if not chunk.entity_path.startswith("/flow/patches/"):
            continue
        if not chunk.is_static:
            raise ValueError(f"{chunk.entity_path} is not static")
        batch = chunk.to_record_batch()
        pos = batch.column("Mesh3D:vertex_positions")[0].values.flatten()
        idx = batch.column("Mesh3D:triangle_indices")[0].values.flatten()
        got[chunk.entity_path.removeprefix("/flow/patches/")] = (
            np.asarray(pos, dtype=np.float32).reshape(-1, 3),
            np.asarray(idx, dtype=np.uint32).reshape(-1, 3))
    if got.keys() != want.keys():
        raise ValueError(f"patches differ: rrd {sorted(got)}, mcap {sorted(want)}")
    for name, (role, points, tris) in want.items():
        if not (np.array_equal(got[name][0], points) and np.array_equal(got[name][1], tris)):
            raise ValueError(f"patch {name!r}: rrd mesh differs from the MCAP's")
    if not want:
        return "no mesh flow: no patches in either file"
    return ", ".join(f"{n} ({want[n][0]}, {len(want[n][2])} triangles)" for n in sorted(want))


def check_erosion(rrd: Path, mcap_path: Path, vtk: Path | None = None) -> str:
    """The wear map of a run with [erosion]: the MCAP's `erosion.json` attachment, the
    rrd's `/erosion/<patch>` Mesh3D (three vertices per triangle, the face's depth rate
    per vertex, float64 exactly) and, with a VTK folder, `*_erosion.vtu` read by meshio
    (the same rate per triangle)."""
    from rerun.experimental import RrdReader

    raw = read_mcap(mcap_path, validate_crcs=False)["attachments"].get("erosion.json")
    meshes = {}
    for chunk in RrdReader(rrd).stream():
        if chunk.entity_path.startswith("/erosion/") and chunk.entity_path != "/erosion/deepest":
            batch = chunk.to_record_batch()
            pos = batch.column("Mesh3D:vertex_positions")[0].values.flatten()
            rate = batch.column("depth_rate")[0].values.to_numpy(zero_copy_only=False)
            meshes[chunk.entity_path.removeprefix("/erosion/")] = (len(pos) // 3, rate)
    if raw is None:
        if meshes:
            raise ValueError(f"rrd has erosion meshes {sorted(meshes)} but the MCAP no erosion.json")
        return "no [erosion]: no wear map in either file"
    wear = json.loads(raw)
    names = [p["name"] for p in wear["patches"]]
    if sorted(meshes) != sorted(names):
        raise ValueError(f"wear patches: rrd {sorted(meshes)}, mcap {names}")
    parts = []
    for p in wear["patches"]:
        per_vertex = np.repeat(np.asarray(p["depth_rate"])[np.asarray(p["triangle_face"], dtype=int)], 3)
        n, rate = meshes[p["name"]]
        if n != 3 * len(p["triangles"]) or not np.array_equal(rate, per_vertex):
            raise ValueError(f"wear of {p['name']!r}: rrd mesh differs from the MCAP's map")
        parts.append(f"{p['name']} ({len(p['faces'])} faces, max {max(p['depth_rate']):.3e} m/s)")
    if vtk is not None:
        import meshio

        files = list(vtk.glob("*_erosion.vtu"))
        if len(files) != 1:
            raise ValueError(f"expected one *_erosion.vtu in {vtk}, found {len(files)}")
        m = meshio.read(files[0])
        got = np.concatenate(m.cell_data["depth_rate_m_per_s"])
        want = np.concatenate([np.asarray(p["depth_rate"])[np.asarray(p["triangle_face"], dtype=int)]
                               for p in wear["patches"]])
        if not np.array_equal(got, want):
            raise ValueError(f"{files[0].name}: depth rates differ from the MCAP's map")
        parts.append(f"meshio reads {files[0].name} ({len(got)} triangles)")
    return ", ".join(parts)


def check_vtk(vtk: Path, mcap_path: Path) -> str:
    import xml.etree.ElementTree as ET

    import meshio

    mcap = read_mcap(mcap_path, validate_crcs=False)
    by_step = {}
    for sequence, points in mcap["clouds"].items():
        by_step[int(mcap["stats"][sequence]["step"])] = points
    pvds = list(vtk.glob("*.pvd"))
    if len(pvds) != 1:
        raise ValueError(f"expected one .pvd in {vtk}, found {len(pvds)}")
    files = [d.get("file") for d in ET.parse(pvds[0]).getroot().iter("DataSet")]
    if len(files) != len(by_step):
        raise ValueError(f"{len(files)} frames in the .pvd, {len(by_step)} in the MCAP")
    n = 0
    for name in files:
        step = int(name.rsplit("_", 1)[1].split(".")[0])
        points = by_step[step]
        if len(points) == 0:
            # meshio reads no grid without cells (vtk.rs): an empty frame is checked as XML
            piece = ET.parse(vtk / name).getroot().find("UnstructuredGrid/Piece")
            if piece is None or piece.get("NumberOfPoints") != "0":
                raise ValueError(f"{name}: the MCAP's frame is empty, the file is not")
            continue
        mesh = meshio.read(vtk / name)
        order = np.argsort(mesh.point_data["id"], kind="stable")
        ids = np.asarray(mesh.point_data["id"])[order]
        if not np.array_equal(ids, points["id"]):
            raise ValueError(f"{name}: ids differ from the MCAP's")
        xyz = np.stack([points["x"], points["y"], points["z"]], axis=1)
        vel = np.stack([points["vx"], points["vy"], points["vz"]], axis=1)
        for label, got, want in [("points", mesh.points[order], xyz),
                                 ("velocity", mesh.point_data["velocity"][order], vel),
                                 ("diameter", mesh.point_data["diameter"][order],
                                  points["diameter"])]:
            if not np.array_equal(np.asarray(got, dtype=np.float64).view(np.uint64),
                                  np.asarray(want, dtype=np.float64).view(np.uint64)):
                raise ValueError(f"{name}: {label} differ from the MCAP's")
        if mesh.cells[0].type != "vertex":
            raise ValueError(f"{name}: cells are {mesh.cells[0].type}, not vertex")
        n += len(ids)
    geometry = list(vtk.glob("*_geometry.vtu"))
    lines = sum(len(c.data) for g in geometry for c in meshio.read(g).cells if c.type == "line")
    return (f"meshio {meshio.__version__}: {len(files)} frames, {n} points bit-identical to the "
            f"MCAP; geometry {lines} line cells")


CHECKS = [
    ("rerun rrd verify", check_verify),
    ("positions rrd == mcap", check_positions),
    ("mcap reader + foxglove PointCloud", check_mcap),
    ("rerun mcap convert + verify", check_convert),
    ("blueprint in the rrd", check_blueprint),
    ("flow patches rrd Mesh3D == mcap SceneUpdate", check_patches),
]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("rrd", type=Path, help="Rerun recording (.rrd)")
    parser.add_argument("mcap", type=Path, help="MCAP recording of the same run")
    parser.add_argument("--vtk", type=Path, help="VTK folder written by `scg replay --vtk`")
    args = parser.parse_args()

    checks = list(CHECKS)
    if args.vtk is not None:
        vtk = args.vtk
        checks.append(("meshio reads the VTK export", lambda _rrd, mcap: check_vtk(vtk, mcap)))
    checks.append(("wear map rrd Mesh3D == mcap erosion.json",
                   lambda rrd, mcap: check_erosion(rrd, mcap, args.vtk)))
    failures = 0
    for number, (name, check) in enumerate(checks, start=1):
        try:
            detail = check(args.rrd, args.mcap)
            print(f"PASS {number}. {name}: {detail}")
        except Exception as err:  # noqa: BLE001 - report every failure and go on
            failures += 1
            print(f"FAIL {number}. {name}: {err}")
            traceback.print_exc(limit=3, file=sys.stderr)
    print(f"{len(checks) - failures} passed, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
