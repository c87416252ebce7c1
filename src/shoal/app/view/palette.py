"""Colours that tell two things apart, and how far apart they stay for a colour-blind student.

A :class:`Cue` is how a layer draws one thing: its colour and its second cue (the glyph of its
legend entry, a dash, a width, a marker shape). A :class:`Pair` is two things a scene tells apart
(a bearing ray and its mirror, the global best and the selected robot, swarm A and swarm B):
the kinds list theirs (``AppKind.pairs``), and ``tests/test_palette.py`` checks each from the
colours the layers draw with: ΔE ≥ :data:`MIN_DELTA_E` under protan, deutan and tritan
simulation (Machado, Oliveira and Fernandes 2009, severity 1; then CIEDE2000) and a second cue
that differs. :data:`MIN_MAP_CONTRAST` is what a robot, a trail or an outline needs against every
colour of the heat map (WCAG 2.1 contrast; ``layers.Landscape``).
"""

from __future__ import annotations

from dataclasses import dataclass

Colour = tuple[int, int, int]

MIN_DELTA_E = 30.0  # CIEDE2000 between the two colours as each colour-blind simulation sees them
MIN_MAP_CONTRAST = 3.0  # WCAG contrast of a glyph against every colour of the heat map
DEFICIENCIES = ("protan", "deutan", "tritan")


@dataclass(frozen=True)
class Cue:
    """How one thing is drawn: its colour and what else sets it apart (``glyph``: its legend
    glyph; ``dash``: dashed; ``width``: line width or marker size in pixels; ``shape``: marker)."""

    colour: Colour
    glyph: str
    dash: bool = False
    width: float = 0.0
    shape: str = ""

    def second(self) -> tuple:
        """Everything but the colour."""
        return (self.glyph, self.dash, self.width, self.shape)


@dataclass(frozen=True)
class Pair:
    """Two things a scene tells apart, ``a`` and ``b``, named for the report (``what``)."""

    what: str
    a: Cue
    b: Cue


def simulate(colour: Colour, deficiency: str) -> tuple[float, float, float]:
    """``colour`` (sRGB 0–255) as a dichromat of ``deficiency`` sees it (Machado 2009, severity 1),
    clipped to what a screen shows; sRGB 0–1."""
    from coloraide import Color

    c = Color("srgb", [v / 255.0 for v in colour]).filter(deficiency, 1.0, method="machado").clip()
    r, g, b = c.coords()
    return (float(r), float(g), float(b))


def delta_e(a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    """CIEDE2000 between two sRGB colours (0–1)."""
    from coloraide import Color

    return float(Color("srgb", list(a)).delta_e(Color("srgb", list(b)), method="2000"))


def cvd_delta_e(a: Colour, b: Colour) -> float:
    """The smallest CIEDE2000 of ``a`` and ``b`` under protan, deutan and tritan simulation."""
    return min(delta_e(simulate(a, d), simulate(b, d)) for d in DEFICIENCIES)


def luminance(c: Colour) -> float:
    """WCAG 2.1 relative luminance of an sRGB colour (0–255)."""
    def f(v: float) -> float:
        v /= 255.0
        return v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4
    return 0.2126 * f(c[0]) + 0.7152 * f(c[1]) + 0.0722 * f(c[2])


def contrast(a: Colour, b: Colour) -> float:
    """WCAG 2.1 contrast ratio of two sRGB colours (0–255)."""
    x, y = luminance(a), luminance(b)
    return (max(x, y) + 0.05) / (min(x, y) + 0.05)
