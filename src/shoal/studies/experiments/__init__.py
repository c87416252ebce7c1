"""Thesis-figure reproductions and the seeded Monte-Carlo runner behind them.

``shoal reproduce TARGET`` calls :func:`reproduce`; ``--list`` prints :data:`TARGETS`.
"""

from shoal.engine.core.atomic import OutputDirError

from .registry import TARGETS, Target, reproduce
from .runner import BatchResult, Job, run_batch, run_jobs

__all__ = ["TARGETS", "BatchResult", "Job", "OutputDirError", "Target", "reproduce", "run_batch", "run_jobs"]
