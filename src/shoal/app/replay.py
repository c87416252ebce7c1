"""Replay files: a recorded run as one compressed file that another ``shoal serve`` can show.

A replay is a NumPy ``.npz`` archive (a deflate-compressed zip of ``.npy`` arrays, read
without pickle) holding

* ``meta``: UTF-8 JSON as bytes: ``format``, ``version``, the ``shoal`` version that wrote
  it, the resolved ``preset`` (as JSON), its ``name``, the ``seed``, the ``kind`` of scene,
  the names of the ``metrics`` columns, the number of ``live_edits`` made while it ran and
  (version 2) ``twin``: ``{"overrides": {dotted.key: value}}`` when swarm B of Compare ran, else null;
* ``k`` (F,) step numbers, ``t`` (F,) times, ``n`` (F,) robots in each frame;
* ``x`` (R, d) positions, ``heading`` (R,), ``status`` (R,): the frames' robots one after
  another (R = Σ n; a Chapter 3 swarm may change size while it runs);
* ``metrics`` (M, C): the per-step metric rows;

and, from version 2, what else the arena drew at each frame:

* ``b_n`` (F,) swarm B's robots in each frame (0: none), ``b_x`` (R_B, d_B), ``b_status`` (R_B,)
  (B may move in another dimension than A: ``sim.d`` is one of the fields B may override);
* for each part of the scene that can change while a run goes on (each registered kind declares
  its own, ``SceneKind.scene_parts``: a fleet's ``obstacles`` [x, y, r], a sonar's ``source``
  [x, y]; :func:`scene_parts`), its changes only: ``<part>_i`` (W,) the frame from which each
  version holds (increasing, the first 0), ``<part>_n`` (W,) its rows and ``<part>_v`` (Σ n,
  columns) the rows one version after another. Every registered part is written (W = 0 for a
  kind without it); a reader takes those it knows, and a part a file lacks has no changes.
  Version-1 files have none of these arrays.

Pure functions of bytes and arrays, no engine: :func:`to_bytes` and :func:`from_bytes`,
which checks size, format, version and every shape and raises :class:`ReplayError` naming
what is wrong.
"""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass, field, replace
from typing import Any, Mapping, Sequence

import numpy as np

from shoal.presets import kinds

FORMAT = "shoal-replay"
VERSION = 2  # what this shoal writes
READS = (1, 2)  # what it reads
MAX_REPLAY_BYTES = 20 * 1024 * 1024  # a replay file, compressed
MAX_NUMBERS = 12_000_000  # numbers over all arrays once unpacked: a zip bomb stops here
MAX_META_BYTES = 1024 * 1024
MAX_MEMBERS = 32
MAX_ROWS_SHOWN = 20_000  # rows of one version of a scene part (obstacles drawn at once)
MAX_SCENE_M = 1e7  # |x|, |y|, r of a scene part (a preset's places are within 1e5 m; float32 views stay finite)
MAX_FRAMES = 20_000  # frames (a session keeps 5,000; each frame shown becomes objects of its own)
MAX_ROWS = 400_000  # robot rows (frames × robots) of swarm A, and of swarm B: what a session's history keeps
ROBOTS = ("k", "t", "n", "x", "heading", "status", "metrics")
TWIN = ("b_n", "b_x", "b_status")
ARRAYS = {1: ROBOTS, 2: ROBOTS + TWIN}  # by format version (and, from 2, the scene parts' arrays)
META_KEYS = {"format": str, "version": int, "shoal": str, "preset": dict, "name": str, "seed": int,
             "kind": str, "metrics": list, "live_edits": int}


class ReplayError(ValueError):
    """A replay file that cannot be shown; ``messages`` say what is wrong, one line each."""

    def __init__(self, messages: list[str]) -> None:
        self.messages = messages
        super().__init__("\n".join(messages))


def _offsets(n: np.ndarray) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(n)]).astype(np.int64)


