"""A preset uploaded from the browser: size, encoding and format checked before the model."""

from __future__ import annotations

from shoal.presets import io as presets_io
from shoal.presets.io import PresetError
from shoal.presets.models import Scenario

MAX_UPLOAD_BYTES = 256 * 1024


def parse_upload(filename: str, content: bytes) -> Scenario:
    """A validated scenario from an uploaded TOML/JSON preset, or :class:`PresetError`."""
    if len(content) > MAX_UPLOAD_BYTES:
        raise PresetError([f"{filename}: {len(content) / 1024:.0f} KiB is larger than the "
                           f"{MAX_UPLOAD_BYTES // 1024} KiB limit for a preset"])
    try:
        text = content.decode("utf-8")
    except UnicodeDecodeError:
        raise PresetError([f"{filename}: not UTF-8 text"]) from None
    lower = filename.lower()
    if lower.endswith(".json"):
        kind = "json"
    elif lower.endswith(".toml"):
        kind = "toml"
    else:  # no telling extension: JSON starts with '{'
        kind = "json" if text.lstrip().startswith("{") else "toml"
    return presets_io.validate(presets_io.parse_text(text, kind))
