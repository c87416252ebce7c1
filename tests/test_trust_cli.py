"""The commands stop cleanly: folders that cannot be written, SIGTERM, two sweeps at once.

- ``shoal run``, ``sweep`` and ``reproduce`` into a folder that cannot be written (read-only,
  a path under a file, a full disk) print one line naming the folder and the reason, exit 1
  and leave nothing behind. A read-only file system and a full disk are simulated with an
  audit hook in the child process (it makes ``mkdir`` or the first file opened for writing
  there fail with ``EROFS`` / ``ENOSPC``, as the kernel would); a path under a file and,
  when the tests do not run as root, a folder without write permission are real.
- SIGTERM stops ``shoal serve`` as Ctrl-C does (tabs told, port released, exit 0) and makes
  ``shoal run`` remove its partial folder as Ctrl-C does.
- A second ``shoal sweep`` into a folder that one is writing is refused by its lock file.
"""

from __future__ import annotations

import errno
import os
import resource
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from shoal.studies.sweep import SweepError
from shoal.studies.sweep.store import SweepDir

from browser.browser_helpers import wait_until  # noqa: E402  (tests/ is on sys.path)
from viser_wire import WireClient

# The child: optionally make writes under ROOT fail with ERRNO at WHEN ("mkdir": making any
# folder there; "write": opening any file there for writing), then run the CLI.
CHILD = """
import os, sys
root, err, when, *argv = sys.argv[1:]
WRITE = os.O_WRONLY | os.O_RDWR | os.O_CREAT

def writes(args):
    mode, flags = (args[1] if len(args) > 1 else None), (args[2] if len(args) > 2 else 0)
    return (isinstance(mode, str) and any(c in mode for c in "wax+")) or bool(isinstance(flags, int) and flags & WRITE)

def hook(event, args):
    if root == "-" or not args or not isinstance(args[0], (str, bytes, os.PathLike)):
        return
    if not os.path.abspath(os.fsdecode(args[0])).startswith(root):
        return
    if (event == "os.mkdir" and when == "mkdir") or (event == "open" and writes(args)):
        raise OSError(int(err), os.strerror(int(err)), os.fsdecode(args[0]))

sys.addaudithook(hook)
from shoal.app.cli import main
raise SystemExit(main(argv))
"""


def shoal(*argv: str, fail_under: Path | None = None, err: int = 0, when: str = "write",
          timeout: float = 300) -> subprocess.CompletedProcess:
    root = str(fail_under) if fail_under else "-"
    return subprocess.run([sys.executable, "-c", CHILD, root, str(err), when, *argv], capture_output=True,
                          text=True, timeout=timeout)


COMMANDS = {
    "run": lambda out: ["run", "default", "--steps", "20", "--out", str(out)],
    "sweep": lambda out: ["sweep", "default", "--grid", "controller.U=6,8", "--runs", "1", "--steps", "10",
                          "--out", str(out)],
    "reproduce": lambda out: ["reproduce", "fig3-5", "--runs", "1", "--out", str(out)],
}


def _one_line_naming(res: subprocess.CompletedProcess, out: Path, reason: str) -> None:
    assert res.returncode == 1, (res.returncode, res.stderr[-2000:])
    lines = [line for line in res.stderr.splitlines() if line.startswith("shoal: error")]
    assert lines == [f"shoal: error: cannot write {out}: {reason}"], res.stderr[-2000:]
    assert "Traceback" not in res.stderr


@pytest.mark.parametrize("command", COMMANDS)
def test_a_read_only_folder_is_named_with_the_reason(tmp_path, command):
    place = tmp_path / "mounted"
    place.mkdir()
    out = place / "out"
    res = shoal(*COMMANDS[command](out), fail_under=place, err=errno.EROFS, when="mkdir")
    _one_line_naming(res, out, "Read-only file system")
    assert list(place.iterdir()) == []


@pytest.mark.parametrize("command", COMMANDS)
def test_a_full_disk_is_named_and_nothing_is_left_half_written(tmp_path, command):
    out = tmp_path / "out"
    res = shoal(*COMMANDS[command](out), fail_under=tmp_path, err=errno.ENOSPC, when="write")
    _one_line_naming(res, out, "No space left on device")
    assert list(tmp_path.iterdir()) == []  # no partial folder or file


@pytest.mark.parametrize("command", COMMANDS)
def test_a_path_under_a_file_is_named_with_the_reason(tmp_path, command):
    (tmp_path / "notes.txt").write_text("a file, not a folder\n")
    out = tmp_path / "notes.txt" / "sub" / "out"
    _one_line_naming(shoal(*COMMANDS[command](out)), out, "Not a directory")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]


@pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_folder_without_write_permission_is_named(tmp_path):
    place = tmp_path / "locked"
    place.mkdir()
    place.chmod(0o555)
    try:
        res = shoal(*COMMANDS["run"](place / "out"))
        _one_line_naming(res, place / "out", "Permission denied")
    finally:
        place.chmod(0o755)


def test_run_names_a_world_that_cannot_be_laid_out_and_a_scene_too_big_for_memory(tmp_path):
    res = shoal("run", "course-dvc", "--set", "world.width=5.5", "--steps", "2", "--out", str(tmp_path / "w"))
    assert res.returncode == 2 and "world.width: must exceed start_size" in res.stderr and "Traceback" not in res.stderr
    limited = subprocess.run([sys.executable, "-c", CHILD, "-", "0", "-", "run", "slo-walk", "--set",
                              "sim.robots=100000", "--steps", "2", "--out", str(tmp_path / "big")],
                             capture_output=True, text=True, timeout=300,
                             preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (6 * 2**30, 6 * 2**30)))
    assert limited.returncode == 1 and "Traceback" not in limited.stderr, limited.stderr[-2000:]
    assert "not enough memory for slo-walk with sim.robots = 100000" in limited.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", ["run", "sweep", "serve", "presets"])
