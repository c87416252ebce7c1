"""Replay files: a recorded run as one compressed file that another ``shoal serve`` can show.

A replay is a NumPy ``.npz`` archive (a deflate-compressed zip of ``.npy`` arrays, read
without pickle) holding

* ``meta``: UTF-8 JSON as bytes: ``format``, ``version``, the ``shoal`` version that wrote
  it, the resolved ``preset`` (as JSON), its ``name``, the ``seed``, the ``kind`` of scene,
  the names of the ``metrics`` columns and the number of ``live_edits`` made while it ran;
* ``k`` (F,) step numbers, ``t`` (F,) times, ``n`` (F,) robots in each frame;
* ``x`` (R, d) positions, ``heading`` (R,), ``status`` (R,): the frames' robots one after
  another (R = Σ n; a Chapter 3 swarm may change size while it runs);
* ``metrics`` (M, C): the per-step metric rows.

Pure functions of bytes and arrays, no engine: :func:`to_bytes` and :func:`from_bytes`,
which checks size, format, version and every shape and raises :class:`ReplayError` naming
what is wrong.
"""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass, field
from typing import Any

import numpy as np

FORMAT = "shoal-replay"
VERSION = 1
MAX_REPLAY_BYTES = 20 * 1024 * 1024  # a replay file, compressed
MAX_NUMBERS = 12_000_000  # numbers over all arrays once unpacked: a zip bomb stops here
MAX_META_BYTES = 1024 * 1024
MAX_MEMBERS = 32
ARRAYS = ("k", "t", "n", "x", "heading", "status", "metrics")
META_KEYS = {"format": str, "version": int, "shoal": str, "preset": dict, "name": str, "seed": int,
             "kind": str, "metrics": list, "live_edits": int}


class ReplayError(ValueError):
    """A replay file that cannot be shown; ``messages`` say what is wrong, one line each."""

    def __init__(self, messages: list[str]) -> None:
        self.messages = messages
        super().__init__("\n".join(messages))


