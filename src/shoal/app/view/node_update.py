"""A scene node's array (its points, its colours) sent again, at the cost of the array alone.

viser's setter (``handle.points = a``) casts every value it is given against the prop's type hint
before it compares it with what the node holds: four comparisons of ``numpy.typing`` aliases,
about 0.1 ms a call for a cloud of 20 points, every draw of every layer of every tab (a third of
what a tab's robots cost the server). :func:`set_array` does what the setter does for an array
whose dtype the node already holds (points in the node's precision, ``uint8`` colours): nothing
when the values are the same, else the values kept in the node's own buffer and one update
message with a private copy, then the node's own hook, so the page and ``handle.points`` see
exactly what the setter would give them (``tests/test_node_update.py`` compares both, message
for message). It reads viser internals (``_impl.props``, ``_impl.removed``, ``_queue_update``,
``_on_prop_assigned``: ``tests/test_internals.py``); any other value, or a viser without them,
goes through the setter.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def set_array(node: Any, name: str, value: np.ndarray) -> bool:
    """``node.<name> = value``; False when the node held it already (nothing was sent)."""
    impl = getattr(node, "_impl", None)
    props = getattr(impl, "props", None)
    held = getattr(props, name, None)
    queue = getattr(node, "_queue_update", None)
    if (not isinstance(held, np.ndarray) or not isinstance(value, np.ndarray) or held.dtype != value.dtype
            or queue is None or getattr(impl, "removed", True)):
        setattr(node, name, value)  # (viser's own way; it raises on a removed node)
        return True
    if held.shape == value.shape:
        if np.array_equal(held, value):
            return False
        held[...] = value
    else:
        setattr(props, name, value.copy())
    queue(name, value.copy())
    node._on_prop_assigned(name)
    return True
