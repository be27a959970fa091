"""The scg Python package against the command line it wraps.

Run from the repository root: ``pytest python/tests`` (the CLI comparisons use
``target/release/scg``, or ``SCG_BIN``).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import scg

ROOT = Path(__file__).resolve().parents[2]
CASES = Path("cases")  # relative, as a user at the repository's root writes them
SCG_BIN = Path(os.environ.get("SCG_BIN", ROOT / "target" / "release" / "scg"))
# The elbow as CI's interop check runs it: a mesh flow with dispersion, erosion and
# patch fates, 20 ms of it.
ELBOW_EDITS = {"duration": 0.02, "feed_scale": 0.05}
# Figures of the machine, not of the run.
TIMING = ("wall_s", "particle_steps_per_s", "threads")


def cli(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    if not SCG_BIN.exists():
        pytest.skip(f"{SCG_BIN} is not built (cargo build --release)")
    return subprocess.run([str(SCG_BIN), *args], cwd=cwd, capture_output=True, text=True)


@pytest.fixture(autouse=True)
def at_root(monkeypatch):
    monkeypatch.chdir(ROOT)


def without_timing(summary: dict) -> dict:
    return {k: v for k, v in summary.items() if k not in TIMING}


def test_a_bad_value_is_a_scene_error_with_file_key_and_line():
    with pytest.raises(scg.SceneError) as e:
        scg.Scene.load(CASES / "uniform.toml", set={"dt": -1})
    err = e.value
    assert err.file.endswith("uniform.toml")
    assert err.key == "dt"
    assert isinstance(err.line, int) and err.line > 0
    assert "must be a finite number > 0" in err.message
    # the CLI prints the same message
    out = cli("check", "cases/uniform.toml", "--set", "dt=-1")
    assert out.returncode == 2
    assert str(err) in out.stderr


def test_unknown_keys_and_missing_files_are_errors():
    with pytest.raises(scg.SceneError) as e:
        scg.Scene.from_toml('duration = 1.0\ndt = 1e-3\nbogus_key = 3\n')
    assert "bogus_key" in str(e.value)
    with pytest.raises(scg.SceneError) as e:
        scg.Scene.load(CASES / "no-such-scene.toml")
    assert "cannot read scene file" in e.value.message
    with pytest.raises(TypeError):
        scg.Scene.embedded().set("duration", object())


def test_a_failed_edit_leaves_the_scene_unchanged():
    s = scg.Scene.load(CASES / "uniform.toml")
    before = s.toml
    with pytest.raises(scg.SceneError):
        s.set("groups.0.diameter", -1.0)
    assert s.toml == before
    s.set("duration", 0.25)
    assert s.get("duration") == 0.25
    assert s.duration == 0.25
    assert s["groups.0.name"] == s.get("groups.0.name")
    with pytest.raises(KeyError):
        s.get("no.such.key")
    assert s.get("no.such.key", None) is None


def test_edits_are_those_of_set():
    # a mapping, `key=value` strings and later .set() calls give one text
    a = scg.Scene.load(CASES / "elbow.toml", set=ELBOW_EDITS)
    b = scg.Scene.load(CASES / "elbow.toml", set=["duration=0.02", "feed_scale=0.05"])
    c = scg.Scene.load(CASES / "elbow.toml").set("duration", 0.02).set("feed_scale", 0.05)
    assert a.toml == b.toml == c.toml
    assert a.edits == ["duration=0.02", "feed_scale=0.05"]
    assert scg.toml_literal([1, 2.5, "x", True]) == '[1, 2.5, "x", true]'
    assert scg.toml_literal({"model": "stick"}) == '{ model = "stick" }'


def test_check_gives_the_figures_as_data():
    s = scg.Scene.load(CASES / "cyclone.toml")
    c = s.check()
    assert list(c.groups["name"]) == [g["name"] for g in s.get("groups")]
    assert c.dt == s.dt and c.steps == s.steps
    # τ = ρ d² / (18 μ) for the Stokes regime the 1 µm class is in
    tau = 2000.0 * (1e-6) ** 2 / (18 * 1.8e-5)
    assert c.groups.loc[0, "tau"] == pytest.approx(tau, rel=1e-9)
    assert all(level in ("note", "warning", "error") for level, _ in c.findings)
    out = cli("check", "cases/cyclone.toml")
    assert out.returncode == 0
    assert c.text == out.stdout


def test_a_run_gives_the_cli_s_fates_and_summary_bit_for_bit(tmp_path):
    scene = scg.Scene.load(CASES / "elbow.toml", set=ELBOW_EDITS)
    run = scene.run(threads=1)
    sets = [a for k, v in ELBOW_EDITS.items() for a in ("--set", f"{k}={v}")]
    out = cli(
        "run", "cases/elbow.toml", "--no-record", *sets,
        "--summary-json", str(tmp_path / "s.json"),
        "--fates-csv", str(tmp_path / "f.csv"),
        "--erosion-csv", str(tmp_path / "e.csv"),
    )
    assert out.returncode == 0, out.stderr
    cli_summary = json.loads((tmp_path / "s.json").read_text())
    assert without_timing(run.summary) == without_timing(cli_summary)
    pd.testing.assert_frame_equal(run.fates, pd.read_csv(tmp_path / "f.csv"), check_exact=True)
    assert run.erosion is not None
    pd.testing.assert_frame_equal(run.erosion, pd.read_csv(tmp_path / "e.csv"), check_exact=True)
    # the run fed particles and some of them left: the comparison is not of empty tables
    assert run.groups["fed"].sum() > 0
    assert (run.fates.query("fate == 'entered'")["count"] > 0).all()


def test_frames_streamed_from_a_run_equal_the_mcap_s(tmp_path):
    scene = scg.Scene.load(CASES / "elbow.toml", set=ELBOW_EDITS)
    live = []
    run = scene.run(out=tmp_path, record=True, on_frame=live.append)
    rec = run.recording
    assert rec is not None and rec.path.exists()
    read = list(rec.frames())
    assert len(read) == len(live) > 2
    for a, b in zip(live, read):
        assert (a.step, a.time) == (b.step, b.time)
        for name in ("id", "group", "position", "velocity", "diameter", "density", "fluctuation"):
            x, y = getattr(a, name), getattr(b, name)
            assert x.dtype == y.dtype and np.array_equal(x, y), name
        assert a.stats == b.stats
    assert read[-1].n > 0 and read[-1].position.shape == (read[-1].n, 3)
    assert read[-1].fluctuation.shape == (read[-1].n,)  # the elbow has dispersion
    assert rec.complete
    assert rec.meta["case"] == "elbow"
    assert run.paths[0].name == "elbow-feed_scale=0.05.rrd"  # as `scg run --set` names it
    # arrays are read-only views; a frame nobody keeps is refilled for the next, and the
    # copies taken from such frames are the kept frames
    assert not live[-1].position.flags.writeable
    copies = []
    scene.run(on_frame=lambda f: copies.append({n: np.array(getattr(f, n)) for n in ("id", "position", "velocity")}))
    assert len(copies) == len(live)
    for a, c in zip(live, copies):
        for name, y in c.items():
            assert np.array_equal(getattr(a, name), y), name
    assert "[flow]" in rec.scene
    wear = rec.wear
    assert wear is not None and {"patch", "volume", "depth_rate"} <= set(wear.columns)
    # the CLI reads the same file
    out = cli("replay", str(rec.path), "--verify")
    assert out.returncode == 0, out.stderr


def test_sweep_runs_every_point():
    base = scg.Scene.load(CASES / "uniform.toml", set={"duration": 0.01})
    table = scg.sweep(base, {"groups.0.diameter": [1e-3, 2e-3], "seed": [1, 2]}, threads=1)
    points = table[["groups.0.diameter", "seed"]].drop_duplicates()
    assert len(points) == 4
    one = base.with_set("groups.0.diameter", 2e-3).with_set("seed", 2).run(threads=1).fates
    got = table[(table["groups.0.diameter"] == 2e-3) & (table["seed"] == 2)]
    pd.testing.assert_frame_equal(got.drop(columns=["groups.0.diameter", "seed"]).reset_index(drop=True), one)


def test_a_callback_s_error_stops_the_run_and_is_raised():
    calls = []

    def progress(step, steps):
        calls.append(step)
        raise ValueError("stop here")

    scene = scg.Scene.load(CASES / "uniform.toml", set={"duration": 1.0})
    with pytest.raises(ValueError, match="stop here"):
        scene.run(progress=progress)
    assert calls == [256]


def test_ctrl_c_stops_a_run_cleanly(tmp_path):
    script = textwrap.dedent(
        f"""
        import sys, scg
        scene = scg.Scene.load({str(ROOT / CASES / 'elbow.toml')!r}, set={{"duration": 5.0}})
        def progress(step, steps):
            if step == 256:
                print("running", flush=True)
        try:
            scene.run(out={str(tmp_path)!r}, record=True, progress=progress)
        except KeyboardInterrupt:
            rec = scg.open_recording(next(p for p in __import__("pathlib").Path({str(tmp_path)!r}).glob("*.mcap")))
            n = sum(1 for _ in rec.frames())
            print("interrupted", n, rec.complete, flush=True)
            sys.exit(0)
        sys.exit(3)
        """
    )
    p = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, cwd=ROOT)
    assert p.stdout is not None
    assert p.stdout.readline().strip() == "running"
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=120)
    assert p.returncode == 0, out
    words = out.split()
    assert words[0] == "interrupted"
    assert int(words[1]) >= 1  # the frames written so far
    assert words[2] == "True"  # the recording was closed properly


def test_a_bad_recording_is_a_recording_error(tmp_path):
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not an mcap file")
    with pytest.raises(scg.RecordingError):
        scg.open_recording(bad)


def test_a_study_s_summary_and_tables_are_read_back(tmp_path):
    st = scg.study("elbow", quick=True, out=tmp_path / "elbow")
    assert st.summary is not None
    assert {"variants", "tracers", "verdicts"} <= set(st.summary)
    # the same numbers as the files the study wrote
    on_disk = json.loads((tmp_path / "elbow" / "summary.json").read_text())
    assert st.summary == on_disk
    assert "wear" in st.tables and len(st.tables["wear"]) > 0
    assert "report" in st.markdown
    with pytest.raises(scg.RunError):
        scg.study("no-such-study", out=tmp_path / "x")