@dataclass(frozen=True)
class Recording:
    """A recorded run: metadata, F frames of robots (ragged, see the module doc) and metrics."""

    meta: dict[str, Any]
    k: np.ndarray  # (F,) int64
    t: np.ndarray  # (F,) float64
    n: np.ndarray  # (F,) int64
    x: np.ndarray  # (R, d) float64
    heading: np.ndarray  # (R,) float64
    status: np.ndarray  # (R,) int8
    metrics: np.ndarray  # (M, C) float64
    offsets: np.ndarray = field(init=False, repr=False)  # (F + 1,) first row of each frame

    def __post_init__(self) -> None:
        object.__setattr__(self, "offsets", np.concatenate([[0], np.cumsum(self.n)]).astype(np.int64))

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

    def robots(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x (n, d), heading (n,), status (n,)) of frame ``i``."""
        a, b = self.offsets[i], self.offsets[i + 1]
        return self.x[a:b], self.heading[a:b], self.status[a:b]


def make_meta(*, shoal: str, preset: dict[str, Any], name: str, seed: int, kind: str, metrics: tuple[str, ...],
              live_edits: int = 0) -> dict[str, Any]:
    """The ``meta`` entry of a replay written now."""
    return {"format": FORMAT, "version": VERSION, "shoal": shoal, "preset": preset, "name": name, "seed": int(seed),
            "kind": kind, "metrics": list(metrics), "live_edits": int(live_edits)}


def from_frames(meta: dict[str, Any], k: list[int], t: list[float], xs: list[np.ndarray], headings: list[np.ndarray],
                statuses: list[np.ndarray], metrics: np.ndarray) -> Recording:
    """A recording from per-frame arrays (``xs[i]`` is (n_i, d))."""
    d = xs[0].shape[1] if xs else 2
    return Recording(
        meta=meta, k=np.asarray(k, np.int64), t=np.asarray(t, np.float64),
        n=np.array([len(x) for x in xs], np.int64),
        x=np.concatenate(xs).astype(np.float64) if xs else np.zeros((0, d)),
        heading=np.concatenate(headings).astype(np.float64) if xs else np.zeros(0),
        status=np.concatenate(statuses).astype(np.int8) if xs else np.zeros(0, np.int8),
        metrics=np.asarray(metrics, np.float64).reshape(len(metrics), -1),
    )


def to_bytes(rec: Recording) -> bytes:
    """The replay file of ``rec`` (compressed ``.npz``)."""
    buf = io.BytesIO()
    meta = np.frombuffer(json.dumps(rec.meta, separators=(",", ":")).encode("utf-8"), dtype=np.uint8)
    np.savez_compressed(buf, meta=meta, k=rec.k, t=rec.t, n=rec.n, x=rec.x, heading=rec.heading,
                        status=rec.status, metrics=rec.metrics)
    return buf.getvalue()


# ---------------------------------------------------------------------------- reading
def _headers(zf: zipfile.ZipFile, where: str) -> dict[str, tuple[tuple[int, ...], np.dtype]]:
    """Shape and dtype of every ``.npy`` member, from its header alone (nothing unpacked yet)."""
    out = {}
    members = zf.infolist()
    if len(members) > MAX_MEMBERS:
        raise ReplayError([f"{where}: {len(members)} members, a replay has {len(ARRAYS) + 1}"])
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
    if version != VERSION:
        newer = isinstance(version, int) and version > VERSION
        raise ReplayError([f"{where}: format version {version!r} "
                           + ("is newer than this shoal reads" if newer else "is not one this shoal reads")
                           + f" (it reads version {VERSION})"])
    bad = [f"meta.{key}: missing or not a {kind.__name__}" for key, kind in META_KEYS.items()
           if not isinstance(meta.get(key), kind) or (kind is int and isinstance(meta.get(key), bool))]
    if not bad and not all(isinstance(m, str) for m in meta["metrics"]):
        bad.append("meta.metrics: not a list of names")
    if bad:
        raise ReplayError([f"{where}: {b}" for b in bad])
    return meta


def _check_shapes(shapes: dict[str, tuple[int, ...]], n_metrics: int, where: str) -> list[str]:
    errors = []
    f = shapes["k"][0] if len(shapes["k"]) == 1 else -1
    for name in ("k", "t", "n"):
        if shapes[name] != (f,) or f < 1:
            errors.append(f"{name}: shape {shapes[name]}, expected (F,) with F ≥ 1 frames like k")
    rows = shapes["x"][0] if len(shapes["x"]) == 2 else -1
    if len(shapes["x"]) != 2 or not 1 <= shapes["x"][1] <= 3:
        errors.append(f"x: shape {shapes['x']}, expected (rows, d) with d = 1, 2 or 3")
    for name in ("heading", "status"):
        if shapes[name] != (rows,):
            errors.append(f"{name}: shape {shapes[name]}, expected ({rows},) like the rows of x")
    m = shapes["metrics"]
    if len(m) != 2 or m[1] != n_metrics:
        errors.append(f"metrics: shape {m}, expected (steps, {n_metrics}) for the {n_metrics} names in meta")
    return [f"{where}: {e}" for e in errors]


def _check_values(rec: Recording, where: str) -> list[str]:
    errors = []
    if np.any(rec.n < 1):
        errors.append("n: every frame needs at least one robot")
    elif int(rec.n.sum()) != len(rec.x):
        errors.append(f"n: the frames hold {int(rec.n.sum())} robots in all but x has {len(rec.x)} rows")
    if np.any(np.diff(rec.k) <= 0):
        errors.append("k: step numbers must increase")
    if not np.all(np.isfinite(rec.t)) or np.any(np.diff(rec.t) < 0):
        errors.append("t: times must be finite and never decrease")
    for name in ("x", "heading"):  # (metrics may hold NaN: a value not defined at that step)
        if not np.all(np.isfinite(getattr(rec, name))):
            errors.append(f"{name}: {'positions' if name == 'x' else 'headings'} must be finite numbers")
    return [f"{where}: {e}" for e in errors]


def from_bytes(content: bytes, filename: str = "replay") -> Recording:
    """Read and check a replay file. Raises :class:`ReplayError` (size, format, version,
    missing arrays, shapes, values), never anything else for bad input."""
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
            missing = [a for a in ("meta",) + ARRAYS if a not in headers]
            if missing:
                raise ReplayError([f"{where}: missing {', '.join(missing)} (not a shoal replay?)"])
            numbers = sum(int(np.prod(s)) for s, _ in headers.values())
            if numbers > MAX_NUMBERS or headers["meta"][0][0] > MAX_META_BYTES:
                raise ReplayError([f"{where}: {numbers:,} numbers once unpacked, more than the "
                                   f"{MAX_NUMBERS:,} a replay may hold"])
            if len(headers["meta"][0]) != 1:
                raise ReplayError([f"{where}: meta: shape {headers['meta'][0]}, expected (bytes,)"])
            with np.load(io.BytesIO(content), allow_pickle=False) as npz:
                meta = _meta(npz["meta"], where)
                errors = _check_shapes({a: headers[a][0] for a in ARRAYS}, len(meta["metrics"]), where)
                if errors:
                    raise ReplayError(errors)
                arrays = {a: npz[a] for a in ARRAYS}
    except ReplayError:
        raise
    except Exception as err:  # a damaged member (bad CRC, cut short, bad deflate stream)
        raise ReplayError([f"{where}: damaged or truncated ({type(err).__name__}: {err})"]) from None
    rec = Recording(
        meta=meta, k=arrays["k"].astype(np.int64), t=arrays["t"].astype(np.float64), n=arrays["n"].astype(np.int64),
        x=arrays["x"].astype(np.float64), heading=arrays["heading"].astype(np.float64),
        status=arrays["status"].astype(np.int8), metrics=arrays["metrics"].astype(np.float64))
    errors = _check_values(rec, where)
    if errors:
        raise ReplayError(errors)
    return rec
