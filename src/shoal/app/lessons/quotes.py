"""What an answer says about a reading, and whether the reading agrees.

A step's check names the words its answer uses for a reading (``quote``): "about 4 units",
"past 10^−25", "near 10^−5", "about 7 %". :func:`claim` reads such words as a claim about a
number, :func:`holds` says whether a value bears it out: "about N" (or near, nearly, around,
roughly, ≈) within a quarter of N, a power of ten within half a decade; "below"/"under"/"less
than" N and "above"/"over"/"more than" N as bounds, "past" N as the one away from 1 (past a
million: above; past 10^−25: below); a bare N rounds to N at its own precision; N % is a share.
``tests/test_lessons.py`` holds every shipped quote against the headless reading it quotes.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

APPROX = ("about", "near", "nearly", "around", "roughly", "≈")
BELOW = ("below", "under", "less than")
ABOVE = ("above", "over", "more than", "beyond")
_SUPER = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")
_NUMBER = re.compile(r"(?P<ten>10\s*\^\s*(?P<exp>[−\-–]?\d+)|10(?P<sup>[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+))|(?P<plain>[−\-]?\d+(?:\.\d+)?)")


@dataclass(frozen=True)
class Claim:
    """``how`` (about, below, above, exact) ``value``; ``power``: written as a power of ten;
    ``decimals``: the places an exact number is written to."""

    how: str
    value: float
    power: bool = False
    decimals: int = 0


def _how(before: str, value: float) -> str:
    words = f" {before} "
    if any(f" {h} " in words for h in APPROX):
        return "about"
    if any(f" {h} " in words for h in BELOW):
        return "below"
    if any(f" {h} " in words for h in ABOVE):
        return "above"
    if " past " in words:
        return "above" if abs(value) >= 1 else "below"
    return "exact"


def claim(words: str) -> Claim:
    """The claim of a quote, or ValueError when it says no number."""
    text = " ".join(words.lower().replace("≈", " ≈ ").split())
    m = _NUMBER.search(text)
    if m is None:
        raise ValueError(f"{words!r} quotes no number")
    share = 0.01 if text[m.end():].lstrip().startswith("%") else 1.0
    if m["ten"]:
        exp = (m["exp"] or "").replace("−", "-").replace("–", "-") if m["exp"] else m["sup"].translate(_SUPER)
        value = 10.0 ** int(exp)
        return Claim(_how(text[:m.start()], value), value * share, power=True)
    plain = m["plain"].replace("−", "-")
    decimals = len(plain.split(".")[1]) if "." in plain else 0
    value = float(plain)
    return Claim(_how(text[:m.start()], value), value * share, decimals=decimals + (2 if share != 1.0 else 0))


def holds(c: Claim, value: float) -> bool:
    """Does ``value`` bear out claim ``c``?"""
    if not math.isfinite(value):
        return False
    if c.how == "below":
        return value < c.value
    if c.how == "above":
        return value > c.value
    if c.power:
        return value > 0 and abs(math.log10(value) - math.log10(c.value)) <= 0.5
    if c.how == "about":
        return abs(value - c.value) <= 0.25 * abs(c.value)
    return round(value, c.decimals) == round(c.value, c.decimals)
