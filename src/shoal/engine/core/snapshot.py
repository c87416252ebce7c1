"""An engine's state as plain data, and that data as bytes (no pickle).

Every built-in engine offers ``snapshot() -> dict`` and ``restore(data)``: the snapshot is a tree
of ``dict`` (str keys), ``list``, ``tuple``, numpy arrays, numpy scalars and JSON scalars
(``bool``, ``int``, ``float``, ``str``, ``None``) holding everything a run depends on beyond what
the engine was built from (step, positions, bests, every generator's state, …); ``restore`` puts
it into an engine built from the same settings, so that both continue with the same bits.

:func:`to_bytes` writes a header (JSON) and such a tree as one ``.npz`` archive: the arrays as
``.npy`` members, the rest as JSON in the member ``snapshot.json``. :func:`from_bytes` reads it back
with ``allow_pickle=False``; nothing in the bytes names code to import or run. Bad or truncated
bytes raise :class:`SnapshotError`.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
import zipfile
from typing import Any, Iterable, Mapping, Sequence, TypeVar

import numpy as np

FORMAT = "shoal-snapshot"
VERSION = 1
HEADER = "snapshot.json"
MAX_ARRAYS = 100_000
MAX_BYTES = 1 << 30  # what from_bytes unpacks at most by default (its members' sizes as the zip declares them)

T = TypeVar("T")


class SnapshotError(ValueError):
    """A snapshot that cannot be read or does not fit the engine it is restored into."""


# ---------------------------------------------------------------------- engine helpers
def rng_state(g: np.random.Generator) -> dict[str, Any]:
    """A generator's bit-generator state as plain data (PCG64: two 128-bit integers and a buffered half)."""
    return dict(g.bit_generator.state)


def set_rng_state(g: np.random.Generator, state: Mapping[str, Any], where: str = "rng") -> None:
    """Put ``state`` into ``g`` in place (a compiled draw keeps its address of the generator's C state)."""
    name = type(g.bit_generator).__name__
    if not isinstance(state, Mapping) or state.get("bit_generator") != name:
        raise SnapshotError(f"{where}: expected the state of a {name} generator")
    try:
        g.bit_generator.state = dict(state)
    except (TypeError, ValueError, KeyError) as e:
        raise SnapshotError(f"{where}: {e}") from None


def rng_states(gens: Iterable[np.random.Generator]) -> list[dict[str, Any]]:
    return [rng_state(g) for g in gens]


def set_rng_states(gens: Sequence[np.random.Generator], states: Any, where: str = "rngs") -> None:
    if not isinstance(states, list) or len(states) != len(gens):
        raise SnapshotError(f"{where}: expected {len(gens)} generator states")
    for i, (g, st) in enumerate(zip(gens, states)):
        set_rng_state(g, st, f"{where}[{i}]")


def fields_of(obj: Any, nested: Iterable[str] = ()) -> dict[str, Any]:
    """A dataclass's init fields as a dict; the fields named in ``nested`` (dataclasses or None) as dicts too."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(obj):
        if not f.init:
            continue
        value = getattr(obj, f.name)
        out[f.name] = (None if value is None else fields_of(value)) if f.name in nested else value
    return out


def from_fields(cls: type[T], data: Any, where: str, nested: Mapping[str, type] | None = None) -> T:
    """``cls(**data)`` for a dataclass the caller names (never one the data names); nested fields
    through their own classes."""
    if not isinstance(data, dict):
        raise SnapshotError(f"{where}: expected the fields of {cls.__name__}")
    names = {f.name for f in dataclasses.fields(cls) if f.init}  # type: ignore[arg-type]
    if set(data) - names:
        raise SnapshotError(f"{where}: {cls.__name__} has no field {sorted(set(data) - names)[0]!r}")
    values = dict(data)
    for name, sub in (nested or {}).items():
        if values.get(name) is not None:
            values[name] = from_fields(sub, values[name], f"{where}.{name}")
    try:
        return cls(**values)
    except (TypeError, ValueError) as e:
        raise SnapshotError(f"{where}: {e}") from None


def array_like(value: Any, like: np.ndarray, where: str) -> np.ndarray:
    """``value`` as a fresh array of ``like``'s dtype and shape, or a :class:`SnapshotError` naming ``where``."""
    if not isinstance(value, np.ndarray) or value.shape != like.shape or value.dtype != like.dtype:
        got = f"{value.dtype}{value.shape}" if isinstance(value, np.ndarray) else type(value).__name__
        raise SnapshotError(f"{where}: expected a {like.dtype} array of shape {like.shape}, got {got}")
    return np.array(value, copy=True)


