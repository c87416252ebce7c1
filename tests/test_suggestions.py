"""A mistyped preset, field, section, kind or registered name gets a "did you mean …?" with the
closest names, in the API and in the command."""

from __future__ import annotations

import pytest

import shoal
from shoal.app.cli import main
from shoal.engine.core.objectives import OBJECTIVES
from shoal.engine.core.suggest import did_you_mean
from shoal.presets.io import PresetError

CASES = [
    (("cours-dvc",), {}, "did you mean 'course-dvc'"),
    (("course-dvc",), {"controller": {"alpah": 0.5}}, "controller.alpah: Extra inputs are not permitted (got 0.5) "
                                                      "(did you mean 'alpha'?)"),
    (("default",), {"sim": {"robtos": 3}}, "(did you mean 'robots'?)"),
    (("default",), {"controler": {"omega": 0.5}}, "(did you mean 'controller'?)"),
    (("rastrigin",), {"objective": "rastrign"}, "(got 'rastrign') (did you mean 'rastrigin'?)"),
    (("course-dvc",), {"world": {"kind": "forrest"}}, "(did you mean 'forest'?)"),
    (("default",), {"slo": {"swarm": "hots"}}, "(did you mean 'host'?)"),
]


@pytest.mark.parametrize("args, sections, hint", CASES)
def test_the_api_suggests(args, sections, hint):
    with pytest.raises(PresetError) as err:
        shoal.make(*args, **sections)
    assert hint in str(err.value)


@pytest.mark.parametrize("argv, hint", [
    (["run", "cours-dvc"], "did you mean 'course-dvc'"),
    (["run", "course-dvc", "--set", "controller.alpah=0.5"], "did you mean 'alpha'?"),
    (["run", "rastrigin", "--set", "objective.kind=rastrign"], "did you mean 'rastrigin'?"),
])
def test_the_command_suggests(argv, hint, capsys, tmp_path):
    assert main([*argv, "--out", str(tmp_path / "out")]) != 0
    assert hint in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_registry_suggests():
    with pytest.raises(ValueError, match=r"unknown 'sphear' \(did you mean 'sphere'\?\), choose from"):
        OBJECTIVES.pick("sphear")


def test_nothing_close_suggests_nothing():
    assert did_you_mean("zzzz", ["alpha", "beta"]) == "" and did_you_mean(3, ["alpha"]) == ""
    with pytest.raises(PresetError) as err:
        shoal.make("default", sim={"qqqqqq": 1})
    assert "did you mean" not in str(err.value)
