"""``shoal serve`` and the other commands refuse a bad number before anything starts, and a
connection that ends before its request is one line in the log, not a traceback."""

from __future__ import annotations

import re
import signal
import socket
import subprocess
import sys
import time

import pytest

from shoal.app.cli import main

BAD = [
    (["serve", "--port", "99999"], "--port", "from 0 to 65535"),
    (["serve", "--port", "-1"], "--port", "from 0 to 65535"),
    (["serve", "--port", "http"], "--port", "expected a whole number"),
    (["serve", "--max-sessions", "0"], "--max-sessions", "at least 1"),
    (["serve", "--experiment-workers", "0"], "--experiment-workers", "at least 1"),
    (["run", "default", "--runs", "0"], "--runs", "at least 1"),
    (["run", "default", "--steps", "-5"], "--steps", "at least 0"),
    (["run", "default", "--seed", "-1"], "--seed", "at least 0"),
    (["reproduce", "fig3-5", "--workers", "0"], "--workers", "at least 1"),
    (["reproduce", "fig3-5", "--runs", "0"], "--runs", "at least 1"),
    (["sweep", "default", "--grid", "controller.omega=0.5", "--workers", "0"], "--workers", "at least 1"),
    (["sweep", "default", "--grid", "controller.omega=0.5", "--runs", "0"], "--runs", "at least 1"),
    (["sweep", "default", "--grid", "controller.omega=0.5", "--steps", "1.5"], "--steps", "whole number"),
    (["export-replay", "default", "--out", "x.html", "--seed", "-3"], "--seed", "at least 0"),
]


@pytest.mark.parametrize("args, option, words", BAD, ids=[" ".join(a[:1] + a[-2:]) for a, _, _ in BAD])
def test_a_number_out_of_range_is_refused_before_anything_starts(args, option, words, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as stop:
        main(args)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert f"argument {option}: " in err and words in err and "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []


def test_serve_on_port_99999_fails_at_once_in_one_line():
    start = time.monotonic()
    done = subprocess.run([sys.executable, "-m", "shoal", "serve", "--port", "99999"], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2 and "must be from 0 to 65535, got 99999" in done.stderr
    assert "Traceback" not in done.stderr and time.monotonic() - start < 60


def test_serve_on_a_host_that_is_not_this_machine_fails_at_once():
    done = subprocess.run([sys.executable, "-m", "shoal", "serve", "--host", "999.1.1.1", "--port", "0"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode != 0 and done.stderr.strip().count("\n") == 0, done.stderr
    assert "--host 999.1.1.1: not an address of this machine" in done.stderr


def test_a_port_in_use_is_refused_in_one_line():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = subprocess.run([sys.executable, "-m", "shoal", "serve", "--port", str(port)], capture_output=True,
                              text=True, timeout=120)
    assert done.returncode != 0 and f"port {port} on 127.0.0.1 is already in use" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_connection_that_ends_before_its_request_is_one_line():
    server = subprocess.Popen([sys.executable, "-m", "shoal", "serve", "--port", "0"], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
    try:
        port = None
        deadline = time.monotonic() + 120
        while port is None and time.monotonic() < deadline:
            line = server.stdout.readline()
            if m := re.search(r"running at http://127\.0\.0\.1:(\d+)/", line):
                port = int(m.group(1))
        assert port is not None, "the server did not start"
        for probe in (b"", b"GET / HTTP/1.1\r\n", b"not http\r\n\r\n"):
            with socket.create_connection(("127.0.0.1", port)) as s:
                s.sendall(probe)
        time.sleep(1.0)
    finally:
        server.send_signal(signal.SIGTERM)
        _, err = server.communicate(timeout=60)
    said = [line for line in err.splitlines() if "ended before a valid request" in line]
    assert len(said) == 3, err
    assert "Traceback" not in err and "opening handshake failed" not in err, err
