"""What the Python package costs over the CLI (issue 57), measured.

    python bench/python-overhead.py [--repeat 5] [--only elbow|frames]   # from the root

1. cases/elbow.toml on one thread, alternated with `target/release/scg run --no-record`,
   best of --repeat: the steps' wall time (`wall_s` of the summary, the CLI's "done: …
   in X s") and load + run (the CLI: its whole process; Python: `Scene.load` + `run`,
   the interpreter's start and `import scg` apart, which are printed too).
2. Frames of a 10^6-particle run handed to `on_frame` as numpy arrays (a run with and
   without the callback; the difference over the records), and read back from its MCAP
   with `open_recording(...).frames()`.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import scg

MILLION = """
name = "million"
duration = 3.0e-2
dt = 1.0e-3
record_every = 1
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "uniform"
velocity = [1.0, 0.0, 0.0]
[drag]
law = "stokes"
[[groups]]
name = "p"
diameter = 1.0e-5
density = 1000.0
count = 1000000
region = { kind = "box", min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--bin", default="target/release/scg")
    ap.add_argument("--only", choices=["elbow", "frames"], help="one of the two parts")
    a = ap.parse_args()
    if a.only != "frames":
        elbow(a)
    if a.only != "elbow":
        frames()


def elbow(a: argparse.Namespace) -> None:

    cli_steps, cli_all, py_steps, py_all = [], [], [], []
    for _ in range(a.repeat):
        t = time.perf_counter()
        out = subprocess.run(
            [a.bin, "--threads", "1", "run", "cases/elbow.toml", "--no-record"],
            capture_output=True, text=True, check=True,
        )
        cli_all.append(time.perf_counter() - t)
        cli_steps.append(float(re.search(r"done: \d+ steps .* in ([0-9.]+) s", out.stderr).group(1)))
        t = time.perf_counter()
        run = scg.Scene.load("cases/elbow.toml").run(threads=1)
        py_all.append(time.perf_counter() - t)
        py_steps.append(run.summary["wall_s"])
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import scg"], check=True)
    start_import = time.perf_counter() - t
    print(f"elbow, 1 thread, best of {a.repeat} (alternated):")
    print(f"  steps:      CLI {min(cli_steps):.3f} s   Python {min(py_steps):.3f} s   ({min(py_steps) / min(cli_steps) - 1:+.1%})")
    print(f"  load + run: CLI {min(cli_all):.3f} s (whole process)   Python {min(py_all):.3f} s   ({min(py_all) / min(cli_all) - 1:+.1%})")
    print(f"  a Python process's start + `import scg` (numpy, pandas): {start_import:.3f} s")


def frames() -> None:

    scene = scg.Scene.from_toml(MILLION)
    best_plain, best_frames, records = [], [], 0
    for _ in range(3):
        t = time.perf_counter()
        scene.run()
        best_plain.append(time.perf_counter() - t)
        n = []
        t = time.perf_counter()
        scene.run(on_frame=lambda f: n.append(f.n))
        best_frames.append(time.perf_counter() - t)
        records = sum(n)
    extra = min(best_frames) - min(best_plain)
    print(f"10^6 particles, {records} records: on_frame adds {extra:.3f} s: {records / extra:.3e} records/s "
          "(the engine building each frame included)")
    with tempfile.TemporaryDirectory() as d:
        rec = scene.run(out=d, record=True).recording
        t = time.perf_counter()
        k = sum(f.n for f in rec.frames())
        dt = time.perf_counter() - t
        print(f"  read back from the MCAP ({Path(rec.path).stat().st_size / 1e6:.0f} MB): {k / dt:.3e} records/s")


if __name__ == "__main__":
    main()
