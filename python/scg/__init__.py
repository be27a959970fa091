"""scg from Python: run scenes, sweep them, and read every result as arrays and tables.

The engine is scg's Rust library (the native module ``scg._scg``): a scene is validated,
run and recorded by the same code as ``scg run``, so a run from Python gives the same
fates and summary bit for bit. This package turns what the engine returns into pandas
DataFrames and numpy arrays.

Five lines that needed a shell loop and a JSON parser before::

    import scg
    scene = scg.Scene.load("cases/elbow.toml", set={"duration": 0.05})
    for feed in (0.5, 1.0, 2.0):
        run = scene.with_set("feed_scale", feed).run()
        print(feed, run.fates[["group", "entered", "airborne"]])

Errors are exceptions: :class:`SceneError` (file, key, line, message), :class:`CheckError`
(``scg check`` found an error), :class:`RunError`, :class:`RecordingError`.
"""

from __future__ import annotations

import io
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterable, Iterator, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import pandas as pd

from . import _scg
from ._errors import CheckError, RecordingError, RunError, ScgError, SceneError

__all__ = [
    "Scene",
    "Check",
    "Run",
    "Frame",
    "Recording",
    "Study",
    "open_recording",
    "sweep",
    "study",
    "toml_literal",
    "ScgError",
    "SceneError",
    "CheckError",
    "RunError",
    "RecordingError",
    "engine_version",
]

PathLike = Union[str, "os.PathLike[str]"]
Progress = Union[bool, Callable[[int, int], Any], None]


def engine_version() -> str:
    """The version of the scg engine this package was built with."""
    return _scg.version()


def toml_literal(value: Any) -> str:
    """``value`` written as the TOML value of a ``--set key=value`` edit.

    bool → ``true``/``false``; int, float (``inf``, ``nan``); str (quoted); list/tuple →
    array; dict → inline table. Anything else is a ``TypeError``.
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_literal(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{k} = {toml_literal(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"cannot write {type(value).__name__} {value!r} as a TOML value")


def _edits(set: Union[Mapping[str, Any], Sequence[str], None]) -> List[str]:
    """``--set`` edits from a mapping (values written as TOML) or ``key=value`` strings."""
    if set is None:
        return []
    if isinstance(set, Mapping):
        return [f"{k}={toml_literal(v)}" for k, v in set.items()]
    out = []
    for s in set:
        if not isinstance(s, str) or "=" not in s:
            raise TypeError(f"an edit is `key=value` text or a mapping entry, not {s!r}")
        out.append(s)
    return out


@dataclass(frozen=True)
class Check:
    """What ``scg check`` derives from a scene.

    ``groups``: one row per group (name, law, alpha, count, diameter m, density kg/m³,
    tau s, slip m/s, reynolds, density_ratio, contact_time s); ``findings``: (level,
    message) pairs, level one of ``note``, ``warning``, ``error``; ``text``: what
    ``scg check`` prints.
    """

    groups: pd.DataFrame
    stokes_number: float
    dt: float
    steps: int
    findings: List[Tuple[str, str]]
    text: str

    @property
    def warnings(self) -> List[str]:
        """The warning messages."""
        return [m for level, m in self.findings if level == "warning"]

    @property
    def errors(self) -> List[str]:
        """The error messages (a run is refused when there is one)."""
        return [m for level, m in self.findings if level == "error"]

    def __str__(self) -> str:
        return self.text


@dataclass
class Frame:
    """One recorded frame: ``n`` particles at ``step`` (time s).

    ``id``, ``group``: uint32 (n); ``position`` m, ``velocity`` m/s: float64 (n, 3);
    ``diameter`` m, ``density`` kg/m³ (as simulated, after coarse graining): float64 (n);
    ``fluctuation``: |u′| m/s (n), empty without dispersion; ``stats``: the frame's
    scalars (``count/<group>``…). The arrays are read-only views of the engine's own
    buffers (no copy is made); ``np.array(frame.position)`` gives a copy to change.
    """

    step: int
    time: float
    id: np.ndarray
    group: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    diameter: np.ndarray
    density: np.ndarray
    fluctuation: np.ndarray
    stats: Dict[str, float]

    @property
    def n(self) -> int:
        """Particles in the frame."""
        return int(self.id.shape[0])

    def to_frame(self) -> pd.DataFrame:
        """The particles as a DataFrame (x, y, z, vx, vy, vz, diameter, density, id, group)."""
        d = {
            "id": self.id,
            "group": self.group,
            "x": self.position[:, 0],
            "y": self.position[:, 1],
            "z": self.position[:, 2],
            "vx": self.velocity[:, 0],
            "vy": self.velocity[:, 1],
            "vz": self.velocity[:, 2],
            "diameter": self.diameter,
            "density": self.density,
        }
        if self.fluctuation.size:
            d["fluctuation"] = self.fluctuation
        return pd.DataFrame(d)


def _frame(d: Dict[str, Any]) -> Frame:
    # each column is numpy's view of the engine's own buffer (read-only, no copy)
    return Frame(
        step=d["step"],
        time=d["time"],
        id=np.asarray(d["id"]),
        group=np.asarray(d["group"]),
        position=np.asarray(d["position"]),
        velocity=np.asarray(d["velocity"]),
        diameter=np.asarray(d["diameter"]),
        density=np.asarray(d["density"]),
        fluctuation=np.asarray(d["fluctuation"]),
        stats=d["stats"],
    )


class Recording:
    """An MCAP recording written by scg (``scg run``, :meth:`Scene.run` with ``record``).

    :meth:`frames` reads it one frame at a time (one frame in memory); ``meta`` is the run
    description (case, version, seed, dt, record_every, groups, scene text, warnings,
    patches).
    """

    def __init__(self, path: PathLike):
        self.path = Path(path)
        self._native = _scg.open_recording(str(self.path))
        self.meta: Dict[str, Any] = self._native.meta()
        self._end: Optional[Tuple[bool, Optional[str]]] = None

    @property
    def scene(self) -> str:
        """The scene's TOML text as the run read it (edits applied)."""
        return self.meta["scene"]

    @property
    def groups(self) -> pd.DataFrame:
        """The groups: name, law, alpha, original_diameter m, color."""
        return pd.DataFrame(self.meta["groups"])

    def frames(self) -> Iterator[Frame]:
        """Every frame in the order written, read as it is asked for."""
        native = _scg.open_recording(str(self.path))
        while True:
            d = native.next_frame()
            if d is None:
                self._end = native.end()
                return
            yield _frame(d)

    def _ended(self) -> Tuple[bool, Optional[str]]:
        if self._end is None:
            for _ in self.frames():
                pass
        assert self._end is not None
        return self._end

    @property
    def complete(self) -> bool:
        """Whether the file was closed properly (a killed run's is not)."""
        return self._ended()[0]

    @property
    def wear(self) -> Optional[pd.DataFrame]:
        """With ``[erosion]``: one row per face (patch, face, volume m³, depth_rate m/s,
        impacts when recorded); ``None`` without."""
        text = self._ended()[1]
        if text is None:
            return None
        w = json.loads(text)
        rows = []
        for p in w["patches"]:
            cols = {k: v for k, v in p.items() if isinstance(v, list) and len(v) == len(p["faces"])}
            t = pd.DataFrame(cols)
            t.insert(0, "patch", p["name"])
            rows.append(t)
        return pd.concat(rows, ignore_index=True) if rows else pd.DataFrame()