@dataclass(frozen=True)
class Changes:
    """A part of the scene that changes now and then: version j holds from frame ``i[j]`` on and
    has rows ``v[offsets[j]:offsets[j + 1]]`` (``n[j]`` of them)."""

    i: np.ndarray  # (W,) int64, increasing, the first 0
    n: np.ndarray  # (W,) int64
    v: np.ndarray  # (Σ n, columns) float64
    offsets: np.ndarray = field(init=False, repr=False)
    rows: tuple[np.ndarray, ...] = field(init=False, repr=False)  # each version's rows (views into ``v``)

    def __post_init__(self) -> None:
        offsets = _offsets(self.n)
        object.__setattr__(self, "offsets", offsets)
        object.__setattr__(self, "rows", ())
        if np.all(self.n >= 0) and offsets[-1] == len(self.v):  # (a file's are checked after: then again)
            object.__setattr__(self, "rows", tuple(self.v[a:b] for a, b in zip(offsets[:-1], offsets[1:])))

    @classmethod
    def of(cls, values: Sequence[np.ndarray], columns: int) -> Changes:
        """The changes of one value per frame (each (rows, columns)): a version where it differs
        from the frame before."""
        i, rows, last = [], [], None
        for f, value in enumerate(values):
            value = np.asarray(value, np.float64).reshape(-1, columns)
            if last is None or not np.array_equal(value, last):
                i.append(f)
                rows.append(value)
            last = value
        return cls(i=np.asarray(i, np.int64), n=np.array([len(r) for r in rows], np.int64),
                   v=np.concatenate(rows) if rows else np.zeros((0, columns)))

    def version(self, frame: int) -> int:
        """The version shown at ``frame`` (-1 before the first)."""
        return int(np.searchsorted(self.i, frame, side="right")) - 1

    def at(self, frame: int) -> np.ndarray | None:
        """The rows at ``frame`` (the same array for every frame of a version), None if nothing
        was recorded by then."""
        j = self.version(frame)
        return None if j < 0 else self.rows[j]


def _empty_twin(frames: int, d: int) -> dict[str, np.ndarray]:
    return {"b_n": np.zeros(frames, np.int64), "b_x": np.zeros((0, d)), "b_status": np.zeros(0, np.int8)}


@dataclass(frozen=True)
class Recording:
    """A recorded run: metadata, F frames of robots (ragged, see the module doc), metrics, swarm
    B's robots (``b_*``; none in a version-1 file or without Compare) and the ``scene`` parts
    that changed while it ran."""

    meta: dict[str, Any]
    k: np.ndarray  # (F,) int64
    t: np.ndarray  # (F,) float64
    n: np.ndarray  # (F,) int64
    x: np.ndarray  # (R, d) float64
    heading: np.ndarray  # (R,) float64
    status: np.ndarray  # (R,) int8
    metrics: np.ndarray  # (M, C) float64
    b_n: np.ndarray | None = None  # (F,) int64, 0 where B has no frame (None: no B)
    b_x: np.ndarray | None = None  # (R_B, d) float64
    b_status: np.ndarray | None = None  # (R_B,) int8
    scene: Mapping[str, Changes] = field(default_factory=dict)  # part (:func:`scene_parts`) → its changes
    offsets: np.ndarray = field(init=False, repr=False)  # (F + 1,) first row of each frame
    b_offsets: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.b_n is None:
            for name, value in _empty_twin(len(self.k), self.x.shape[1]).items():
                object.__setattr__(self, name, value)
        object.__setattr__(self, "offsets", _offsets(self.n))
        object.__setattr__(self, "b_offsets", _offsets(self.twin_rows[0]))

    @property
    def twin_rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Swarm B's ``(b_n, b_x, b_status)``: empty (no robot in any frame) when no B was
        recorded, as :meth:`__post_init__` fills them."""
        if self.b_n is None or self.b_x is None or self.b_status is None:
            raise ValueError("a recording's swarm B is filled in when it is made")
        return self.b_n, self.b_x, self.b_status

    @property
    def frames(self) -> int:
        return len(self.k)

    @property
    def name(self) -> str:
        return str(self.meta["name"])

    @property
    def seed(self) -> int:
        return int(self.meta["seed"])

    @property
    def metric_names(self) -> tuple[str, ...]:
        return tuple(self.meta["metrics"])

    @property
    def twin_overrides(self) -> dict[str, Any] | None:
        """How swarm B differed from A (None: no B recorded)."""
        twin = self.meta.get("twin")
        return dict(twin["overrides"]) if twin else None

    def robots(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x (n, d), heading (n,), status (n,)) of frame ``i``."""
        a, b = self.offsets[i], self.offsets[i + 1]
        return self.x[a:b], self.heading[a:b], self.status[a:b]

    def twin(self, i: int) -> tuple[np.ndarray, np.ndarray] | None:
        """Swarm B's (x, status) at frame ``i`` (None where B has no frame)."""
        a, b = self.b_offsets[i], self.b_offsets[i + 1]
        _, b_x, b_status = self.twin_rows
        return (b_x[a:b], b_status[a:b]) if b > a else None

    def scene_at(self, i: int) -> dict[str, np.ndarray]:
        """The recorded parts of the scene as they were at frame ``i``."""
        out = {}
        for part, changes in self.scene.items():
            rows = changes.at(i)
            if rows is not None:
                out[part] = rows
        return out


