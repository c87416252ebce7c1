"""A careless plug-in cannot silence Shoal.

Each case installs one plug-in package as a temporary ``.dist-info`` on ``PYTHONPATH`` and runs
the real ``shoal`` command (the console script of this environment) in a child process:
``sys.exit(3)``, ``KeyboardInterrupt`` or another ``BaseException`` at import or in
``register()``, a malformed registry entry, a slow import, a replaced built-in, a scene kind
naming an app module that does not exist. Each broken plug-in is skipped with one line on
stderr naming its package, the error and ``SHOAL_PLUGINS=off``, and the command does its work.
A real Ctrl-C while the plug-ins load still ends the command.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from shoal.engine.core.plugins import GROUP

SHOAL = Path(sys.executable).with_name("shoal")  # the console script, as a user runs it


def install(site: Path, package: str, body: str) -> Path:
    """A plug-in package ``package`` (one module, ``body``; entry point ``package:register``) in ``site``."""
    dist = site / f"{package}-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {package.replace('_', '-')}\nVersion: 0.1\n",
                                   encoding="utf-8")
    (dist / "entry_points.txt").write_text(f"[{GROUP}]\n{package} = {package}:register\n", encoding="utf-8")
    (site / f"{package}.py").write_text(body, encoding="utf-8")
    return site


def env(site: Path) -> dict[str, str]:
    out = {k: v for k, v in os.environ.items() if k != "SHOAL_PLUGINS"}
    out["PYTHONPATH"] = os.pathsep.join([str(site), *filter(None, [out.get("PYTHONPATH")])])
    return out


def run(site: Path, *args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(SHOAL), *args], capture_output=True, text=True, timeout=timeout, env=env(site))


def shoal_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.strip()]


BROKEN = {
    "exits_at_import": "import sys\nsys.exit(3)\ndef register():\n    pass\n",
    "exits_in_register": "import sys\ndef register():\n    sys.exit(3)\n",
    "interrupts_in_register": "def register():\n    raise KeyboardInterrupt\n",
    "interrupts_at_import": "raise KeyboardInterrupt\n",
    "base_exception": "class Odd(BaseException):\n    pass\ndef register():\n    raise Odd('odd')\n",
    "generator_exit": "def register():\n    raise GeneratorExit\n",
    "bad_law": ("def register():\n    from shoal.engine.pso.laws import LAWS, VelocityLaw\n"
                "    LAWS.register(VelocityLaw('nope', 'Not a law', adapted=False, velocity=3))\n"),
}
WORDS = {"exits_at_import": "SystemExit", "exits_in_register": "SystemExit",
         "interrupts_in_register": "KeyboardInterrupt", "interrupts_at_import": "KeyboardInterrupt",
         "base_exception": "Odd: odd", "generator_exit": "GeneratorExit",
         "bad_law": "law 'nope' (shoal.engine.pso.laws.VelocityLaw): velocity must be callable, got 3"}


@pytest.mark.parametrize("package", sorted(BROKEN))
def test_a_broken_plugin_is_skipped_with_one_line_and_every_command_works(tmp_path, package):
    site = install(tmp_path / "site", package, BROKEN[package])
    out = run(site, "presets", "list")
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
    assert "default" in out.stdout and "course-dvc" in out.stdout
    lines = shoal_lines(out.stderr)
    assert len(lines) == 1, out.stderr
    (line,) = lines
    assert package.replace("_", "-") in line and WORDS[package] in line and "SHOAL_PLUGINS=off" in line, line
    assert "Traceback" not in out.stderr
    shown = run(site, "presets", "show", "default")
    assert shown.returncode == 0 and "[sim]" in shown.stdout and len(shoal_lines(shown.stderr)) == 1


def test_a_plugin_kind_with_a_missing_app_module_leaves_every_other_kind_and_serve_starts(tmp_path):
    body = '''
def register():
    from dataclasses import replace
    from shoal.presets.kinds import KINDS
    KINDS.register(replace(KINDS["sonar"], name="ghost", label="ghost kind", section="ghost", model=None,
                           app="ghost_app_module_that_is_not_there", detect=lambda sc: False))
'''
    site = install(tmp_path / "site", "ghost_kind", body)
    code = ("from shoal.app.kinds.registry import app_kinds, app_presets\n"
            "print(sorted(app_kinds())); print(len(app_presets()))")
    listed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env(site))
    assert listed.returncode == 0, listed.stderr[-2000:]
    kinds, presets = listed.stdout.splitlines()
    assert kinds == str(sorted(["swarm", "fleet", "sonar", "slo_swarm"])) and int(presets) > 20
    (line,) = shoal_lines(listed.stderr)
    assert "ghost kind" in line and "ghost_app_module_that_is_not_there" in line and "SHOAL_PLUGINS=off" in line

    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen([str(SHOAL), "serve", "--port", str(port)], env=env(site), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        end, page = time.monotonic() + 240, None
        while time.monotonic() < end and proc.poll() is None and page is None:
            try:
                page = urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=5).read()
            except OSError:
                time.sleep(0.5)
        assert proc.poll() is None and page, "shoal serve did not start"
    finally:
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    assert "Traceback" not in err, err[-3000:]
    assert "ghost_app_module_that_is_not_there" in err


def test_a_slow_plugin_is_named(tmp_path):
    site = install(tmp_path / "site", "slow_plugin", "import time\ntime.sleep(1.5)\ndef register():\n    pass\n")
    out = run(site, "presets", "list")
    assert out.returncode == 0 and "default" in out.stdout
    (line,) = shoal_lines(out.stderr)
    assert "slow-plugin" in line and re.search(r"took \d+\.\d s to load", line), line


def test_replacing_a_built_in_entry_says_so_naming_both(tmp_path):
    body = '''
def register():
    from dataclasses import replace
    from shoal.engine.pso.laws import LAWS
    LAWS.register(replace(LAWS["standard"], label="My standard"), replace=True)
'''
    site = install(tmp_path / "site", "replacer", body)
    out = run(site, "presets", "list")
    assert out.returncode == 0 and "default" in out.stdout
    said = out.stderr
    assert "law 'standard'" in said and "'Standard PSO'" in said and "'My standard'" in said and "replacer" in said


def test_a_real_ctrl_c_while_the_plugins_load_still_ends_the_command(tmp_path):
    site = install(tmp_path / "site", "sleepy", "import time\ntime.sleep(30)\ndef register():\n    pass\n")
    proc = subprocess.Popen([str(SHOAL), "presets", "list"], env=env(site), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    time.sleep(6)  # (the interpreter and Shoal import, then the plug-in sleeps)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "interrupted" in err and "default" not in out, (proc.returncode, err[-2000:])


@pytest.mark.parametrize("entry, words", [
    ("ObjectiveFunction('o', 'O', f='x')", "f must be callable"),
    ("ObjectiveFunction('o', 'O', f=abs, frame='sideways')", "frame must be one of"),
    ("replace(ROBOT_LAWS['rpso'], name='r', command=None)", "command must be callable"),
    ("replace(ROBOT_LAWS['rpso'], name='r', terms='3')", "terms must be int"),
    ("replace(SELECTIONS['css'], name='s', select=1)", "select must be callable"),
    ("replace(KINDS['sonar'], name='k', section='k', builder=None)", "builder must be callable"),
    ("replace(KINDS['sonar'], name='k', section='k', cost=(float('nan'), 1.0))", "cost must be"),
    ("replace(LAWS['standard'], name='l', region='round')", "region must be one of"),
])
def test_a_malformed_entry_of_every_registry_is_refused_at_registration(entry, words):
    from dataclasses import replace  # noqa: F401  (used by the entries' code)

    from shoal.engine.core.objectives import OBJECTIVES, ObjectiveFunction  # noqa: F401
    from shoal.engine.pso.laws import LAWS  # noqa: F401
    from shoal.engine.robots.laws import ROBOT_LAWS  # noqa: F401
    from shoal.engine.slo.selection import SELECTIONS  # noqa: F401
    from shoal.presets.kinds import KINDS  # noqa: F401

    made = eval(entry)  # noqa: S307 - the test's own literals
    registry = {"ObjectiveFunction": OBJECTIVES, "ROBOT_LAWS": ROBOT_LAWS, "SELECTIONS": SELECTIONS,
                "KINDS": KINDS, "LAWS": LAWS}[next(k for k in ("ObjectiveFunction", "ROBOT_LAWS", "SELECTIONS",
                                                              "KINDS", "LAWS") if k in entry)]
    before = dict(registry)
    with pytest.raises(ValueError, match=words):
        registry.register(made)
    assert dict(registry) == before


def test_a_strategy_without_update_is_refused():
    from shoal.engine.acoustics.strategies import STRATEGIES

    class NoUpdate:
        name, label, min_robots, needs, hydrophones, global_best = "nu", "No update", 3, (), 1, "best"

    with pytest.raises(ValueError, match="update must be callable"):
        STRATEGIES.register(NoUpdate)  # type: ignore[arg-type]
    assert "nu" not in STRATEGIES
