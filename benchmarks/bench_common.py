"""Small helpers shared by the benchmark scripts: one-core pinning, timing summaries,
memory readings and markdown tables. Not a test helper: nothing here asserts speed."""

from __future__ import annotations

import os
import time
from typing import Any, Callable, Sequence

THREAD_VARS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMEXPR_NUM_THREADS",
               "VECLIB_MAXIMUM_THREADS")


def one_core() -> str:
    """Limit this process to one core: BLAS/OpenMP threads = 1 (must run before numpy is
    imported to take effect) and, where the OS allows, CPU affinity to one core.
    Returns a short description for the report."""
    for name in THREAD_VARS:
        os.environ[name] = "1"
    pinned = ""
    if hasattr(os, "sched_setaffinity"):
        try:
            cpu = min(os.sched_getaffinity(0))
            os.sched_setaffinity(0, {cpu})
            pinned = f", pinned to CPU {cpu}"
        except OSError:
            pass
    return "BLAS/OpenMP threads = 1" + pinned


def timed(fn: Callable[[], object], reps: int, warmup: int = 3) -> list[float]:
    """Wall milliseconds of ``reps`` calls of ``fn`` after ``warmup`` untimed calls."""
    return timed_cpu(fn, reps, warmup)[0]


def timed_cpu(fn: Callable[[], object], reps: int, warmup: int = 3) -> tuple[list[float], list[float]]:
    """(wall, CPU) milliseconds of ``reps`` calls of ``fn`` after ``warmup`` untimed calls.

    CPU is this thread's CPU time: what a call costs on a core of its own, even while other
    jobs share the machine and stretch the wall time."""
    for _ in range(warmup):
        fn()
    wall, cpu = [], []
    for _ in range(reps):
        c0, t0 = time.thread_time(), time.perf_counter()
        fn()
        wall.append((time.perf_counter() - t0) * 1e3)
        cpu.append((time.thread_time() - c0) * 1e3)
    return wall, cpu


def load_note() -> str:
    """The machine's load averages and core count, for the report."""
    try:
        one, five, _ = os.getloadavg()
        return f"load average {one:.1f} (1 min), {five:.1f} (5 min) on {os.cpu_count()} cores"
    except OSError:
        return f"{os.cpu_count()} cores"


def summary(ms: Sequence[float]) -> dict[str, float]:
    """Median, 95th percentile, best and mean of a list of times."""
    import numpy as np

    a = np.asarray(ms, dtype=float)
    return {"median": float(np.median(a)), "p95": float(np.percentile(a, 95)), "best": float(a.min()),
            "mean": float(a.mean())}


def rss_mib(pid: int | None = None) -> float:
    """Resident set size of a process (default: this one) in MiB, from /proc or psutil."""
    pid = os.getpid() if pid is None else pid
    try:
        with open(f"/proc/{pid}/statm") as fh:
            pages = int(fh.read().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, ValueError):
        import psutil  # not a dependency: only where /proc is missing

        return psutil.Process(pid).memory_info().rss / 2**20


def peak_rss_mib() -> float:
    """Peak resident set size of this process so far (MiB)."""
    import resource
    import sys

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 2**20 if sys.platform == "darwin" else peak / 1024


def table(header: Sequence[str], rows: Sequence[Sequence[object]], align: str | None = None) -> str:
    """A markdown table; ``align`` is one of 'l'/'r' per column (default: first left, rest right)."""
    align = align or "l" + "r" * (len(header) - 1)
    rule = ["---" if a == "l" else "---:" for a in align]
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(rule) + " |"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def fmt(x: float, digits: int = 3) -> str:
    """A number with ``digits`` significant digits, thousands kept readable."""
    if x != x:
        return "–"
    if abs(x) >= 10 ** digits:
        return f"{x:,.0f}"
    return f"{x:.{digits}g}"


def rate(x: float) -> str:
    """A rate in k/M with three significant digits."""
    if x >= 1e6:
        return f"{x / 1e6:.3g} M"
    if x >= 1e3:
        return f"{x / 1e3:.3g} k"
    return f"{x:.3g}"


def save_png(fig, path) -> None:  # type: ignore[no-untyped-def]
    """Write a matplotlib figure as a PNG, completely or not at all, and close it."""
    import io

    import matplotlib.pyplot as plt

    from shoal.engine.core.atomic import atomic_write_bytes

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    atomic_write_bytes(path, buf.getvalue())


def wait_for(cond: Any, timeout: float, what: str) -> None:
    """Poll ``cond`` until it holds; TimeoutError naming ``what`` after ``timeout`` s."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return
        time.sleep(0.05)
    raise TimeoutError(f"timed out waiting for {what}")