def make_meta(*, shoal: str, preset: dict[str, Any], name: str, seed: int, kind: str, metrics: tuple[str, ...],
              live_edits: int = 0, twin: dict[str, Any] | None = None) -> dict[str, Any]:
    """The ``meta`` entry of a replay written now (``twin``: swarm B's overrides, None without B)."""
    return {"format": FORMAT, "version": VERSION, "shoal": shoal, "preset": preset, "name": name, "seed": int(seed),
            "kind": kind, "metrics": list(metrics), "live_edits": int(live_edits),
            "twin": None if twin is None else {"overrides": dict(twin)}}


def scene_parts() -> dict[str, int]:
    """The parts of a scene a replay stores, name → numbers in a row: every registered kind's."""
    return kinds.scene_parts()


def from_frames(meta: dict[str, Any], k: list[int], t: list[float], xs: list[np.ndarray], headings: list[np.ndarray],
                statuses: list[np.ndarray], metrics: np.ndarray,
                twins: Sequence[tuple[np.ndarray, np.ndarray] | None] | None = None,
                scenes: Sequence[Mapping[str, np.ndarray]] | None = None) -> Recording:
    """A recording from per-frame arrays (``xs[i]`` is (n_i, d)); ``twins[i]``: swarm B's (x, status)
    at frame i or None; ``scenes[i]``: the parts of the scene (:func:`scene_parts`) at frame i."""
    d = xs[0].shape[1] if xs else 2
    twin: dict[str, Any] = {}
    if twins is not None and any(b is not None for b in twins):
        kept = [b for b in twins if b is not None]
        twin = {"b_n": np.array([0 if b is None else len(b[0]) for b in twins], np.int64),
                "b_x": np.concatenate([b[0] for b in kept]).astype(np.float64),
                "b_status": np.concatenate([b[1] for b in kept]).astype(np.int8)}
    scene = {}
    for part, columns in scene_parts().items():
        values = [s[part] for s in scenes or () if part in s]
        if values and len(values) == len(xs):
            scene[part] = Changes.of(values, columns)
    return Recording(
        meta=meta, k=np.asarray(k, np.int64), t=np.asarray(t, np.float64),
        n=np.array([len(x) for x in xs], np.int64),
        x=np.concatenate(xs).astype(np.float64) if xs else np.zeros((0, d)),
        heading=np.concatenate(headings).astype(np.float64) if xs else np.zeros(0),
        status=np.concatenate(statuses).astype(np.int8) if xs else np.zeros(0, np.int8),
        metrics=np.asarray(metrics, np.float64).reshape(len(metrics), -1), scene=scene, **twin,
    )


def to_bytes(rec: Recording) -> bytes:
    """The replay file of ``rec`` (compressed ``.npz``, format version 2)."""
    buf = io.BytesIO()
    meta = np.frombuffer(json.dumps(rec.meta, separators=(",", ":")).encode("utf-8"), dtype=np.uint8)
    scene = {}
    for part, columns in scene_parts().items():
        c = rec.scene.get(part) or Changes(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, columns)))
        scene.update({f"{part}_i": c.i, f"{part}_n": c.n, f"{part}_v": c.v})
    b_n, b_x, b_status = rec.twin_rows
    contents: dict[str, Any] = dict(meta=meta, k=rec.k, t=rec.t, n=rec.n, x=rec.x, heading=rec.heading,
                                    status=rec.status, metrics=rec.metrics, b_n=b_n, b_x=b_x, b_status=b_status,
                                    **scene)  # (arrays only, in this order)
    np.savez_compressed(buf, **contents)
    return buf.getvalue()


