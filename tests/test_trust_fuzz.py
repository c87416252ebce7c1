"""Fuzzing the preset loader and the ``--set`` parser (hypothesis).

Whatever comes in (random TOML documents, random dotted keys and values, random mutations of
the shipped presets), the loader either returns a valid :class:`Scenario` or raises a
:class:`PresetError` whose messages name the field by its dotted path: never a raw traceback,
a ``KeyError`` or pydantic internals.
"""

from __future__ import annotations

import json
import math
from typing import Any

import tomli_w
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from shoal.presets.io import (
    MAX_DEPTH,
    PresetError,
    apply_overrides,
    list_presets,
    load,
    parse_text,
    read_raw,
    to_toml,
    validate,
)
from shoal.presets.kinds import plugin_sections
from shoal.presets.models import Scenario

PRESETS = sorted(list_presets())
SECTIONS = tuple(Scenario.model_fields) + tuple(plugin_sections())  # the model's and the plug-in kinds' sections
INTERNALS = ("Traceback", "pydantic", "errors.pydantic.dev", "type=", "ValidationError", "KeyError")
FUZZ = settings(max_examples=150, suppress_health_check=[HealthCheck.too_slow])


def leaf_paths(data: Any, prefix: str = "") -> list[str]:
    """Dotted paths of every value (list items by index) in a raw preset dict."""
    if isinstance(data, dict):
        return [p for k, v in data.items() for p in leaf_paths(v, f"{prefix}{k}.")]
    if isinstance(data, list) and data and isinstance(data[0], dict):
        return [p for i, v in enumerate(data) for p in leaf_paths(v, f"{prefix}{i}.")]
    return [prefix[:-1]]


def check_refusal(err: PresetError, data: Any = None, path: str | None = None) -> None:
    """Messages are plain lines that each name a field: a key of the input, a section of the model
    or (with ``path``) the changed field's section."""
    assert err.messages, "a refusal says why"
    for msg in err.messages:
        assert isinstance(msg, str) and msg.strip() and len(msg) < 600, msg
        assert not any(word in msg for word in INTERNALS), msg
        head = msg.split(": ")[0]
        named = (
            (data is not None and any(msg.startswith(str(k)) for k in data))
            or any(s in msg for s in SECTIONS)
            or (path is not None and (path in msg or head in path))
            or msg.startswith(("TOML syntax", "JSON syntax", "a preset must", "--set"))
        )
        assert named, f"message names no field: {msg!r}"


def check_accepted(sc: Scenario) -> None:
    assert isinstance(sc, Scenario)
    assert validate(sc.model_dump(mode="json")) == sc
    for x in json.loads(sc.model_dump_json()).values():  # nothing non-finite slipped through
        assert "NaN" not in json.dumps(x) and "Infinity" not in json.dumps(x)


# ------------------------------------------------------------------ random values
def _finite_or_not() -> st.SearchStrategy[float]:
    return st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                     st.sampled_from([0.0, -0.0, 1e-300, 1e300, -1e300, math.inf, -math.inf, math.nan]))


scalars = st.one_of(
    st.integers(min_value=-(2**70), max_value=2**70), _finite_or_not(), st.booleans(),
    st.text(max_size=12), st.sampled_from(["raw", "physical", "dvc", "adapted-sgn", "standard", "forest", "xb-pso"]),
)
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                      st.dictionaries(st.text(max_size=8), inner, max_size=3)),
                      max_leaves=8)
keys = st.one_of(st.sampled_from(SECTIONS), st.text(min_size=1, max_size=12))
field_names = st.sampled_from(sorted({n for f in Scenario.model_fields.values()
                                      for n in getattr(f.annotation, "model_fields", {})} | {"x", "0", "omega"}))


def toml_safe(value: Any) -> bool:
    try:
        tomli_w.dumps({"v": value})
    except Exception:
        return False
    return True


# ------------------------------------------------------------------ random TOML documents
@FUZZ
@given(st.dictionaries(keys, st.one_of(values, st.dictionaries(field_names, values, max_size=5)), max_size=5))
def test_random_toml_documents_are_accepted_or_named(doc):
    assume(toml_safe(doc))
    text = tomli_w.dumps(doc)
    try:
        sc = validate(parse_text(text, "toml"))
    except PresetError as err:
        check_refusal(err, doc)
    else:
        check_accepted(sc)


@FUZZ
@given(st.text(max_size=200))
def test_random_text_is_refused_or_accepted_never_crashes(text):
    for fmt in ("toml", "json"):
        try:
            data = parse_text(text, fmt)
        except PresetError as err:
            check_refusal(err)
            continue
        try:
            sc = validate(data)
        except PresetError as err:
            check_refusal(err, data)  # e.g. text "0=0": the message names the key "0"
        else:
            check_accepted(sc)