def arrays(value: Any, where: str, ndim: int | None = None, dtype: type | None = None) -> np.ndarray:
    """``value`` as a fresh array (of ``ndim`` dimensions, of ``dtype``'s kind), or a :class:`SnapshotError`."""
    if not isinstance(value, np.ndarray) or value.dtype.hasobject or (ndim is not None and value.ndim != ndim):
        raise SnapshotError(f"{where}: expected a {'' if ndim is None else f'{ndim}-D '}array")
    if dtype is not None and not np.issubdtype(value.dtype, dtype):
        raise SnapshotError(f"{where}: expected a {np.dtype(dtype).name} array, got {value.dtype}")
    return np.array(value, copy=True)


def part(data: Any, name: str, where: str = "snapshot") -> Any:
    """``data[name]``, or a :class:`SnapshotError` saying it is missing."""
    if not isinstance(data, dict) or name not in data:
        raise SnapshotError(f"{where}: no {name!r}")
    return data[name]


def integer(value: Any, where: str, low: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise SnapshotError(f"{where}: expected an integer >= {low}, got {value!r}")
    return int(value)


# ---------------------------------------------------------------------- plain data <-> JSON + arrays
def _pack(value: Any, out: list[np.ndarray], where: str) -> Any:
    if isinstance(value, np.ndarray):
        if value.dtype.hasobject:
            raise TypeError(f"{where}: object arrays cannot be snapshotted")
        out.append(np.ascontiguousarray(value))
        return {"$array": len(out) - 1}
    if isinstance(value, np.generic):
        if isinstance(value, np.bool_):
            return {"$scalar": "bool", "value": bool(value)}
        if isinstance(value, np.integer):
            return {"$scalar": value.dtype.name, "value": int(value)}
        if isinstance(value, np.floating):
            return {"$scalar": value.dtype.name, "value": _pack(float(value), out, where)}
        raise TypeError(f"{where}: cannot snapshot a {type(value).__name__}")
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else {"$float": repr(value)}
    if isinstance(value, tuple):
        return {"$tuple": [_pack(v, out, f"{where}[{i}]") for i, v in enumerate(value)]}
    if isinstance(value, list):
        return [_pack(v, out, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, dict):
        for k in value:
            if not isinstance(k, str) or k.startswith("$"):
                raise TypeError(f"{where}: keys must be strings not starting with '$', got {k!r}")
        return {k: _pack(v, out, f"{where}.{k}") for k, v in value.items()}
    raise TypeError(f"{where}: cannot snapshot a {type(value).__name__} (plain data only)")


FLOATS = {"nan": math.nan, "inf": math.inf, "-inf": -math.inf}
SCALARS = {"bool": np.bool_, "float64": np.float64, "float32": np.float32, "float16": np.float16,
           "int64": np.int64, "int32": np.int32, "int16": np.int16, "int8": np.int8, "uint64": np.uint64,
           "uint32": np.uint32, "uint16": np.uint16, "uint8": np.uint8}


def _unpack(value: Any, arrays_: Mapping[int, np.ndarray], where: str) -> Any:
    if isinstance(value, list):
        return [_unpack(v, arrays_, f"{where}[{i}]") for i, v in enumerate(value)]
    if not isinstance(value, dict):
        if value is None or isinstance(value, (bool, int, float, str)):
            return value
        raise SnapshotError(f"{where}: not plain data")
    if "$array" in value:
        i = value["$array"]
        if not isinstance(i, int) or isinstance(i, bool) or i not in arrays_:
            raise SnapshotError(f"{where}: names a missing array")
        return arrays_[i]
    if "$float" in value:
        if value["$float"] not in FLOATS:
            raise SnapshotError(f"{where}: bad float {value['$float']!r}")
        return FLOATS[value["$float"]]
    if "$tuple" in value:
        if not isinstance(value["$tuple"], list):
            raise SnapshotError(f"{where}: bad tuple")
        return tuple(_unpack(v, arrays_, f"{where}[{i}]") for i, v in enumerate(value["$tuple"]))
    if "$scalar" in value:
        kind = SCALARS.get(value["$scalar"])
        inner = _unpack(value.get("value"), arrays_, where)
        if kind is None or isinstance(inner, (str, type(None), list, tuple, dict)):
            raise SnapshotError(f"{where}: bad scalar {value['$scalar']!r}")
        try:
            return kind(inner)
        except (OverflowError, ValueError, TypeError):
            raise SnapshotError(f"{where}: bad scalar value") from None
    if any(k.startswith("$") for k in value):
        raise SnapshotError(f"{where}: unknown tag {next(k for k in value if k.startswith('$'))!r}")
    return {k: _unpack(v, arrays_, f"{where}.{k}") for k, v in value.items()}


def to_bytes(header: Mapping[str, Any], data: Any) -> bytes:
    """``header`` (JSON-able) and the plain-data tree ``data`` as one ``.npz`` archive."""
    found: list[np.ndarray] = []
    tree = _pack(data, found, "snapshot")
    doc = {"format": FORMAT, "version": VERSION, "header": _pack(dict(header), [], "header"), "data": tree}
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr(HEADER, json.dumps(doc, allow_nan=False, separators=(",", ":")))
        for i, a in enumerate(found):
            with z.open(f"a{i}.npy", "w", force_zip64=True) as f:
                np.lib.format.write_array(f, a, allow_pickle=False)
    return buf.getvalue()


def from_bytes(blob: bytes, max_bytes: int = MAX_BYTES) -> tuple[dict[str, Any], Any]:
    """The header and the plain-data tree of :func:`to_bytes`'s bytes; :class:`SnapshotError` if they are
    not a whole Shoal snapshot, or would unpack to more than ``max_bytes`` (checked from the zip's
    headers before anything is unpacked)."""
    if not isinstance(blob, (bytes, bytearray, memoryview)):
        raise SnapshotError(f"a snapshot is bytes, got {type(blob).__name__}")
    try:
        with zipfile.ZipFile(io.BytesIO(bytes(blob))) as z:
            names = z.namelist()
            if HEADER not in names:
                raise SnapshotError(f"not a Shoal snapshot: no {HEADER}")
            if len(names) > MAX_ARRAYS or len(set(names)) != len(names):
                raise SnapshotError(f"not a Shoal snapshot: {len(names)} members")
            size = sum(i.file_size for i in z.infolist())
            if size > max_bytes:
                raise SnapshotError(f"snapshot: unpacks to {size} bytes, more than the {max_bytes} allowed")
            doc = json.loads(z.read(HEADER).decode("utf-8"), parse_constant=_no_constant)
            if not isinstance(doc, dict) or doc.get("format") != FORMAT:
                raise SnapshotError("not a Shoal snapshot (its format is not named)")
            if doc.get("version") != VERSION:
                raise SnapshotError(f"snapshot format version {doc.get('version')!r}; this Shoal reads {VERSION}")
            found: dict[int, np.ndarray] = {}
            for name in names:
                if name == HEADER:
                    continue
                if not (name.startswith("a") and name.endswith(".npy") and name[1:-4].isdigit()):
                    raise SnapshotError(f"not a Shoal snapshot: unexpected member {name!r}")
                with z.open(name) as f:
                    found[int(name[1:-4])] = np.lib.format.read_array(f, allow_pickle=False)
    except SnapshotError:
        raise
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, OSError, UnicodeDecodeError, json.JSONDecodeError,
            ValueError, KeyError, RecursionError, MemoryError) as e:
        raise SnapshotError(f"not a whole Shoal snapshot ({type(e).__name__}: {str(e)[:200]})") from None
    try:
        header = _unpack(doc.get("header"), {}, "header")
        data = _unpack(doc.get("data"), found, "snapshot")
    except RecursionError:
        raise SnapshotError("snapshot: nested too deep") from None
    if not isinstance(header, dict):
        raise SnapshotError("snapshot: its header is not a table")
    return header, data


def _no_constant(name: str) -> Any:
    raise SnapshotError(f"snapshot.json: {name} is not JSON")