def open_recording(path: PathLike) -> Recording:
    """Open an MCAP recording (its description now, its frames as they are read)."""
    return Recording(path)


@dataclass
class Run:
    """A finished run.

    ``summary``: the ``scg run --summary-json`` document; ``fates``: the ``--fates-csv``
    table (per group: entered, escaped and stuck per patch, lost, airborne; counts,
    shares and the original powder's mass); ``erosion``: the ``--erosion-csv`` table
    (``None`` without ``[erosion]``); ``paths``: the files written.
    """

    summary: Dict[str, Any]
    fates: pd.DataFrame
    erosion: Optional[pd.DataFrame]
    paths: List[Path] = field(default_factory=list)

    @property
    def groups(self) -> pd.DataFrame:
        """Per group: fed, drained, lost, held (counts) and diameter, density."""
        cols = ["group", "diameter", "density", "fed", "drained", "lost", "held"]
        return pd.DataFrame([{k: g[k] for k in cols} for g in self.summary["groups"]])

    @property
    def recording(self) -> Optional[Recording]:
        """The run's MCAP recording, when it wrote one."""
        for p in self.paths:
            if p.suffix == ".mcap":
                return Recording(p)
        return None

    @property
    def particle_steps_per_s(self) -> float:
        """Particle-steps per second of wall time."""
        return float(self.summary["particle_steps_per_s"])


def _bar(total: int) -> Callable[[int, int], None]:
    start = time.monotonic()

    def show(step: int, steps: int) -> None:
        width = 40
        done = int(width * step / max(steps, 1))
        elapsed = time.monotonic() - start
        sys.stderr.write(f"\r{'#' * done}{'-' * (width - done)} {step}/{steps} steps {elapsed:7.1f} s")
        if step >= steps:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show


