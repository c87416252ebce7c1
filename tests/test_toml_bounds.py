"""TOML text is bounded before ``tomllib`` parses it (issue 20, case 2): keys, dotted parts,
nesting, key count. What a preset holds passes untouched; what only a hostile file holds is
refused, naming the line, without parsing it."""

from __future__ import annotations

import tomllib

import pytest
import tomli_w
from hypothesis import given, settings
from hypothesis import strategies as st

from shoal.presets import io as presets_io
from shoal.presets.toml_bounds import MAX_KEY_PARTS, MAX_NESTING, TomlBoundsError, check_toml
from shoal.studies.sweep.grid import parse_values

KEYS = st.text(alphabet=st.characters(codec="utf-8", exclude_categories=("Cs", "Cc")), min_size=1, max_size=12)
SCALARS = st.one_of(st.integers(), st.floats(allow_nan=False), st.booleans(), st.text(max_size=20))
TABLES = st.recursive(st.dictionaries(KEYS, SCALARS, max_size=4),
                      lambda inner: st.dictionaries(KEYS, st.one_of(inner, st.lists(SCALARS, max_size=4)), max_size=4),
                      max_leaves=20)


@pytest.mark.parametrize("name", presets_io.shipped_names())
def test_every_shipped_preset_and_its_full_dump_pass(name):
    check_toml(presets_io._files().joinpath(f"{name}.toml").read_text(encoding="utf-8"))
    check_toml(presets_io.to_toml(presets_io.load(name)))


@settings(max_examples=200)
@given(TABLES)
def test_any_shallow_toml_passes_and_parses_as_before(data):
    text = tomli_w.dumps(data)
    check_toml(text)
    assert tomllib.loads(text) == data


def test_strings_comments_floats_and_dates_are_not_keys():
    text = ('a = 1.5  # x.y.z = [[[[\nb = [1.5, 2.5e3, "x.y.z[{", \'q.r.s\']\nc = 1979-05-27T07:32:00Z\n'
            '[s."a.b".c]\nd = {e = 1, f.g = [1, {h = 2}]}\nm = """\n[[x.y.z]]\n"""\n' + "v = " + "1.0." * 40 + "\n")
    check_toml(text)


@pytest.mark.parametrize("text, words", [
    ("a" + ".a" * MAX_KEY_PARTS + " = 1", "more than 16 dotted parts (line 1)"),
    ("x = 1\n\n[" + "a." * MAX_KEY_PARTS + "a]", "more than 16 dotted parts (line 3)"),
    ("x = [\n1,\n{" + "a." * MAX_KEY_PARTS + "a = 1}]", "(line 3)"),
    ("x = " + "[" * (MAX_NESTING + 1) + "]" * (MAX_NESTING + 1), "nested deeper than 16 levels"),
    ("'" + "k" * 300 + "' = 1", "a key of 302 characters"),
])
def test_beyond_a_bound_is_refused_with_the_line(text, words):
    with pytest.raises(TomlBoundsError, match=words.replace("(", r"\(").replace(")", r"\)")):
        check_toml(text)
    with pytest.raises(presets_io.PresetError, match="TOML syntax"):
        presets_io.parse_text(text)


def test_a_typed_value_beyond_the_bounds_is_a_bare_string_never_parsed():
    hostile = "{" + "a." * 20_000 + "a = 1}"  # tomllib: minutes
    assert presets_io.parse_value(hostile) == hostile  # (then refused by the model as the field's wrong type)
    assert parse_values("1, 2, " + hostile)[2] == hostile