@given(depth=st.integers(min_value=MAX_DEPTH + 1, max_value=5000), fmt=st.sampled_from(["toml", "json"]))
@settings(max_examples=20)
def test_deeply_nested_documents_are_refused_as_syntax(depth, fmt):
    text = ("a = " if fmt == "toml" else '{"a": ') + "[" * depth + "]" * depth + ("" if fmt == "toml" else "}")
    try:
        parse_text(text, fmt)
    except PresetError as err:
        assert err.messages[0].startswith(f"{fmt.upper()} syntax: nested")
    else:
        raise AssertionError("a deeply nested document was accepted")


# ------------------------------------------------------------------ --set fuzz
PATHS = sorted({p for name in PRESETS for p in leaf_paths(read_raw(name))})


@FUZZ
@given(preset=st.sampled_from(PRESETS),
       key=st.one_of(st.sampled_from(PATHS),
                     st.builds(lambda p, tail: f"{p}.{tail}", st.sampled_from(PATHS), st.text(max_size=6)),
                     st.builds(lambda a, b: f"{a}.{b}", st.sampled_from(SECTIONS), field_names),
                     st.text(max_size=16).filter(lambda k: "=" not in k)),
       value=st.one_of(st.text(max_size=16),
                       st.sampled_from(["nan", "inf", "-inf", "1e400", "0", "-1", "1" * 5000, "[" * 3000,
                                        "{a = 1}", "[1, 2, 3]", "true", '"x"', "2024-01-01", "07:00:00"])))
def test_random_dotted_overrides_are_accepted_or_name_the_field(preset, key, value):
    try:
        sc = load(preset, [f"{key}={value}"])
    except PresetError as err:
        check_refusal(err, read_raw(preset), path=key.strip())
    else:
        check_accepted(sc)


@FUZZ
@given(st.lists(st.text(max_size=20), max_size=3))
def test_any_override_strings_never_crash(items):
    try:
        apply_overrides(read_raw("default"), items)
    except PresetError as err:
        check_refusal(err, path=" ".join(items))


# ------------------------------------------------------------------ mutations of shipped presets
@st.composite
def mutated_preset(draw: st.DrawFn) -> tuple[dict[str, Any], str, str]:
    name = draw(st.sampled_from(PRESETS))
    data = read_raw(name)
    path = draw(st.sampled_from(leaf_paths(data)))
    *parents, last = path.split(".")
    node: Any = data
    for p in parents:
        node = node[int(p)] if isinstance(node, list) else node[p]
    how = draw(st.sampled_from(["replace", "delete", "sibling"]))
    if how == "replace":
        node[last] = draw(values)
    elif how == "delete":
        del node[last]
    else:  # an unknown field beside it: that one must be named
        last = draw(st.text(min_size=1, max_size=8).filter(lambda k: k not in node))
        node[last] = draw(scalars)
        path = ".".join([*parents, last])
    return data, path, how


@FUZZ
@given(mutated_preset())
def test_mutated_shipped_presets_are_accepted_or_name_the_field(case):
    data, path, how = case
    try:
        sc = validate(data)
    except PresetError as err:
        check_refusal(err, data, path=path)
        section = path.split(".")[0]
        assert any(section in m or m.startswith(section) for m in err.messages), (path, err.messages)
    else:
        check_accepted(sc)


@FUZZ
@given(mutated_preset())
def test_mutated_presets_survive_a_toml_round_trip(case):
    data, path, _ = case
    assume(toml_safe(data))
    try:
        sc = validate(parse_text(tomli_w.dumps(data), "toml"))
    except PresetError as err:
        check_refusal(err, data, path=path)
    else:
        assert validate(parse_text(to_toml(sc))) == sc


@given(st.sampled_from(PRESETS), st.sampled_from(["nan", "inf", "-inf"]))
@settings(max_examples=20)
def test_non_finite_numbers_are_refused_everywhere(preset, bad):
    """NaN and ±inf pass no field, bounded or not (e.g. the unbounded ``init.center``)."""
    data = read_raw(preset)
    floats = [p for p in leaf_paths(data) if isinstance(_get(data, p), (float, list))]
    for path in floats[:6]:
        value = _get(data, path)
        bad_value = [float(bad)] * len(value) if isinstance(value, list) else float(bad)
        try:
            load(preset, [f"{path}={json.dumps(bad_value).replace('NaN', 'nan').replace('Infinity', 'inf')}"])
        except PresetError as err:
            assert any(m.startswith(path) or path.split(".")[0] in m for m in err.messages), err.messages
        else:
            raise AssertionError(f"{preset}: {path} = {bad} was accepted")


def _get(data: Any, dotted: str) -> Any:
    for p in dotted.split("."):
        data = data[int(p)] if isinstance(data, list) else data[p]
    return data