class Scene:
    """A validated scene: a TOML file (or text) and its ``--set`` edits.

    Keys are read and changed with the paths of ``--set`` (``groups.0.alpha``,
    ``flow.series.cycle``); every change is validated at once, with the errors of
    ``scg run`` as :class:`SceneError`.
    """

    def __init__(self, native: Any, origin: Tuple[str, ...]):
        self._native = native
        self._origin = origin

    @classmethod
    def load(cls, path: PathLike, set: Union[Mapping[str, Any], Sequence[str], None] = None) -> "Scene":
        """Load a scene file, with edits (``{"duration": 0.1}`` or ``["duration=0.1"]``)."""
        edits = _edits(set)
        return cls(_scg.load_scene(str(path), edits), ("file", str(path)))

    @classmethod
    def from_toml(
        cls,
        text: str,
        file: PathLike = "<string>",
        set: Union[Mapping[str, Any], Sequence[str], None] = None,
    ) -> "Scene":
        """A scene from TOML text; ``file`` names it in errors and its folder resolves the
        scene's relative paths (a CFD case, STL walls)."""
        file = str(file)
        stem = Path(file).stem if not file.startswith("<") else "scene"
        return cls(_scg.parse_scene(text, file, stem, _edits(set)), ("text", text, file, stem))

    @classmethod
    def embedded(cls, set: Union[Mapping[str, Any], Sequence[str], None] = None) -> "Scene":
        """The embedded default scene (the paper's vortex case), as ``scg run`` runs it."""
        return cls(_scg.embedded_scene(_edits(set)), ("embedded",))

    def _reload(self, edits: List[str]) -> Any:
        kind = self._origin[0]
        if kind == "file":
            return _scg.load_scene(self._origin[1], edits)
        if kind == "text":
            return _scg.parse_scene(self._origin[1], self._origin[2], self._origin[3], edits)
        return _scg.embedded_scene(edits)

    @property
    def name(self) -> str:
        """The scene's name (the file's stem unless ``name`` is set)."""
        return self._native.name

    @property
    def file(self) -> str:
        """Where it came from."""
        return self._native.file

    @property
    def toml(self) -> str:
        """The TOML text with the edits applied (as recordings store it)."""
        return self._native.source

    @property
    def edits(self) -> List[str]:
        """The edits, as ``--set`` takes them."""
        return list(self._native.sets)

    @property
    def dt(self) -> float:
        """Time step, s (resolved when ``auto``)."""
        return self._native.dt

    @property
    def duration(self) -> float:
        """Simulated duration, s."""
        return self._native.duration

    @property
    def steps(self) -> int:
        """Steps of a run."""
        return self._native.steps

    def get(self, key: str, default: Any = KeyError) -> Any:
        """The value of ``key`` as written or set (``groups.0.alpha``); ``default`` (or a
        ``KeyError``) when the scene does not write it (defaults: docs/scenes.md)."""
        try:
            return self._native.value(key)
        except KeyError:
            if default is KeyError:
                raise
            return default

    def __getitem__(self, key: str) -> Any:
        return self.get(key)

    def set(self, key: str, value: Any) -> "Scene":
        """Change ``key`` to ``value`` (as ``--set key=value``), validated now; on an error
        the scene is unchanged and :class:`SceneError` says why. Returns the scene."""
        edits = self.edits + [f"{key}={toml_literal(value)}"]
        self._native = self._reload(edits)
        return self

    def with_set(self, key: str, value: Any) -> "Scene":
        """A copy with ``key`` changed to ``value`` (this scene unchanged)."""
        return Scene(self._reload(self.edits + [f"{key}={toml_literal(value)}"]), self._origin)

    def __setitem__(self, key: str, value: Any) -> None:
        self.set(key, value)

    def check(self) -> Check:
        """``scg check``: derived quantities per group, dt, steps, Stokes number, findings."""
        c = self._native.check()
        return Check(
            groups=pd.DataFrame(c["groups"]),
            stokes_number=c["stokes_number"],
            dt=c["dt"],
            steps=c["steps"],
            findings=[tuple(f) for f in c["findings"]],
            text=c["text"],
        )

    def plan(self) -> str:
        """The systems a run executes, in order (``scg run --plan``)."""
        return self._native.plan()

    def run(
        self,
        out: PathLike = "recordings",
        record: bool = False,
        vtk: Optional[PathLike] = None,
        frames_csv: Optional[PathLike] = None,
        threads: Optional[int] = None,
        progress: Progress = None,
        on_frame: Optional[Callable[[Frame], Any]] = None,
    ) -> Run:
        """Run the scene to its end; the GIL is released while it runs.

        ``record``: write ``<out>/<name>.rrd`` and ``.mcap`` (as ``scg run``); ``vtk``,
        ``frames_csv``: folders for VTK / CSV frames. ``threads``: worker threads (default
        ``SCG_THREADS`` or every core; results are the same bits for any count).
        ``progress``: ``True`` for a bar on stderr, or a callable ``(step, steps)``.
        ``on_frame``: called with each recorded :class:`Frame` as the run goes (no
        recording is held in memory). Ctrl-C stops the run at once, closes its
        recordings and raises ``KeyboardInterrupt``; an exception in a callback stops it
        and is raised.
        """
        cb: Optional[Callable[[int, int], Any]]
        if progress is True:
            cb = _bar(self.steps)
        elif progress is False or progress is None:
            cb = None
        else:
            cb = progress
        frame_cb = None
        if on_frame is not None:

            def frame_cb(d: Dict[str, Any]) -> None:
                on_frame(_frame(d))

        r = self._native.run(
            str(out),
            record,
            None if vtk is None else str(vtk),
            None if frames_csv is None else str(frames_csv),
            threads,
            cb,
            frame_cb,
        )
        erosion = None if r["erosion_csv"] is None else pd.read_csv(io.StringIO(r["erosion_csv"]))
        return Run(
            summary=json.loads(r["summary"]),
            fates=pd.read_csv(io.StringIO(r["fates_csv"])),
            erosion=erosion,
            paths=[Path(p) for p in r["paths"]],
        )

    def __repr__(self) -> str:
        edits = f", edits={self.edits}" if self.edits else ""
        return f"Scene({self.name!r}, file={self.file!r}{edits})"


