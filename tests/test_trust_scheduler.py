"""``--scheduler`` is checked, and reached with a timeout (issue 20, case 6): ``shoal serve`` and
``shoal sweep`` given a malformed, empty, closed or silent address (a port that accepts TCP
and never answers, which used to hang them for good) say so in one line within seconds, with
no traceback (Dask's ``Client.__del__`` printed one after the clear line)."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time

import pytest

from shoal.studies.experiments.schedulers import SchedulerError, scheduler_address

CLI = [sys.executable, "-m", "shoal"]


@pytest.fixture(scope="module")
def silent_port():
    """A port that accepts connections and never says a word."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(64)
    held: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                held.append(srv.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    yield srv.getsockname()[1]
    srv.close()
    for s in held:
        s.close()


@pytest.mark.parametrize("text", ["", "   ", "garbage", "tcp://", "tcp://127.0.0.1:notaport", "http://127.0.0.1:1",
                                  "tcp://127.0.0.1:0", "tcp://127.0.0.1:70000", "tcp://a b:1", "tcp://host:1/path"])
def test_malformed_addresses_are_refused_before_any_connection(text):
    with pytest.raises(SchedulerError, match="--scheduler"):
        scheduler_address(text)


@pytest.mark.parametrize("text, expect", [("127.0.0.1:8786", "tcp://127.0.0.1:8786"),
                                          (" tcp://10.0.0.2:8786 ", "tcp://10.0.0.2:8786"),
                                          ("tls://sched.example:8786", "tls://sched.example:8786"),
                                          ("tcp://[::1]:8786", "tcp://[::1]:8786")])
def test_good_addresses_pass(text, expect):
    assert scheduler_address(text) == expect


def _run(*argv: str, timeout: float = 90) -> tuple[int, str, float]:
    start = time.monotonic()
    p = subprocess.run([*CLI, *argv], capture_output=True, text=True, timeout=timeout)
    return p.returncode, p.stderr, time.monotonic() - start


@pytest.mark.parametrize("command", [["serve", "--port", "0"], ["sweep", "default", "--grid", "controller.U=6,9",
                                                                 "--steps", "5", "--runs", "1"]])
@pytest.mark.parametrize("form, words", [
    ("", "--scheduler is empty"),
    ("garbage", "expected the Dask scheduler's address"),
    ("tcp://127.0.0.1:notaport", "expected the Dask scheduler's address"),
    ("tcp://127.0.0.1:1", "cannot reach the Dask scheduler"),
    ("tcp://nonexistent.invalid:8786", "cannot reach the Dask scheduler"),
    ("tcp://127.0.0.1:{port}", "answered as a Dask scheduler within"),
])
def test_a_bad_scheduler_ends_the_command_in_seconds_with_one_line(command, form, words, silent_port, tmp_path):
    argv = [*command, "--scheduler", form.format(port=silent_port)]
    if command[0] == "sweep":
        argv += ["--out", str(tmp_path / "s")]
    code, err, took = _run(*argv)
    assert code != 0 and words in err, err[-1500:]
    assert "Traceback" not in err and "__del__" not in err, err[-1500:]
    assert took < 40, took
    if command[0] == "sweep":
        assert not (tmp_path / "s").exists()  # nothing written
