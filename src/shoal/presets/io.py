"""Reading, writing, listing and overriding presets (:class:`PresetError`, :func:`short` and
:func:`format_errors` come from :mod:`.errors`; they are offered here too)."""

from __future__ import annotations

import copy
import functools
import json
import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from shoal.engine.core.plugins import load_plugins
from shoal.engine.core.suggest import did_you_mean

from . import errors
from .errors import PresetError, fields_in, short
from .kinds import plugin_sections
from .models import Scenario
from .text import encodable, has_surrogate_escape
from .toml_bounds import check_toml


def format_errors(err: ValidationError) -> list[str]:
    """One line per error of a scenario's validation (:func:`.errors.format_errors`), a mistyped
    field or section with the closest names it could have been."""
    return errors.format_errors(err, _fields_at)


def _fields_at(loc: tuple[Any, ...]) -> list[str]:
    """The field names at ``loc`` inside a scenario: at the top its sections, the plug-in kinds'
    too; inside a plug-in kind's section, its model's."""
    sections = plugin_sections()
    if loc and loc[0] in sections and loc[0] not in Scenario.model_fields:
        return fields_in(sections[loc[0]], loc[1:])
    return fields_in(Scenario, loc) + (list(sections) if not loc else [])


def validate(data: dict[str, Any]) -> Scenario:
    try:
        return Scenario.model_validate(data)
    except ValidationError as err:
        raise PresetError(format_errors(err)) from None


def _files() -> Any:
    return resources.files("shoal.presets").joinpath("files")


def list_presets() -> dict[str, str]:
    """Shipped preset names with their one-line descriptions."""
    return {name: str(read_shipped(name).get("description", "")).split("\n")[0] for name in shipped_names()}


def parse_text(text: str, fmt: str = "toml") -> dict[str, Any]:
    """Parse TOML or JSON text into a dict, syntax errors as :class:`PresetError`. TOML is
    checked against :mod:`.toml_bounds` first (keys, dotted parts, nesting: what makes
    ``tomllib`` slow), so a hostile text costs milliseconds."""
    try:
        if fmt != "json":
            check_toml(text)
        data = json.loads(text) if fmt == "json" else tomllib.loads(text)
    except ValueError as err:  # syntax errors, bounds, and integers too long to convert
        why = "a number with thousands of digits" if "integer string conversion" in str(err) else str(err)[:200]
        raise PresetError([f"{fmt.upper()} syntax: {why}"]) from None
    except RecursionError:
        raise PresetError([f"{fmt.upper()} syntax: nested too deeply"]) from None
    if not isinstance(data, dict):
        raise PresetError(["a preset must be a table of fields"])
    if _depth(data) > MAX_DEPTH:
        raise PresetError([f"{fmt.upper()} syntax: nested deeper than {MAX_DEPTH} levels; a preset needs a few"])
    return encodable(data) if fmt == "json" and has_surrogate_escape(text) else data  # (TOML has no lone surrogate)


MAX_DEPTH = 16  # tables and arrays in a preset; the deepest shipped one has 4


def _depth(data: Any) -> int:
    """How deeply tables and arrays nest in ``data`` (no recursion: any depth is safe)."""
    deepest, stack = 0, [(data, 1)]
    while stack:
        node, level = stack.pop()
        if isinstance(node, (dict, list)):
            deepest = max(deepest, level)
            stack.extend((child, level + 1) for child in (node.values() if isinstance(node, dict) else node))
    return deepest


MAX_PRESET_NAME = 4096  # characters of a preset name or file path (PATH_MAX): longer ones are refused unread
_INSTALLED: dict[str, Any] = {}  # preset name → its file, from an installed plug-in (add_presets)


def add_presets(folder: Any) -> list[str]:
    """Offer the ``*.toml`` files of ``folder`` (a path or an ``importlib.resources`` folder of an
    installed plug-in) as presets by name, beside the shipped ones; a name already taken is
    refused (``ValueError``). Returns the names added."""
    folder = Path(folder) if isinstance(folder, str) else folder
    files = sorted((f for f in folder.iterdir() if f.name.endswith(".toml")), key=lambda f: f.name)
    names = [f.name.removesuffix(".toml") for f in files]
    taken = sorted(set(names) & set(shipped_names()))
    if taken:
        raise ValueError(f"presets {', '.join(taken)}: a preset of that name exists already")
    _INSTALLED.update(zip(names, files))
    _names.cache_clear()
    return names


@functools.lru_cache(maxsize=1)
def _names() -> tuple[str, ...]:
    load_plugins()  # (a plug-in may add presets)
    own = (f.name.removesuffix(".toml") for f in _files().iterdir() if f.name.endswith(".toml"))
    return tuple(sorted({*own, *_INSTALLED}))


def shipped_names() -> tuple[str, ...]:
    """The names of the presets shipped with Shoal (the files of ``shoal.presets``) and with the
    installed plug-ins, sorted."""
    return _names()


