"""Where each preset value comes from: stated, read, fitted or ours (shoal.presets.marks),
in the preset model, in ``shoal presets show`` and in the app's notes."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from shoal.presets import marks
from shoal.presets.io import load, shipped_names

READINGS = (Path(__file__).parents[1] / "docs" / "readings.md").read_text(encoding="utf-8")
HEADINGS = set(re.findall(r"^#+ (.+)$", READINGS, re.M))


@pytest.mark.parametrize("name", marks.THESIS_PRESETS)
def test_every_value_of_a_thesis_preset_is_marked(name):
    unmarked = [p for p, m in load(name).marks().items() if m is None]
    assert not unmarked, f"{name}: unmarked {unmarked}"


def test_the_thesis_presets_are_shipped_and_sandbox_values_are_ours():
    assert set(marks.THESIS_PRESETS) <= set(shipped_names())
    sandbox = load("rastrigin").marks()
    assert all(m is not None for m in sandbox.values())
    assert sandbox["init.spread"] == marks.SANDBOX


def test_a_read_or_fitted_mark_names_a_section_of_the_readings():
    for rule in marks.RULES:
        m = rule.mark
        assert m.kind in marks.KINDS and m.source
        if m.kind in ("read", "fitted"):
            heading = re.fullmatch(r'docs/readings\.md, "(.+)"', m.source)
            assert heading and heading.group(1) in HEADINGS, f"{rule.path}: {m.source}"
        if m.kind == "fitted":
            assert m.evidence, rule.path


def test_the_fitted_values_are_the_chapter_7_receiver_and_split():
    fitted = {p for name in marks.THESIS_PRESETS for p, m in load(name).marks().items() if m and m.kind == "fitted"}
    assert fitted == {"acoustics.fs", "acoustics.lag_peak", "acoustics.c1_share"}
    ch8 = load("sonar-gt-pso").marks()
    assert ch8["acoustics.c1_share"].kind == "stated" and "Algorithm 2" in ch8["acoustics.c1_share"].source


def test_one_receiver_per_algorithm_across_chapters_7_and_8():
    receiver: dict[str, set] = {}
    for name in marks.THESIS_PRESETS:
        a = load(name).acoustics
        if a is not None and a.algorithm in ("x-pso", "b-pso", "xb-pso"):
            receiver.setdefault(a.algorithm, set()).add((a.lag_peak, a.fs))
    # sonar-gt-pso's XB-PSO cases (Fig. 8-2) hear with the same receiver
    gt = load("sonar-gt-pso").acoustics
    receiver.setdefault("xb-pso", set()).add((gt.lag_peak, gt.fs))
    assert receiver and all(len(r) == 1 for r in receiver.values()), receiver


def test_a_mark_belongs_to_a_value():
    fs = dict(load("sonar-xb-pso", ["acoustics.fs=48000"]).marks())
    assert fs["acoustics.fs"] is None  # no rule vouches for another sample rate in a thesis preset
    assert load("slo-walk", ["slo.entry_policy=dead_reckoning"]).marks()["slo.entry_policy"].kind == "ours"


def test_presets_show_lists_the_marks_and_stays_a_valid_preset(tmp_path):
    out = subprocess.run([sys.executable, "-m", "shoal", "presets", "show", "sonar-xb-pso"], capture_output=True,
                         text=True, check=True).stdout
    assert "acoustics.c1_share" in out and re.search(r"acoustics\.fs\s+= 4000\.0\s+-> fitted", out)
    assert "-> stated: Rossides Table 7.1" in out and "UNMARKED" not in out
    (tmp_path / "again.toml").write_text(out, encoding="utf-8")
    assert load(str(tmp_path / "again.toml")).acoustics.fs == 4000.0
