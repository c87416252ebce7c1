"""Colour-blind-safe drawing, from the colours the layers draw with: every pair of things a
kind's arena tells apart (``AppKind.pairs``) differs by ΔE2000 ≥ 30 under protan, deutan and
tritan simulation (Machado 2009, severity 1) and by a second cue (glyph shape, dash or width),
which its legend shows; on a heat map every robot, outline and trail of Compare's two swarms
has 3:1 against every colour of the map."""

from __future__ import annotations

import numpy as np
import pytest

from shoal.app.kinds.registry import kinds
from shoal.app.panel.view_row import SHAPES, legend_html
from shoal.app.view import layers as shared
from shoal.app.view.layers import HeatScale, Landscape, Robots, Trails, Twin
from shoal.app.view.palette import MIN_DELTA_E, MIN_MAP_CONTRAST, contrast, cvd_delta_e, simulate

KINDS = {kind.name: kind for kind in kinds()}
PAIRS = [(name, pair) for name, kind in KINDS.items() for pair in kind.pairs]


def test_every_built_in_kind_names_the_pairs_it_tells_apart():
    assert {"swarm", "fleet", "sonar", "mai"} <= set(KINDS)
    named = {pair.what for _, pair in PAIRS}
    assert {"bearing ray / mirror ray", "global best / selected robot", "Compare: A's robots / B's robots",
            "Compare: A's trail / B's trail"} <= named


def test_the_simulation_is_machados_and_changes_what_a_dichromat_confuses():
    red, green = (220, 50, 50), (30, 150, 60)
    assert cvd_delta_e(red, green) < 15 < MIN_DELTA_E  # the red/green pair issue 32 found
    assert simulate((255, 255, 255), "protan") == pytest.approx((1.0, 1.0, 1.0), abs=1e-3)  # white stays white


@pytest.mark.parametrize("kind, pair", PAIRS, ids=[f"{k}: {p.what}" for k, p in PAIRS])
def test_a_pair_differs_by_its_colour_for_a_colour_blind_student_and_by_a_second_cue(kind, pair):
    assert cvd_delta_e(pair.a.colour, pair.b.colour) >= MIN_DELTA_E, pair
    assert pair.a.second() != pair.b.second(), f"{pair.what}: colour is its only cue"
    assert pair.a.glyph in SHAPES and pair.b.glyph in SHAPES  # drawn as shapes in the legend


@pytest.mark.parametrize("kind, pair", PAIRS, ids=[f"{k}: {p.what}" for k, p in PAIRS])
def test_the_legend_of_the_kind_shows_both_sides_of_a_pair_as_the_layers_draw_them(kind, pair):
    entries = {(e.glyph, tuple(int(v) for v in e.colour)) for layer in KINDS[kind].layers(None) for e in layer.legend}
    for cue in (pair.a, pair.b):
        assert (cue.glyph, tuple(cue.colour)) in entries, (pair.what, cue)
    html = legend_html([e for layer in KINDS[kind].layers(None) for e in layer.legend])
    for cue in (pair.a, pair.b):  # the glyph's shape in its colour: the cue is on screen, not only in words
        assert "rgb(" + ",".join(str(v) for v in cue.colour) + ")" in html


def test_a_dashed_or_thinner_line_is_drawn_so():
    """The cues the pairs claim are what the layers draw: the mirror rays dashed and thinner than
    the true ones, B's trail thinner than A's, B's robots squares."""
    from shoal.app.kinds import sonar
    from shoal.app.view.shapes import dashes

    px = sonar.Rays.PX
    assert px["mirror"] < px["true"] and px["sel_mirror"] < px["sel_true"]
    cut = dashes(np.array([[[0.0, 0.0], [9.0, 0.0]]]))
    assert len(cut) == 5 and cut[0, 0, 0] == 0.0 and cut[-1, 1, 0] == 9.0 and cut[1, 0, 0] == 2.0  # gaps between
    for kind in KINDS.values():
        layer = {type(x).__name__: x for x in kind.layers(None)}
        if "Trails" in layer and "Twin" in layer:
            assert isinstance(layer["Trails"], Trails) and isinstance(layer["Twin"], Twin)
            assert layer["Twin"].px < layer["Trails"].px, kind.name


def _map() -> list[tuple[int, int, int]]:
    return [tuple(int(v) for v in c) for c in HeatScale.rgb(np.linspace(0.0, 1.0, 65))]


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_both_swarms_read_on_every_colour_of_a_heat_map(kind):
    arena = {type(x).__name__: x for x in KINDS[kind].layers(None)}
    if not any(isinstance(x, Landscape) for x in arena.values()):
        pytest.skip(f"{kind} draws no heat map")
    colours = _map()
    robots, trails, twin = arena["Robots"], arena["Trails"], arena["Twin"]
    assert isinstance(robots, Robots) and isinstance(twin, Twin)
    for what, c in (("A's robots", robots.outline or robots.colour), ("B's robots", twin.outline or shared.TWIN),
                    ("A's trail", trails.colour), ("B's trail", shared.TWIN_TRAIL)):
        worst = min(contrast(tuple(c), m) for m in colours)
        assert worst >= MIN_MAP_CONTRAST, f"{kind}: {what} {c} has {worst:.2f}:1 on the map"
