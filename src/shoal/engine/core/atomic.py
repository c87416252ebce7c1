"""Write a folder of outputs completely or not at all, and never remove a file that is not ours."""

from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any, Callable, ContextManager, Iterator

PARTIAL = ".shoal-partial-"  # prefix of the temporary folder an output is written into
SHOWN = 3  # foreign entries named in a refusal


class OutputDirError(ValueError):
    """An output folder that a command may not write: not a folder, or holding files it did not write."""


@contextmanager
def _new_dir(target: Path) -> Iterator[Path]:
    """Yield a fresh temporary folder beside the absent ``target``; on success it becomes
    ``target`` (a rename: complete or absent; never onto a folder that appeared meanwhile with
    files in it). If the body raises (or is interrupted), the temporary folder is removed."""
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=target.parent))
    try:
        tmp.chmod(0o777 & ~_umask())  # mkdtemp makes it private; the result is an ordinary folder
        yield tmp
        tmp.rename(target)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def check_output_dir(target: Path | str, ours: Callable[[str], bool], command: str) -> None:
    """Refuse (:class:`OutputDirError`) a ``target`` that is not a folder or holds an entry whose
    name ``ours`` does not claim (a file ``command`` did not write)."""
    target = Path(target)
    if not target.exists():
        return
    if not target.is_dir():
        raise OutputDirError(f"--out {target}: exists and is not a folder")
    foreign = sorted(p.name for p in target.iterdir() if not (ours(p.name) or p.name.startswith(PARTIAL)))
    if foreign:
        more = f" and {len(foreign) - SHOWN} more" if len(foreign) > SHOWN else ""
        names = ", ".join(foreign[:SHOWN]) + more
        raise OutputDirError(f"--out {target}: holds files {command} did not write ({names}), which it would not "
                             "touch; choose a new or empty folder")


@contextmanager
def output_dir(target: Path | str, ours: Callable[[str], bool], command: str) -> Iterator[Path]:
    """Yield an empty temporary folder for a command's outputs; when the block ends without error
    they take their places in ``target``, completely or not at all.

    ``target`` is refused before the block runs if it holds anything ``ours`` does not claim
    (:func:`check_output_dir`). An absent ``target`` is created by renaming the finished
    folder; an existing one (``--out .`` included) receives each new
    entry by a rename, and loses only the entries of ours the new output does not have. If the
    block raises, ``target`` is as it was.
    """
    target = Path(target)
    check_output_dir(target, ours, command)
    if not target.exists():
        with _new_dir(target) as tmp:
            yield tmp
        return
    tmp = Path(tempfile.mkdtemp(prefix=PARTIAL, dir=target))
    try:
        yield tmp
        new = {p.name for p in tmp.iterdir()}
        for stale in target.iterdir():  # ours, from an earlier output
            if stale.name not in new and ours(stale.name) and not stale.name.startswith(PARTIAL):
                _remove(stale)
        for entry in tmp.iterdir():
            if (target / entry.name).is_dir() and not (target / entry.name).is_symlink():
                _remove(target / entry.name)
            os.replace(entry, target / entry.name)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


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
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes it private; the result is an ordinary file
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
