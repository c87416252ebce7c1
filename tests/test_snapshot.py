"""Snapshots (``scene.snapshot()``, ``shoal.make(snapshot=...)``): a scene kept at step k goes on
with the same bits as the scene it was taken of, in this process or another one, on the compiled
tick or the numpy one; its bytes are an ``.npz`` archive with a JSON header, never a pickle, and
bad bytes are refused with a clear error."""

from __future__ import annotations

import io
import json
import subprocess
import sys
import zipfile

import numpy as np
import pytest

import shoal
from shoal.api.snapshot import Snapshot, SnapshotError
from shoal.engine.core import snapshot as codec
from shoal.presets.io import list_presets, load
from shoal.presets.kinds import kind_for

STEPS_BEFORE, STEPS_AFTER = 5, 100


def one_preset_per_kind() -> dict[str, str]:
    """The first shipped preset of each scene kind, on true and on SLO positions, and the presets
    with state the others lack: pymunk bodies, a moving source, step changes of the limits."""
    out: dict[str, str] = {}
    for name in list_presets():
        sc = load(name)
        out.setdefault(f"{kind_for(sc).name}{'+slo' if sc.slo is not None else ''}", name)
    return {**out, "physics": "course-physics", "moving source": "escort-moving", "step changes": "fig3-5b"}


PRESETS = sorted(set(one_preset_per_kind().values()))


def fingerprint(scene: shoal.Scene) -> bytes:
    """The bits of a scene's state and of every metric row it recorded."""
    s = scene.state
    parts = [np.asarray(getattr(s, n)).tobytes() for n in ("x", "u", "heading", "status")]
    if hasattr(s, "best_fitness"):
        parts.append(np.asarray(s.best_fitness).tobytes())
    table = scene.metrics(pandas=False)
    parts += [np.asarray(table[n]).tobytes() for n in table.dtype.names]
    return b"".join(parts)


def compiled(scene: shoal.Scene, on: bool) -> shoal.Scene:
    if hasattr(scene.engine, "compiled"):
        scene.engine.compiled = on
    return scene


@pytest.mark.parametrize("tick", ["compiled", "numpy"])
@pytest.mark.parametrize("preset", PRESETS)
def test_a_snapshot_goes_on_with_the_same_bits(preset, tick):
    original = compiled(shoal.make(preset, runs=2, seed=11), tick == "compiled")
    original.run(STEPS_BEFORE)
    blob = original.snapshot().to_bytes()
    copy = compiled(shoal.make(snapshot=blob), tick == "compiled")
    assert copy.k == original.k == STEPS_BEFORE and copy.scenario == original.scenario
    assert fingerprint(copy) == fingerprint(original)
    original.run(STEPS_AFTER)
    copy.run(STEPS_AFTER)
    assert copy.k == STEPS_BEFORE + STEPS_AFTER
    assert fingerprint(copy) == fingerprint(original)


def test_pymunk_bodies_that_collide_go_on_the_same():
    """Physics mode with robots colliding during the continuation: the spaces are built again
    round the bodies' poses and velocities, disabled robots kinematic."""
    make = dict(runs=2, seed=11, robots=12, controller={"mode": "raw", "omega": 0.5, "c1": 0.3, "c2": 0.3})
    original = shoal.make("course-physics", **make)
    original.run(5)
    before = original.row()["collided"].copy()
    copy = shoal.make(snapshot=original.snapshot().to_bytes())
    original.run(60)
    copy.run(60)
    assert (original.row()["collided"] > before).all()  # collisions after the snapshot
    assert fingerprint(copy) == fingerprint(original)


def test_the_tick_a_scene_ran_on_does_not_matter():
    """Snapshotted on the numpy tick, continued on the compiled one (the app's warm-up switches)."""
    a = compiled(shoal.make("course-dvc", runs=2, seed=4), False)
    a.run(6)
    b = compiled(shoal.make(snapshot=a.snapshot()), True)
    compiled(a, True)
    a.run(40)
    b.run(40)
    assert fingerprint(a) == fingerprint(b)


def test_taking_a_snapshot_changes_nothing():
    """The swarm's compiled tick draws ahead; a snapshot puts the generators back, which changes no number."""
    a, b = shoal.make("default", runs=3, seed=2), shoal.make("default", runs=3, seed=2)
    a.run(7)
    b.run(7)
    a.snapshot()
    a.run(50)
    b.run(50)
    assert fingerprint(a) == fingerprint(b)


