"""Plug-ins without forking: entries registered from Python, and the example package
(``examples/plugin``: an objective, a velocity law and a scene kind) installed and run through
the command, the API and the app's sessions. A plug-in is code the owner installed: no preset
value ever makes Shoal import anything."""

from __future__ import annotations

import csv
import json
import re
import sys

import numpy as np
import pytest

import shoal as shoal_api
from shoal.engine.core.plugins import GROUP
from shoal.engine.core.registry import Registry
from shoal.engine.pso.laws import LAWS, VelocityLaw, standard_velocity
from shoal.engine.robots.laws import ROBOT_LAWS
from shoal.presets.io import PresetError, load
from shoal.presets.kinds import KINDS

from plugin_env import EXAMPLE, python, shoal


def test_a_law_registered_from_python_is_a_preset_choice_with_its_rule():
    def halved(u, g, c, omega, r, width):
        return 0.5 * standard_velocity(u, g, c, omega, r)

    law = VelocityLaw("halved", "Halved PSO", adapted=False, velocity=halved, omega_range=(0.0, 0.9),
                      rule="0 <= omega < 0.9")
    shoal_api.register(law)
    try:
        assert load("default", ["controller.law=halved", "controller.mode=raw"]).controller.law == "halved"
        with pytest.raises(PresetError, match=r"omega = 0.95: Halved PSO needs 0 <= omega < 0.9"):
            load("default", ["controller.law=halved", "controller.mode=raw", "controller.omega=0.95"])
        with pytest.raises(PresetError, match="mode 'physical' needs an Adapted law"):
            load("default", ["controller.law=halved"])
        with pytest.raises(PresetError, match="a Chapter 4–5 fleet takes a law of rpso"):
            load("course-dvc", ["controller.law=halved", "controller.mode=raw"])
        a = shoal_api.make("default", controller={"law": "halved", "mode": "raw"}, runs=2, seed=1)
        b = shoal_api.make("default", controller={"law": "standard", "mode": "raw"}, runs=2, seed=1)
        a.step(), b.step()
        np.testing.assert_allclose(a.state.u, 0.5 * b.state.u)  # the same draws, half the step
        with pytest.raises(ValueError, match="law: 'halved' is registered already"):
            LAWS.register(law)
    finally:
        LAWS.unregister("halved")
    with pytest.raises(PresetError, match="controller.law"):
        load("default", ["controller.law=halved", "controller.mode=raw"])


def test_register_refuses_what_is_not_an_entry():
    with pytest.raises(TypeError, match="not a registry entry"):
        shoal_api.register(object())
    with pytest.raises(ValueError, match="an entry needs a name and a label"):
        Registry("thing").register(type("Nameless", (), {"label": "x"})())
    assert shoal_api.registry_for(ROBOT_LAWS["nonomni"]) is ROBOT_LAWS


def test_the_example_plugin_is_discovered_through_its_entry_point(example_plugin):
    out = python(example_plugin, "import json, shoal; from shoal.presets.kinds import KINDS; "
                 "from shoal.engine.pso.laws import LAWS; from shoal.engine.core.objectives import OBJECTIVES; "
                 "print(json.dumps([[p.name, p.value, p.error] for p in shoal.plugins()] + "
                 "[list(KINDS), list(LAWS), list(OBJECTIVES)]))")
    assert out.returncode == 0, out.stderr
    plugins, kinds, laws, objectives = json.loads(out.stdout)[0:1], *json.loads(out.stdout)[1:]
    assert plugins == [["example", "shoal_example:register", None]]
    assert kinds[-1] == "gather" and laws[-1] == "clamped" and objectives[-1] == "himmelblau"
    assert "gather" not in KINDS and "clamped" not in LAWS  # this process has no plug-in