def read_shipped(name: str) -> dict[str, Any]:
    """The unvalidated dict of the shipped (or plug-in) preset ``name``. Only a name from
    :func:`shipped_names` is read; anything else (a path, a long or odd string) is refused
    without touching the file system."""
    if not isinstance(name, str) or name not in shipped_names():
        raise PresetError([f"no shipped preset named {short(name)} "
                           f"(shipped presets: {', '.join(shipped_names())})"])
    file = _INSTALLED.get(name) or _files().joinpath(f"{name}.toml")
    return parse_text(file.read_text(encoding="utf-8"))


def load_shipped(name: str, overrides: list[str] | None = None) -> Scenario:
    """Load a shipped preset by name (never a file path: see :func:`read_shipped`)."""
    return validate(apply_overrides(read_shipped(name), overrides or []))


def read_raw(name_or_path: str | Path) -> dict[str, Any]:
    """The unvalidated dict of a shipped preset name or a TOML/JSON file path (what a
    command-line user names; a value from the browser goes through :func:`read_shipped`)."""
    if len(str(name_or_path)) > MAX_PRESET_NAME:
        raise PresetError([f"preset name or file {short(str(name_or_path))}: longer than "
                           f"{MAX_PRESET_NAME} characters"])
    path = Path(name_or_path)
    try:
        is_file = path.suffix in (".toml", ".json") and path.is_file()
    except (OSError, ValueError):  # a name the file system cannot hold (NUL, too long a part)
        is_file = False
    if is_file:
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as err:
            raise PresetError([f"cannot read {path.name}: {err}"]) from None
        return parse_text(text, "json" if path.suffix == ".json" else "toml")
    if str(name_or_path) in shipped_names():
        return read_shipped(str(name_or_path))
    names = ", ".join(shipped_names())
    hint = did_you_mean(str(name_or_path), shipped_names())
    raise PresetError([f"no preset or file named {short(str(name_or_path))}{hint} (shipped presets: {names})"])


def parse_value(text: str) -> Any:
    """A ``--set`` value: a TOML literal (number, bool, array, quoted string) or a bare string
    (also what a text beyond :mod:`.toml_bounds` is taken as, unparsed)."""
    try:
        literal = f"v = {text}"
        check_toml(literal)
        return tomllib.loads(literal)["v"]
    except (ValueError, RecursionError):  # not a TOML literal (or one nested too deeply): a string
        return text


def set_dotted(data: dict[str, Any], key: str, value: Any) -> None:
    """Set ``data[a][b][c] = value`` for ``key = "a.b.c"`` (list items by index)."""
    parts = key.split(".")
    if not all(parts):
        raise PresetError([f"{key}: not a dotted field path"])
    node: Any = data
    for i, part in enumerate(parts[:-1]):
        where = ".".join(parts[: i + 1])
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise PresetError([f"{where}: no such list item"])
            node = node[int(part)]
        elif isinstance(node, dict):
            if node.get(part) is None:  # an absent or empty (null) section: the key creates it
                node[part] = {}
            child = node[part]
            if not isinstance(child, (dict, list)):
                raise PresetError([f"{where}: is a value, not a table, so {key} does not exist"])
            node = child
        else:
            raise PresetError([f"{where}: cannot be indexed"])
    last = parts[-1]
    if isinstance(node, list):
        if not last.isdigit() or int(last) >= len(node):
            raise PresetError([f"{key}: no such list item"])
        node[int(last)] = value
    else:
        node[last] = value


def apply_overrides(data: dict[str, Any], overrides: list[str]) -> dict[str, Any]:
    """Apply ``dotted.key=value`` strings to a copy of ``data`` (validated later, by the model)."""
    out = copy.deepcopy(data)  # (TOML dates are not JSON: no JSON round trip here)
    for item in overrides:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise PresetError([f"--set {short(item)}: expected dotted.key=value"])
        set_dotted(out, key.strip(), parse_value(value.strip()))
    return out


def load(name_or_path: str | Path, overrides: list[str] | None = None) -> Scenario:
    """Load a shipped preset or a file, apply ``--set`` overrides, validate."""
    return validate(apply_overrides(read_raw(name_or_path), overrides or []))


def file_stem(name: str) -> str:
    """A preset's ``name`` made safe as a file or folder name: letters, digits, '-' and '_'
    stay, anything else (path separators, dots, NUL) becomes '_'."""
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name) or "shoal"


def kept_fields(scenario: Scenario, section: str, **fields: Any) -> Scenario:
    """``scenario`` with ``fields`` set in ``section``, validated (:class:`PresetError` names a bad field)."""
    data = scenario.model_dump(mode="json")
    data[section] = {**data[section], **fields}
    return validate(data)


def to_toml(scenario: Scenario) -> str:
    import tomli_w  # (a run writes no TOML)

    return tomli_w.dumps(scenario.model_dump(mode="json", exclude_none=True))


def to_json(scenario: Scenario) -> str:
    return scenario.model_dump_json(indent=2)