def test_a_snapshot_goes_on_in_another_process(tmp_path):
    """Saved to disk, loaded by a fresh interpreter: the same bits as going on here."""
    scenes = {p: shoal.make(p, runs=2, seed=5) for p in ("default", "course-dvc", "escort-moving", "slo-walk",
                                                          "course-dvc-slo")}
    for name, scene in scenes.items():
        scene.run(STEPS_BEFORE)
        scene.snapshot().save(tmp_path / f"{name}.npz")
        scene.run(STEPS_AFTER)
    script = (
        "import hashlib, sys, numpy as np, shoal\n"
        "sys.path.insert(0, sys.argv[2])\n"
        "from test_snapshot import fingerprint\n"
        "for name in sys.argv[3:]:\n"
        "    scene = shoal.make(snapshot=f'{sys.argv[1]}/{name}.npz')\n"
        f"    scene.run({STEPS_AFTER})\n"
        "    print(name, hashlib.sha256(fingerprint(scene)).hexdigest())\n"
    )
    out = subprocess.run([sys.executable, "-c", script, str(tmp_path), str(__import__("pathlib").Path(__file__).parent),
                          *scenes], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    import hashlib

    got = dict(line.split() for line in out.stdout.splitlines())
    assert got == {n: hashlib.sha256(fingerprint(s)).hexdigest() for n, s in scenes.items()}


def test_the_snapshot_carries_the_scenario_and_the_metric_rows():
    scene = shoal.make("default", runs=2, seed=1, controller={"mode": "raw", "omega": 0.5})
    scene.run(4)
    snap = Snapshot.from_bytes(scene.snapshot().to_bytes())
    assert snap.scenario == scene.scenario and snap.k == 4 and snap.kind == "swarm"
    assert snap.rows is not None and snap.rows["step"].shape == (5, 2)
    again = shoal.make(snapshot=snap)
    assert again.scenario.controller.omega == 0.5
    np.testing.assert_array_equal(again.metrics(pandas=False)["best_fitness"],
                                  scene.metrics(pandas=False)["best_fitness"])
    lean = shoal.make(snapshot=scene.snapshot(metrics=False))
    assert len(lean.metrics(pandas=False)) == 2  # the current step's rows only


def test_an_edited_world_comes_back():
    """A fleet's obstacles as edited by hand (not in the scenario) are part of the snapshot."""
    scene = shoal.make("course-dvc", runs=1, seed=3)
    scene.run(3)
    fleet = scene.engine
    fleet.set_world(fleet.world.with_circle(4.0, 0.5, 1.0))
    copy = shoal.make(snapshot=scene.snapshot().to_bytes())
    assert copy.engine.world == fleet.world
    scene.run(30)
    copy.run(30)
    assert fingerprint(copy) == fingerprint(scene)


def test_a_live_retune_as_preset_sections_is_kept_and_engine_keywords_are_refused():
    scene = shoal.make("course-dvc", runs=1, seed=3)
    scene.retune(controller={"alpha": 0.5})
    assert shoal.make(snapshot=scene.snapshot()).engine.params.alpha == 0.5
    scene.retune(beta=0.4)
    with pytest.raises(SnapshotError, match="beta.*engine keywords"):
        scene.snapshot()


def test_make_takes_a_snapshot_or_a_preset():
    snap = shoal.make("default").snapshot()
    with pytest.raises(ValueError, match="not both"):
        shoal.make("course-dvc", snapshot=snap)
    with pytest.raises(ValueError, match="not both"):
        shoal.make(snapshot=snap, runs=3)
    with pytest.raises(TypeError, match="Snapshot, its bytes"):
        shoal.make(snapshot=42)


def test_save_writes_whole_files_and_keeps_what_is_there(tmp_path):
    snap = shoal.make("default").snapshot()
    path = tmp_path / "kept.npz"
    path.write_text("mine")
    with pytest.raises(FileExistsError, match="exists already"):
        snap.save(path)
    assert path.read_text() == "mine"
    snap.save(path, overwrite=True)
    assert Snapshot.load(path).scenario == snap.scenario
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kept.npz"]


# ---------------------------------------------------------------------- bad bytes
def good_bytes() -> bytes:
    scene = shoal.make("slo-walk", runs=1, seed=2)
    scene.run(2)
    return scene.snapshot().to_bytes()


def rezip(blob: bytes, change) -> bytes:
    """``blob`` with its members passed through ``change(name, data) -> data | None`` (None drops one)."""
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(blob)) as src, zipfile.ZipFile(out, "w") as dst:
        for name in src.namelist():
            data = change(name, src.read(name))
            if data is not None:
                dst.writestr(name, data)
    return out.getvalue()


def edit_header(blob: bytes, edit) -> bytes:
    def change(name, data):
        if name != codec.HEADER:
            return data
        doc = json.loads(data)
        edit(doc)
        return json.dumps(doc)
    return rezip(blob, change)


def npy(a) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.asarray(a), allow_pickle=True)
    return buf.getvalue()


