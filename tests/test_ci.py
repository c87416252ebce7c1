"""CI runs what the README says, against the pinned versions of .ci/constraints.txt, and the pins
keep up with pyproject.toml (a dependency added without `.ci/lock` fails here)."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]
LOCK = ROOT / ".ci" / "constraints.txt"


def _bash_blocks() -> list[str]:
    return re.findall(r"```bash\n(.*?)\n```", (ROOT / "README.md").read_text(encoding="utf-8"), re.S)


def _pins() -> dict[str, str]:
    pins = {}
    for line in LOCK.read_text(encoding="utf-8").splitlines():
        if re.match(r"[A-Za-z0-9]", line):
            name, version = line.split(";")[0].strip().split("==")
            pins[canonicalize_name(name)] = version
    return pins


def test_readme_has_two_commands_and_ci_runs_the_second():
    blocks = _bash_blocks()
    assert len(blocks) == 2, "the README gives two commands: install and serve; install the test needs and test"
    ci = [line for line in (ROOT / ".ci" / "run").read_text().splitlines() if line and not line.startswith("#")]
    assert ci[-1] == blocks[1].strip(), ".ci/run runs exactly the README's test command"
    assert "-c .ci/constraints.txt" in blocks[1], "CI installs the pinned versions"


def test_every_requirement_is_pinned_within_its_bounds():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    pins = _pins()
    extras = project["optional-dependencies"]
    for spec in project["dependencies"] + extras["test"] + extras["rl"]:
        req = Requirement(spec)
        name = canonicalize_name(req.name)
        assert name in pins, f"{req.name} is not in .ci/constraints.txt: run .ci/lock"
        assert req.specifier.contains(pins[name], prereleases=True), (
            f"{req.name}=={pins[name]} in .ci/constraints.txt is outside {req.specifier}: run .ci/lock")


def test_pins_are_exact_versions():
    assert len(_pins()) > 20
    for name, version in _pins().items():
        assert re.fullmatch(r"[0-9][0-9A-Za-z.+!-]*", version), f"{name}: {version!r} is not one version"


def test_ci_installs_the_rl_extra_and_locks_it():
    """CI runs the Gymnasium and PettingZoo checks of shoal.rl, so it installs the extra, and the lock
    resolves it."""
    assert "'.[rl,test]'" in _bash_blocks()[1]
    assert "--extra rl" in (ROOT / ".ci" / "lock").read_text(encoding="utf-8")