# ---------------------------------------------------------------------------- reading
def _headers(zf: zipfile.ZipFile, where: str) -> dict[str, tuple[tuple[int, ...], np.dtype]]:
    """Shape and dtype of every ``.npy`` member, from its header alone (nothing unpacked yet)."""
    out = {}
    members = zf.infolist()
    if len(members) > MAX_MEMBERS:
        raise ReplayError([f"{where}: {len(members)} members, a replay has at most {len(ARRAYS[VERSION]) + 1}"])
    fmt = np.lib.format
    for info in members:
        name = info.filename.removesuffix(".npy")
        with zf.open(info) as f:
            try:
                version = fmt.read_magic(f)
                read = {(1, 0): fmt.read_array_header_1_0, (2, 0): fmt.read_array_header_2_0}[version]
                shape, _, dtype = read(f)
            except Exception as err:  # not a .npy member
                raise ReplayError([f"{where}: member {name!r} is not a NumPy array ({err!r})"]) from None
        if dtype.hasobject or dtype.kind not in "biuf":
            raise ReplayError([f"{where}: {name} has dtype {dtype}, expected numbers"])
        out[name] = (tuple(int(s) for s in shape), dtype)
    return out


def _meta(raw: np.ndarray, where: str) -> dict[str, Any]:
    try:
        meta = json.loads(raw.astype(np.uint8).tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ReplayError([f"{where}: meta is not UTF-8 JSON ({err})"]) from None
    if not isinstance(meta, dict):
        raise ReplayError([f"{where}: meta is not a JSON object"])
    if meta.get("format") != FORMAT:
        raise ReplayError([f"{where}: format {meta.get('format')!r} is not {FORMAT!r}"])
    version = meta.get("version")
    if isinstance(version, bool) or version not in READS:
        newer = isinstance(version, int) and not isinstance(version, bool) and version > VERSION
        raise ReplayError([f"{where}: format version {version!r} "
                           + ("is newer than this shoal reads" if newer else "is not one this shoal reads")
                           + f" (it reads versions {', '.join(map(str, READS))})"])
    bad = [f"meta.{key}: missing or not a {kind.__name__}" for key, kind in META_KEYS.items()
           if not isinstance(meta.get(key), kind) or (kind is int and isinstance(meta.get(key), bool))]
    if not bad and not all(isinstance(m, str) for m in meta["metrics"]):
        bad.append("meta.metrics: not a list of names")
    if version >= 2:
        twin = meta.get("twin", "missing")
        if twin is not None and not (isinstance(twin, dict) and set(twin) == {"overrides"}
                                     and isinstance(twin["overrides"], dict)):
            bad.append("meta.twin: missing, or neither null nor {\"overrides\": {dotted.key: value}}")
    else:
        meta = {**meta, "twin": None}
    if bad:
        raise ReplayError([f"{where}: {b}" for b in bad])
    return meta


def _ragged(shapes: dict[str, tuple[int, ...]], n: str, rows: str, f: int, others: tuple[str, ...]) -> list[str]:
    """Shape errors of a ragged block: counts ``n`` (F,), ``rows`` (R, d) and ``others`` (R,)."""
    errors = []
    if shapes[n] != (f,):
        errors.append(f"{n}: shape {shapes[n]}, expected ({f},): one count a frame like k")
    r = shapes[rows][0] if len(shapes[rows]) == 2 else -1
    if len(shapes[rows]) != 2 or not 1 <= shapes[rows][1] <= 3:
        errors.append(f"{rows}: shape {shapes[rows]}, expected (rows, d) with d = 1, 2 or 3")
    for name in others:
        if shapes[name] != (r,):
            errors.append(f"{name}: shape {shapes[name]}, expected ({r},) like the rows of {rows}")
    return errors


def _check_shapes(shapes: dict[str, tuple[int, ...]], n_metrics: int, version: int, where: str) -> list[str]:
    errors = []
    f = shapes["k"][0] if len(shapes["k"]) == 1 else -1
    for name in ("k", "t"):
        if shapes[name] != (f,) or f < 1:
            errors.append(f"{name}: shape {shapes[name]}, expected (F,) with F ≥ 1 frames like k")
    errors += _ragged(shapes, "n", "x", f, ("heading", "status"))
    m = shapes["metrics"]
    if len(m) != 2 or m[1] != n_metrics:
        errors.append(f"metrics: shape {m}, expected (steps, {n_metrics}) for the {n_metrics} names in meta")
    if version >= 2:
        errors += _ragged(shapes, "b_n", "b_x", f, ("b_status",))
        for part, columns in scene_parts().items():
            i, n, v = (f"{part}_{a}" for a in "inv")
            if not any(a in shapes for a in (i, n, v)):
                continue  # (a part this file does not store: no changes)
            w = shapes[i][0] if len(shapes[i]) == 1 else -1
            if w < 0 or w > max(f, 0):
                errors.append(f"{i}: shape {shapes[i]}, expected (W,) with at most one change a frame")
            if shapes[n] != (w,):
                errors.append(f"{n}: shape {shapes[n]}, expected ({w},) like {i}")
            if len(shapes[v]) != 2 or shapes[v][1] != columns:
                errors.append(f"{v}: shape {shapes[v]}, expected (rows, {columns})")
    return [f"{where}: {e}" for e in errors]


def _check_counts(n: np.ndarray, rows: int, name: str, of: str, least: int) -> list[str]:
    """``n`` counts ≥ ``least`` that add up to the ``rows`` of ``of`` (each checked first: no overflow)."""
    if np.any(n < least) or np.any(n > rows):
        return [f"{name}: every count must be between {least} and the {rows} rows of {of}"]
    if int(n.sum()) != rows:
        return [f"{name}: the counts add up to {int(n.sum())} but {of} has {rows} rows"]
    return []


def _check_values(rec: Recording, where: str) -> list[str]:
    errors = _check_counts(rec.n, len(rec.x), "n", "x", 1)
    if np.any(np.diff(rec.k) <= 0):
        errors.append("k: step numbers must increase")
    if not np.all(np.isfinite(rec.t)) or np.any(np.diff(rec.t) < 0):
        errors.append("t: times must be finite and never decrease")
    for name in ("x", "heading", "b_x"):  # (metrics may hold NaN: a value not defined at that step)
        if not np.all(np.isfinite(getattr(rec, name))):
            errors.append(f"{name}: {'headings' if name == 'heading' else 'positions'} must be finite numbers")
    b_n, b_x, _ = rec.twin_rows
    errors += _check_counts(b_n, len(b_x), "b_n", "b_x", 0)
    for part, c in rec.scene.items():
        if len(c.i) and (c.i[0] != 0 or np.any(np.diff(c.i) <= 0) or c.i[-1] >= rec.frames):
            errors.append(f"{part}_i: frames must increase from 0 and stay below the {rec.frames} frames")
        least = 1 if part == "source" else 0
        errors += _check_counts(c.n, len(c.v), f"{part}_n", f"{part}_v", least)
        if part == "source" and np.any(c.n != 1):
            errors.append("source_n: the source is one row [x, y]")
        if np.any(c.n > MAX_ROWS_SHOWN):
            errors.append(f"{part}_n: at most {MAX_ROWS_SHOWN:,} rows at once")
        if not np.all(np.isfinite(c.v)) or np.any(np.abs(c.v) > MAX_SCENE_M):
            errors.append(f"{part}_v: must be finite numbers within ±{MAX_SCENE_M:.0e} m")
        elif part == "obstacles" and np.any(c.v[:, 2] <= 0):
            errors.append("obstacles_v: every radius (column 3) must be positive")
    return [f"{where}: {e}" for e in errors]


def from_bytes(content: bytes, filename: str = "replay") -> Recording:
    """Read and check a replay file (format version 1 or 2). Raises :class:`ReplayError` (size,
    format, version, missing arrays, shapes, values), never anything else for bad input."""
    where = filename or "replay"
    size = len(content)
    if size > MAX_REPLAY_BYTES:
        raise ReplayError([f"{where}: {size / 2**20:.1f} MiB is larger than the "
                           f"{MAX_REPLAY_BYTES // 2**20} MiB limit for a replay"])
    try:
        zf = zipfile.ZipFile(io.BytesIO(content))
    except (zipfile.BadZipFile, OSError, ValueError):
        raise ReplayError([f"{where}: not a replay (a .npz file from Export replay); "
                           "it may be truncated or damaged"]) from None
    try:
        with zf:
            headers = _headers(zf, where)
            missing = [a for a in ("meta",) + ROBOTS if a not in headers]
            if missing:
                raise ReplayError([f"{where}: missing {', '.join(missing)} (not a shoal replay?)"])
            rows = [(name, headers[name][0][0]) for name in ("x", "b_x") if name in headers and headers[name][0]]
            if any(r > MAX_ROWS for _, r in rows):
                raise ReplayError([f"{where}: {name}: {r:,} robot rows (frames × robots), more than the {MAX_ROWS:,} "
                                   "a replay may hold (what a session records)" for name, r in rows if r > MAX_ROWS])
            numbers = sum(int(np.prod(s)) for s, _ in headers.values())
            if numbers > MAX_NUMBERS or headers["meta"][0][0] > MAX_META_BYTES:
                raise ReplayError([f"{where}: {numbers:,} numbers once unpacked, more than the "
                                   f"{MAX_NUMBERS:,} a replay may hold"])
            if len(headers["meta"][0]) != 1:
                raise ReplayError([f"{where}: meta: shape {headers['meta'][0]}, expected (bytes,)"])
            frames = headers["k"][0][0] if len(headers["k"][0]) == 1 else 0
            if frames > MAX_FRAMES:
                raise ReplayError([f"{where}: k: {frames:,} frames, more than the {MAX_FRAMES:,} a replay may hold"])
            with np.load(io.BytesIO(content), allow_pickle=False) as npz:
                meta = _meta(npz["meta"], where)
                names = list(ARRAYS[meta["version"]])
                if meta["version"] >= 2:  # each part it stores: its three arrays (a part it lacks: no changes)
                    for part in scene_parts():
                        group = [f"{part}_{a}" for a in "inv"]
                        names += group if any(a in headers for a in group) else []
                missing = [a for a in names if a not in headers]
                if missing:
                    raise ReplayError([f"{where}: missing {', '.join(missing)} (a version-{meta['version']} "
                                       "replay has them)"])
                errors = _check_shapes({a: headers[a][0] for a in names}, len(meta["metrics"]), meta["version"],
                                       where)
                if errors:
                    raise ReplayError(errors)
                arrays = {a: npz[a] for a in names}
    except ReplayError:
        raise
    except Exception as err:  # a damaged member (bad CRC, cut short, bad deflate stream)
        raise ReplayError([f"{where}: damaged or truncated ({type(err).__name__}: {err})"]) from None
    twin = {}
    scene = {}
    if meta["version"] >= 2:
        twin = {"b_n": arrays["b_n"].astype(np.int64), "b_x": arrays["b_x"].astype(np.float64),
                "b_status": arrays["b_status"].astype(np.int8)}
        for part in scene_parts():
            if f"{part}_i" not in arrays:
                continue
            scene[part] = Changes(i=arrays[f"{part}_i"].astype(np.int64), n=arrays[f"{part}_n"].astype(np.int64),
                                  v=arrays[f"{part}_v"].astype(np.float64))
    rec = Recording(
        meta=meta, k=arrays["k"].astype(np.int64), t=arrays["t"].astype(np.float64), n=arrays["n"].astype(np.int64),
        x=arrays["x"].astype(np.float64), heading=arrays["heading"].astype(np.float64),
        status=arrays["status"].astype(np.int8), metrics=arrays["metrics"].astype(np.float64), scene=scene, **twin)
    errors = _check_values(rec, where)
    if errors:
        raise ReplayError(errors)
    return replace(rec, scene={part: c for part, c in scene.items() if len(c.i)})  # parts that were recorded
