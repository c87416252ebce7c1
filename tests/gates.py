"""A cell simulation that waits at a gate: lets a test hold an in-process experiment at a
chosen cell (``GATES[index]``) while it looks at the service or the page."""

from __future__ import annotations

import threading

from shoal.studies.sweep import simulate_cell

GATES: dict[int, threading.Event] = {}  # cell index → released when set
STARTED: list[int] = []  # cell indices, in the order their chunks started


def gated(job, first_run, runs):
    """``simulate_cell`` that first waits at the gate of its cell, if it has one."""
    STARTED.append(job.key)
    gate = GATES.get(job.key)
    if gate is not None:
        assert gate.wait(60), "gate never opened"
    return simulate_cell(job, first_run, runs)


def reset() -> None:
    for g in GATES.values():
        g.set()
    GATES.clear()
    STARTED.clear()