def test_the_command_runs_the_plugins_kind_law_and_objective(example_plugin, tmp_path):
    listed = shoal(example_plugin, "presets", "list")
    assert listed.returncode == 0 and "gather-demo" in listed.stdout
    done = shoal(example_plugin, "run", "gather-demo", "--runs", "2", "--steps", "20", "--out", str(tmp_path / "g"))
    assert done.returncode == 0, done.stderr
    with open(tmp_path / "g" / "metrics.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["run", "step", "t", "max_speed", "mean_speed", "spread", "radius"]  # no best_fitness
    assert len(rows) == 1 + 2 * 21 and float(rows[-1][5]) < float(rows[1][5])  # they gathered
    sets = ["--set", "objective.kind=himmelblau", "--set", "controller.law=clamped", "--set", "controller.mode=raw"]
    done = shoal(example_plugin, "run", "default", *sets, "--steps", "30", "--out", str(tmp_path / "h"))
    assert done.returncode == 0, done.stderr
    with open(tmp_path / "h" / "metrics.csv", newline="", encoding="utf-8") as fh:
        speeds = [float(r["max_component"]) for r in csv.DictReader(fh)][1:]
    assert max(speeds) <= 2.0  # the clamped law's bound (V_CLAMP)
    swept = shoal(example_plugin, "sweep", "gather-demo", "--grid", "gather.speed=0.5,2", "--runs", "2", "--steps",
                  "10", "--out", str(tmp_path / "s"))
    assert swept.returncode == 0, swept.stderr
    with open(tmp_path / "s" / "results.csv", newline="", encoding="utf-8") as fh:
        header = next(csv.reader(fh))
    assert header[:3] == ["gather.speed", "run", "seed"] and "spread" in header and "best_fitness" not in header


API_SCRIPT = """
import json, numpy as np, shoal
scene = shoal.make("gather-demo", runs=3, seed=2)
table = scene.run(25)
changed = scene.retune(gather={"speed": 2.5})
try:
    scene.retune(gather={"area": 5.0})
    refused = ""
except ValueError as err:
    refused = str(err)
swarm = shoal.make("default", objective="himmelblau", controller={"law": "clamped", "mode": "raw"}, steps=40)
best = swarm.run()["best_fitness"].to_numpy()
print(json.dumps({"columns": list(table.columns), "rows": len(table), "changed": changed, "refused": refused,
                  "speed": scene.engine.params.speed, "kind": scene.kind.name, "optimises": scene.kind.optimises,
                  "best_falls": bool(best[-1] <= best[0])}))
"""


def test_the_api_runs_the_plugins_kind_law_and_objective(example_plugin):
    out = python(example_plugin, API_SCRIPT)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["columns"] == ["run", "step", "t", "max_speed", "mean_speed", "spread", "radius"]
    assert got["rows"] == 3 * 26 and got["changed"] == ["speed"] and got["speed"] == 2.5
    assert got["refused"].startswith("gather: this change needs a new engine")
    assert (got["kind"], got["optimises"], got["best_falls"]) == ("gather", False, True)


APP_SCRIPT = """
import json
from shoal.app.kinds.registry import kinds, session_for
from shoal.app.limits import check_app_limits
from shoal.presets.io import PresetError, load
from shoal.app.panel.spec import field_bounds
session = session_for(load("gather-demo"))
session.play()
session.step(5)
session.apply({"gather.speed": 3.0})
session.step(2)
try:
    check_app_limits(load("gather-demo", ["sim.robots=600"]))
    capped = ""
except PresetError as err:
    capped = err.messages[0]
print(json.dumps({"kinds": [k.name for k in kinds()], "k": session.sim.state.k, "speed": session.sim.params.speed,
                  "columns": list(session.history.names), "bounds": field_bounds("gather.noise"), "capped": capped,
                  "robots": session.snapshot().x.shape[0]}))
"""


def test_the_apps_sessions_run_the_plugins_kind(example_plugin):
    out = python(example_plugin, APP_SCRIPT)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["kinds"] == ["swarm", "fleet", "sonar", "mai", "gather"]
    assert got["k"] == 7 and got["speed"] == 3.0 and got["robots"] == 25
    assert "spread" in got["columns"] and "best_fitness" not in got["columns"]
    assert got["bounds"] == [0.0, 5.0]
    assert got["capped"].startswith("sim.robots = 600: the browser app runs at most 500 robots in this kind of "
                                    "scene (gathering swarm)")


SECURITY_SCRIPT = """
import json, sys
from shoal.presets.io import PresetError, load
refusals = []
for sets in (["objective.kind=shoal_example:himmelblau"], ["objective.kind=shoal_example.gather"],
             ["controller.law=shoal_example:clamped_velocity"], ["objective.kind=not_installed_pkg:f"]):
    try:
        load("default", sets)
    except PresetError as err:
        refusals.append(err.messages[0])
try:
    load("gather-demo")
except PresetError as err:
    refusals.append(err.messages[0])
print(json.dumps({"refusals": refusals, "imported": sorted(m for m in sys.modules
                                                               if m.startswith(("shoal_example", "not_installed")))}))
"""


def test_no_preset_value_imports_code(example_plugin):
    """With plug-ins switched off, a preset naming the installed plug-in's module, function or
    kind, or a package that is not installed, is refused by field and imports nothing; with them
    on, the same module paths are still only unknown names."""
    off = python(example_plugin, SECURITY_SCRIPT, SHOAL_PLUGINS="off")
    assert off.returncode == 0, off.stderr
    got = json.loads(off.stdout)
    assert got["imported"] == []
    assert [m.split(":")[0] for m in got["refusals"]] == ["objective.kind"] * 2 + ["controller.law", "objective.kind"] \
        + ["no preset or file named 'gather-demo' (shipped presets"]
    on = python(example_plugin, SECURITY_SCRIPT)
    assert on.returncode == 0, on.stderr
    got = json.loads(on.stdout)
    assert len(got["refusals"]) == 4 and all("Input should be" in m for m in got["refusals"])
    assert "not_installed_pkg" not in " ".join(got["imported"])


def test_a_broken_plugin_is_reported_and_shoal_carries_on(tmp_path):
    """An entry point that fails to load is a warning and an error in ``shoal.plugins()``."""
    site = tmp_path / "site"
    dist = site / "broken_plugin-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: broken-plugin\nVersion: 0.1\n", encoding="utf-8")
    (dist / "entry_points.txt").write_text(f"[{GROUP}]\nbroken = broken_plugin:register\n", encoding="utf-8")
    (site / "broken_plugin.py").write_text("def register():\n    raise RuntimeError('no luck')\n", encoding="utf-8")
    out = python(site, "import shoal, warnings\nwith warnings.catch_warnings(record=True) as w:\n"
                       "    warnings.simplefilter('always'); p = shoal.plugins()\n"
                       "print(p[0].error); print(str(w[0].message)); print(shoal.make('default').step().t)")
    assert out.returncode == 0, out.stderr
    error, warning, t = out.stdout.splitlines()
    assert error == "RuntimeError: no luck"
    assert "shoal plug-in 'broken' (broken_plugin:register) did not load" in warning
    assert float(t) == pytest.approx(0.1)