def test_a_preset_name_of_100000_characters_is_refused_in_a_line(command, tmp_path):
    name = "x" * 100_000
    argv = {"run": ["run", name, "--out", str(tmp_path / "o")], "sweep": ["sweep", name, "--grid", "sim.seed=1,2"],
            "serve": ["serve", "--preset", name, "--port", "0"], "presets": ["presets", "show", name]}[command]
    res = shoal(*argv)
    assert res.returncode in (1, 2) and "longer than 4096 characters" in res.stderr, res.stderr[-500:]
    assert "Traceback" not in res.stderr and len(res.stderr) < 1000


# ------------------------------------------------------------------ SIGTERM
def _start(*argv: str) -> tuple[subprocess.Popen, list[str]]:
    proc = subprocess.Popen([sys.executable, "-c", CHILD, "-", "0", "-", *argv], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    lines: list[str] = []
    threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True).start()  # type: ignore[arg-type]
    return proc, lines


def test_sigterm_stops_serve_as_ctrl_c_does(tmp_path):
    proc, lines = _start("serve", "--port", "0")
    try:
        url = wait_until(lambda: next((line.split()[4] for line in lines if "Shoal is running" in line), None),
                         timeout=120, what="the server to start")
        port = int(url.rstrip("/").rsplit(":", 1)[1])
        client = WireClient(port, decode=True)
        wait_until(lambda: client.uuid_of("preset"), what="the tab's panels")
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=60)
        err = proc.stderr.read() if proc.stderr else ""
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err[-2000:]
    wait_until(lambda: any("stopping" in line for line in lines), what="'stopping' on stdout")
    assert "Traceback" not in err
    wait_until(lambda: client.closed.is_set(), what="the tab's connection to close")
    assert client.saw("This Shoal server has stopped")
    with socket.socket() as s:  # the port is free again
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind(("127.0.0.1", port))


@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_sigterm_to_run_removes_the_partial_folder_as_sigint_does(tmp_path, sig, code):
    out = tmp_path / "long"
    proc = subprocess.Popen([sys.executable, "-c", CHILD, "-", "0", "-", "run", "default", "--steps", "10000000",
                             "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        wait_until(lambda: any(p.name.startswith(".long.partial-") for p in tmp_path.iterdir()), timeout=120,
                   what="the run's partial folder")
        time.sleep(0.5)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == code and "Traceback" not in err, err[-2000:]
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ two sweeps into one folder
def test_a_second_sweep_into_a_folder_being_written_is_refused(tmp_path):
    out = tmp_path / "sweep"
    argv = ["sweep", "default", "--grid", "sim.steps=5,10000000", "--runs", "1", "--out", str(out)]
    first = subprocess.Popen([sys.executable, "-c", CHILD, "-", "0", "-", *argv], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        wait_until(lambda: (out / "cells" / "cell-00000.csv").exists(), timeout=120, what="the first sweep's cell 0")
        second = shoal(*argv)
        assert second.returncode == 2 and "another shoal sweep is writing into it" in second.stderr, second.stderr
        assert sorted(p.name for p in (out / "cells").iterdir()) == ["cell-00000.csv"]
        first.send_signal(signal.SIGINT)
        first.communicate(timeout=60)
    finally:
        if first.poll() is None:
            first.kill()
    assert first.returncode == 130


def test_the_sweep_lock_is_held_only_while_a_sweep_runs(tmp_path):
    store = SweepDir(tmp_path / "s")
    with store.locked():
        with pytest.raises(SweepError, match="another shoal sweep"):
            with SweepDir(tmp_path / "s").locked():
                pass
    with SweepDir(tmp_path / "s").locked():  # free again
        pass
    assert not (tmp_path / "s").exists()  # nothing was written: the folder made for the lock goes again


def test_validate_refuses_what_run_refuses_with_the_same_words(tmp_path):
    """A forest 7 m wide was valid for ``presets validate`` and refused by ``run``: one set of rules."""
    import shoal.presets.io as presets_io

    forest = tmp_path / "narrow.toml"
    forest.write_text(presets_io.to_toml(presets_io.load("forest-dvc", ["world.width=7"])), encoding="utf-8")
    checked = shoal("presets", "validate", str(forest))
    ran = shoal("run", str(forest), "--steps", "2", "--out", str(tmp_path / "o"))
    assert checked.returncode == 1 and "world.width: must be > 12 m" in checked.stderr, checked.stderr
    assert ran.returncode == 2 and "world.width: must be > 12 m" in ran.stderr, ran.stderr
    assert not (tmp_path / "o").exists()
    assert shoal("presets", "validate", "forest-dvc").returncode == 0


@pytest.mark.parametrize("argv", [["presets", "show", "default"], ["presets", "list"],
                                  ["presets", "validate", "default"], ["reproduce", "--list"]])
def test_a_reader_that_goes_away_ends_the_command_quietly(argv):
    """``shoal presets show default | head -1``: a BrokenPipe traceback before."""
    read, write = os.pipe()
    proc = subprocess.Popen([sys.executable, "-c", CHILD, "-", "0", "-", *argv], stdout=write, stderr=subprocess.PIPE)
    os.close(write)
    os.close(read)  # the reader is gone before the command prints (as head is, after its lines)
    _, err = proc.communicate(timeout=120)
    text = err.decode()
    assert "Traceback" not in text and "BrokenPipe" not in text and "Exception ignored" not in text, text[-2000:]
    assert proc.returncode == 141, (proc.returncode, text)  # as a command SIGPIPE ended
