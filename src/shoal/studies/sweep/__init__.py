"""Parameter sweeps: seeded runs of a preset over a grid of field values (``shoal sweep``)."""

from .grid import Axis, SweepError
from .outcomes import CellBatch, CellJob, simulate_cell
from .run import SweepReport, run_sweep

__all__ = ["Axis", "CellBatch", "CellJob", "SweepError", "SweepReport", "run_sweep", "simulate_cell"]
