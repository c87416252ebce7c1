"""The example plug-in (``examples/plugin``) installed for the tests: ``pip install --target`` into
a temporary folder (no build isolation, no dependencies: a second or two), then used by child
processes whose ``PYTHONPATH`` holds that folder. The test process itself stays without it, so
every other test sees Shoal's own registries only."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plugin"


def install_example(target: Path) -> Path:
    """Install the example plug-in into ``target``; returns ``target``."""
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
                           "--no-index", "--target", str(target), str(EXAMPLE)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    return target


def plugin_env(target: Path, **extra: str) -> dict[str, str]:
    """The environment of a child process that has the example plug-in installed."""
    env = {k: v for k, v in os.environ.items() if k != "SHOAL_PLUGINS"}
    env["PYTHONPATH"] = os.pathsep.join([str(target), *filter(None, [env.get("PYTHONPATH")])])
    return {**env, **extra}


def python(target: Path, code: str, **extra: str) -> subprocess.CompletedProcess[str]:
    """Run ``code`` in a child interpreter with the plug-in installed."""
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600,
                          env=plugin_env(target, **extra))


def shoal(target: Path, *args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """Run the ``shoal`` command in a child process with the plug-in installed."""
    code = "import sys; from shoal.app.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=600,
                          env=plugin_env(target), cwd=cwd)
