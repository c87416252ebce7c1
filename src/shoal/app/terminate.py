"""SIGTERM stops a command as Ctrl-C does.

Python turns SIGINT into :class:`KeyboardInterrupt`, so ``shoal serve`` tells its tabs and
frees its port, and ``shoal run`` removes its partial folder; SIGTERM (``kill``, a service
manager, a container stopping) would end the process on the spot instead. Inside
:func:`terminate_as_interrupt` it raises :class:`Terminated`, a ``KeyboardInterrupt``, so the
same clean-up runs. Worker processes forked meanwhile keep SIGTERM's usual meaning.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from typing import Any, Iterator

EXIT_TERMINATED = 128 + signal.SIGTERM


class Terminated(KeyboardInterrupt):
    """SIGTERM arrived."""


@contextlib.contextmanager
def terminate_as_interrupt() -> Iterator[None]:
    """While active (in the main thread), SIGTERM raises :class:`Terminated`."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pid = os.getpid()

    def handler(signum: int, frame: Any) -> None:
        if os.getpid() != pid:  # a forked worker: end as SIGTERM ends a process
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGTERM)
            return
        raise Terminated()

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