def test_the_bytes_are_an_npz_with_a_json_header_and_no_pickle():
    blob = good_bytes()
    with zipfile.ZipFile(io.BytesIO(blob)) as z:
        names = z.namelist()
        doc = json.loads(z.read(codec.HEADER))
        for name in names[1:]:
            with z.open(name) as f:
                assert not np.lib.format.read_array(f, allow_pickle=False).dtype.hasobject
    assert names[0] == codec.HEADER and all(n.endswith(".npy") for n in names[1:])
    assert doc["format"] == "shoal-snapshot" and doc["header"]["scenario"]["name"]
    assert b"pickle" not in blob


@pytest.mark.parametrize("case, message", [
    ("truncated", "not a whole Shoal snapshot"),
    ("empty", "not a whole Shoal snapshot"),
    ("noise", "not a whole Shoal snapshot"),
    ("no header", "no snapshot.json"),
    ("other format", "format is not named"),
    ("newer version", "format version 99"),
    ("pickled array", "not a whole Shoal snapshot"),
    ("stray member", "unexpected member"),
    ("missing array", "missing array"),
    ("bad scenario", "scenario is not valid here"),
    ("other kind", "builds a 'slo_swarm' one"),
    ("wrong shape", "expected shape"),
    ("bad generator", "expected the state of a PCG64"),
    ("json constant", "not JSON"),
])
def test_bad_snapshot_bytes_are_refused(case, message):
    blob = good_bytes()
    bad = {
        "truncated": lambda: blob[: len(blob) // 2],
        "empty": lambda: b"",
        "noise": lambda: bytes(np.random.default_rng(0).integers(0, 256, 4000, dtype=np.uint8)),
        "no header": lambda: rezip(blob, lambda n, d: None if n == codec.HEADER else d),
        "other format": lambda: edit_header(blob, lambda doc: doc.update(format="something")),
        "newer version": lambda: edit_header(blob, lambda doc: doc.update(version=99)),
        "pickled array": lambda: rezip(blob, lambda n, d: npy(np.array([object()], dtype=object)) if n == "a0.npy"
                                       else d),
        "stray member": lambda: _with_member(blob, "evil.py", b"import os"),
        "missing array": lambda: rezip(blob, lambda n, d: None if n == "a0.npy" else d),
        "bad scenario": lambda: edit_header(blob, lambda doc: doc["header"]["scenario"]["sim"].update(runs=-3)),
        "other kind": lambda: edit_header(blob, lambda doc: doc["header"].update(kind="fleet")),
        "wrong shape": lambda: rezip(blob, lambda n, d: npy(np.zeros((1, 3, 2))) if n == "a0.npy" else d),
        "bad generator": lambda: edit_header(blob, lambda doc: doc["data"]["engine"]["streams"]["init"][0].update(
            bit_generator="MT19937")),
        "json constant": lambda: rezip(blob, lambda n, d: d.replace(b'"k":2', b'"k":NaN') if n == codec.HEADER
                                       else d),
    }[case]()
    with pytest.raises(SnapshotError, match=message):
        shoal.make(snapshot=bad)


def test_a_snapshot_too_big_to_unpack_is_refused_from_the_zip_headers():
    blob = good_bytes()
    with pytest.raises(SnapshotError, match="more than the 1000 allowed"):
        Snapshot.from_bytes(blob, max_bytes=1000)
    nested = b'{"format":"shoal-snapshot","version":1,"header":{},"data":' + b"[" * 100_000 + b"]" * 100_000 + b"}"
    deep = rezip(blob, lambda n, d: nested if n == codec.HEADER else d)
    with pytest.raises(SnapshotError, match="nested too deep|not a whole"):
        Snapshot.from_bytes(deep)


def test_a_snapshot_is_bytes():
    with pytest.raises(SnapshotError, match="a snapshot is bytes, got str"):
        Snapshot.from_bytes("a snapshot")  # type: ignore[arg-type]


def _with_member(blob: bytes, name: str, data: bytes) -> bytes:
    out = io.BytesIO(blob)
    with zipfile.ZipFile(out, "a") as z:
        z.writestr(name, data)
    return out.getvalue()


def test_the_codec_takes_plain_data_only():
    tree = {"a": np.arange(3), "b": (1, 2.5, float("nan"), -np.inf), "c": [None, True, "x"], "d": np.float32(1.5),
            "e": np.int8(-3), "f": {"g": np.bool_(True)}, "h": 2**100}
    header, back = codec.from_bytes(codec.to_bytes({"x": 1}, tree))
    assert header == {"x": 1}
    np.testing.assert_array_equal(back["a"], tree["a"])
    assert back["b"][:2] == (1, 2.5) and np.isnan(back["b"][2]) and back["b"][3] == -np.inf
    assert back["c"] == [None, True, "x"] and type(back["d"]) is np.float32 and type(back["e"]) is np.int8
    assert back["f"]["g"] is np.True_ and back["h"] == 2**100
    for bad in ({"f": print}, {"o": np.array([object()])}, {"$array": 1}, {1: 2}):
        with pytest.raises(TypeError):
            codec.to_bytes({}, bad)
