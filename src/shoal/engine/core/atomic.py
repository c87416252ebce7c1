"""Write a folder of outputs completely or not at all."""

from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any, ContextManager, Iterator


@contextmanager
def atomic_output_dir(target: Path | str) -> Iterator[Path]:
    """Yield a fresh temporary folder beside ``target``; on success it replaces ``target``.

    If the body raises (or is interrupted), the temporary folder is removed and an
    existing ``target`` is left exactly as it was.
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=target.parent))
    try:
        yield tmp
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    old = None
    if target.exists():
        old = target.with_name(f".{target.name}.old-{os.getpid()}")
        target.rename(old)
    tmp.rename(target)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


@contextmanager
def _atomic_file(target: Path | str, mode: str, **kw: Any) -> Iterator[IO[Any]]:
    """An open temporary sibling of ``target`` that replaces it when the block ends without
    error, so that readers see the old file or the whole new one, never a part."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.partial-", dir=target.parent)
    try:
        with os.fdopen(fd, mode, **kw) as f:
            yield f
        mask = os.umask(0o022)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)  # mkstemp makes it private; the result is an ordinary file
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_text_writer(target: Path | str) -> ContextManager[IO[str]]:
    """Stream UTF-8 text into ``target`` atomically (see :func:`_atomic_file`)."""
    return _atomic_file(target, "w", encoding="utf-8", newline="")


def atomic_write_bytes(target: Path | str, data: bytes) -> None:
    """Write ``data`` to ``target`` atomically (see :func:`_atomic_file`)."""
    with _atomic_file(target, "wb") as f:
        f.write(data)


def atomic_write_text(target: Path | str, text: str) -> None:
    """:func:`atomic_write_bytes` of UTF-8 text."""
    atomic_write_bytes(target, text.encode("utf-8"))