def test_this_process_loaded_no_plugin():
    assert "shoal_example" not in sys.modules and shoal_api.plugins() == []


def test_a_strategy_a_selection_and_a_robot_law_register_from_python_too():
    """Each registry takes a plug-in's entry the same way; here copies of built-in entries under
    new names, which must run exactly as the originals (the fleet's copy on the numpy tick, which
    the compiled one equals bit for bit)."""
    from dataclasses import dataclass, replace
    from typing import ClassVar

    from shoal.engine.acoustics.strategies import STRATEGIES, XBPSO
    from shoal.engine.slo.selection import SELECTIONS

    @dataclass(frozen=True)
    class Mine(XBPSO):
        name: ClassVar[str] = "xb-mine"
        label: ClassVar[str] = "XB-PSO (a copy)"

    added = [shoal_api.register(Mine),
             shoal_api.register(replace(SELECTIONS["rts"], name="rts-mine", label="RTS copy")),
             shoal_api.register(replace(ROBOT_LAWS["rpso"], name="rpso-mine", label="RPSO copy"))]
    try:
        for preset, key, mine, theirs in (("sonar-xb-pso", "acoustics.algorithm", "xb-mine", "xb-pso"),
                                          ("slo-walk", "slo.selection", "rts-mine", "rts"),
                                          ("course-rpso", "controller.law", "rpso-mine", "rpso")):
            a = shoal_api.make(preset, [f"{key}={mine}"], runs=2, seed=3).run(8)
            b = shoal_api.make(preset, [f"{key}={theirs}"], runs=2, seed=3).run(8)
            np.testing.assert_array_equal(a.to_numpy(), b.to_numpy(), err_msg=preset)
    finally:
        for registry, entry in zip((STRATEGIES, SELECTIONS, ROBOT_LAWS), added):
            registry.unregister(entry.name)


def test_the_example_plugins_own_tests_pass_the_conformance_kit(example_plugin):
    """examples/plugin/tests runs shoal.testing's checks on the gather kind, as a plug-in author
    would in their package, with the plug-in installed."""
    tests = EXAMPLE / "tests"
    done = python(example_plugin, f"import sys, pytest; sys.exit(pytest.main(['-q', '-p', 'no:cacheprovider', "
                                  f"{str(tests)!r}]))")
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert re.search(r"\b(1[0-9]|[2-9][0-9]) passed\b", done.stdout), done.stdout[-500:]  # the kit's checks and its own