def sweep(
    scene: Scene,
    grid: Mapping[str, Iterable[Any]],
    threads: Optional[int] = None,
    progress: bool = False,
) -> pd.DataFrame:
    """Run ``scene`` at every point of ``grid`` (key → values; every combination) and
    return the fates of every group at every point, one row per group and point, the
    grid's keys as the first columns.

    Each run uses ``threads`` worker threads (default: every core), one run after the
    other; a run's result does not depend on the thread count.
    """
    keys = list(grid)
    values = [list(grid[k]) for k in keys]
    points: List[Tuple[Any, ...]] = [()]
    for vs in values:
        points = [p + (v,) for p in points for v in vs]
    tables = []
    for i, p in enumerate(points):
        s = scene
        for k, v in zip(keys, p):
            s = s.with_set(k, v)
        if progress:
            sys.stderr.write(f"point {i + 1}/{len(points)}: {dict(zip(keys, p))}\n")
        fates = s.run(threads=threads).fates
        for k, v in reversed(list(zip(keys, p))):
            fates.insert(0, k, v)
        tables.append(fates)
    return pd.concat(tables, ignore_index=True)


@dataclass
class Study:
    """A finished study: its folder, its ``summary.json`` (when it writes one), every CSV
    it wrote as a DataFrame (by file stem) and its Markdown reports (by file stem)."""

    name: str
    out: Path
    summary: Optional[Dict[str, Any]]
    tables: Dict[str, pd.DataFrame]
    markdown: Dict[str, str]


def study(
    name: str,
    quick: bool = False,
    out: Optional[PathLike] = None,
    set: Union[Mapping[str, Any], Sequence[str], None] = None,
    record: bool = False,
    threads: Optional[int] = None,
) -> Study:
    """Run ``scg study NAME`` (``classifier``, ``classifier-psd``, ``classifier-cut``,
    ``cyclone``, ``elbow``, ``wheel``, ``loading``) into ``out`` (default
    ``recordings/study-<name>[-quick]``) and read what it wrote."""
    folder = Path(out) if out is not None else Path("recordings") / f"study-{name}{'-quick' if quick else ''}"
    code = _scg.study(name, quick, str(folder), _edits(set), record, threads)
    if code != 0:
        raise RunError(f"scg study {name} failed (exit status {code}; its messages are on stderr)")
    summary_path = folder / "summary.json"
    summary = json.loads(summary_path.read_text()) if summary_path.exists() else None
    tables = {p.stem: pd.read_csv(p) for p in sorted(folder.glob("*.csv"))}
    markdown = {p.stem: p.read_text() for p in sorted(folder.glob("*.md"))}
    return Study(name=name, out=folder, summary=summary, tables=tables, markdown=markdown)
