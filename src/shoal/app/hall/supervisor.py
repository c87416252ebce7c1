"""``shoal hall --workers N``: a class across processes, behind nginx, started and stopped as one.

:class:`Hall` makes its own folder (readable by this user alone), starts the lecture's process
and ``N`` workers on loopback ports (:mod:`.process`), writes nginx's configuration there
(:mod:`.nginx`) and starts nginx on the hall's address; then it watches them. A worker that
stops is said and started again on its port (its tabs reconnect meanwhile to the other
workers, and are told they start again); the lecture's process or nginx stopping ends the hall.

Ctrl-C or SIGTERM stops the processes (their tabs are told), then nginx, waits for each, kills
what does not stop in time, and removes the hall's folder: no process is left, and no file but
those the hall made ever existed (nginx writes its log to the hall's stderr and keeps no access
log; the keys travel to the processes on their stdin, never on a command line).

Every child process is told to stop with its parent (Linux ``PR_SET_PDEATHSIG``), so even a
killed hall leaves no server running.
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from ..server import MAX_PORT, _cannot_listen
from . import nginx, routes

READY_SECONDS = 300.0  # a process has this long to listen (a first start compiles nothing first, but loads a lot)
STOP_SECONDS = 10.0
RESTARTS = 5  # of one worker within RESTART_WINDOW; then it stays down
RESTART_WINDOW = 60.0
PR_SET_PDEATHSIG = 1


class HallError(Exception):
    """The hall cannot start or went down; the message says why."""


def _die_with_parent() -> None:  # (runs in the child between fork and exec)
    with contextlib.suppress(Exception):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


@dataclass
class Child:
    """A process of the hall: ``name``, its settings, its process and port."""

    name: str
    config: dict[str, Any]
    proc: subprocess.Popen[str] | None = None
    port: int | None = None
    restarts: list[float] = field(default_factory=list)


class Hall:
    """A lecture with ``workers`` workers behind nginx on ``host:port`` (see the module doc)."""

    def __init__(self, preset: str = "default", *, workers: int = 2, host: str = "127.0.0.1", port: int = 8080,
                 max_sessions: int = 24, max_watchers: int = 500, allow_origins: tuple[str, ...] = (),
                 say: IO[str] | None = None) -> None:
        if workers < 1:
            raise HallError(f"--workers {workers}: a hall has at least one worker")
        if not 0 < port <= MAX_PORT:
            raise HallError(f"--port {port}: a hall listens on a port from 1 to {MAX_PORT}")
        self.preset, self.workers, self.host, self.port = preset, workers, host, port
        self.max_sessions, self.max_watchers, self.allow_origins = max_sessions, max_watchers, allow_origins
        self.say = say or sys.stderr
        self.key = routes.new_key()  # the lecturer's
        self.proxy_key, self.channel_key = secrets.token_urlsafe(24), secrets.token_urlsafe(24)  # nginx's, the desk's
        self.folder: Path | None = None
        self.lecture: Child | None = None
        self.pool: list[Child] = []
        self.proxy: subprocess.Popen[bytes] | None = None
        self._stopped = False

    # ------------------------------------------------------------------ addresses
    @property
    def url(self) -> str:
        host = "127.0.0.1" if self.host in ("", "0.0.0.0", "::") else self.host
        host = f"[{host}]" if ":" in host else host
        return f"http://{host}:{self.port}/"

    @property
    def lecturer_url(self) -> str:
        return f"{self.url.rstrip('/')}{routes.LECTURER_PATH}#key={self.key}"

    def _line(self, text: str) -> None:
        print(f"shoal hall: {text}", file=self.say, flush=True)

    # ------------------------------------------------------------------ starting
    def start(self) -> None:
        """Start everything (raises :class:`HallError`, having stopped what it started)."""
        program = nginx.find()
        if program is None:
            raise HallError("nginx is not installed (Debian: apt-get install nginx)")
        if (why := _cannot_listen(self.host, self.port)) is not None:
            raise HallError(str(why))
        try:
            self.folder = Path(tempfile.mkdtemp(prefix="shoal-hall-"))  # (mode 0700)
            common = dict(preset=self.preset, max_sessions=self.max_sessions, allow_origins=list(self.allow_origins),
                          proxy_key=self.proxy_key, channel=str(self.folder / "desk.sock"),
                          channel_key=self.channel_key)
            self.lecture = Child("lecture", {**common, "role": "lecture", "key": self.key,
                                             "max_watchers": self.max_watchers})
            self._launch(self.lecture)
            self.pool = [Child(f"worker {i + 1}", {**common, "role": "worker", "index": i + 1})
                         for i in range(self.workers)]
            for child in self.pool:
                self._launch(child, wait=False)
            for child in self.pool:
                self._ready(child)
            conf = self.folder / "nginx.conf"
            conf.write_text(nginx.config(self.folder, self.host, self.port, self._port(self.lecture),
                                         [self._port(c) for c in self.pool], self.proxy_key))
            self.proxy = subprocess.Popen([program, "-e", "stderr", "-p", str(self.folder), "-c", str(conf)],
                                          stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                          preexec_fn=_die_with_parent)
            self._wait_for_proxy()
        except BaseException:
            self.stop()
            raise

    @staticmethod
    def _port(child: Child) -> int:
        assert child.port is not None
        return child.port

    def _launch(self, child: Child, *, wait: bool = True) -> None:
        """Start ``child``'s process (on its old port, when it had one) and give it its settings."""
        config = {**child.config, "port": child.port or 0}
        child.proc = subprocess.Popen([sys.executable, "-m", "shoal.app.hall.process"], stdin=subprocess.PIPE,
                                      stdout=subprocess.PIPE, text=True, preexec_fn=_die_with_parent,
                                      env={**os.environ, "PYTHONUNBUFFERED": "1"})
        assert child.proc.stdin is not None
        child.proc.stdin.write(json.dumps(config) + "\n")
        child.proc.stdin.close()
        if wait:
            self._ready(child)

    def _ready(self, child: Child) -> None:
        """Wait for ``child``'s ``{"port": N}`` line (HallError if it stops or takes too long)."""
        proc = child.proc
        assert proc is not None and proc.stdout is not None
        got: list[str] = []
        reader = threading.Thread(target=lambda: got.append(proc.stdout.readline() if proc.stdout else ""),
                                  daemon=True)
        reader.start()
        reader.join(READY_SECONDS)
        line = got[0] if got else ""
        try:
            port = int(json.loads(line)["port"])
        except (ValueError, KeyError, TypeError):
            raise HallError(f"the {child.name} process did not start" +
                            (f" (exit status {proc.poll()})" if proc.poll() is not None else "")) from None
        child.port = port
        threading.Thread(target=self._forward, args=(child, proc), daemon=True).start()

    def _forward(self, child: Child, proc: subprocess.Popen[str]) -> None:
        """What a process prints after its port, said on the hall's stdout with its name."""
        assert proc.stdout is not None
        for line in proc.stdout:
            print(f"[{child.name}] {line.rstrip()}", flush=True)

    def _wait_for_proxy(self) -> None:
        deadline = time.monotonic() + 30.0
        target = "127.0.0.1" if self.host in ("", "0.0.0.0", "::") else self.host
        while time.monotonic() < deadline:
            if self.proxy is not None and self.proxy.poll() is not None:
                raise HallError(f"nginx stopped at once (exit status {self.proxy.returncode}); its message is above")
            with contextlib.suppress(OSError), socket.create_connection((target, self.port), timeout=1.0):
                return
            time.sleep(0.1)
        raise HallError(f"nginx does not listen on port {self.port}")

    # ------------------------------------------------------------------ watching
    def check(self) -> None:
        """One look at the processes: a worker that stopped starts again (HallError if the lecture
        or nginx stopped)."""
        if self.proxy is not None and self.proxy.poll() is not None:
            raise HallError(f"nginx stopped (exit status {self.proxy.returncode}); the hall stops")
        if self.lecture is not None and self.lecture.proc is not None and self.lecture.proc.poll() is not None:
            raise HallError(f"the lecture's process stopped (exit status {self.lecture.proc.returncode}); "
                            "the hall stops")
        now = time.monotonic()
        for child in self.pool:
            if child.proc is None or child.proc.poll() is None:
                continue
            child.restarts = [t for t in child.restarts if now - t < RESTART_WINDOW]
            code = child.proc.returncode
            child.proc = None
            if len(child.restarts) >= RESTARTS:
                self._line(f"{child.name} stopped (exit status {code}) {RESTARTS} times within a minute; "
                           "it stays down, the other workers take its tabs")
                continue
            child.restarts.append(now)
            self._line(f"{child.name} stopped (exit status {code}); its tabs reconnect to the other workers. "
                       "Starting it again")
            try:
                self._launch(child)
            except HallError as err:
                self._line(str(err))

    def run(self) -> None:
        """Watch until Ctrl-C, SIGTERM or the lecture's end; then stop everything."""
        try:
            while True:
                self.check()
                time.sleep(0.5)
        finally:
            self.stop()

    # ------------------------------------------------------------------ stopping
    def stop(self) -> None:
        """Stop the processes (their tabs told), then nginx; remove the hall's folder."""
        if self._stopped:
            return
        self._stopped = True
        old = {s: signal.signal(s, signal.SIG_IGN) for s in (signal.SIGINT, signal.SIGTERM)} \
            if threading.current_thread() is threading.main_thread() else {}
        try:
            children = [c.proc for c in [*self.pool, *([self.lecture] if self.lecture else [])] if c.proc is not None]
            for proc in children:
                with contextlib.suppress(ProcessLookupError):
                    proc.terminate()
            for proc in children:
                self._reap(proc)
            if self.proxy is not None:
                with contextlib.suppress(ProcessLookupError):
                    self.proxy.terminate()
                self._reap(self.proxy)
            if self.folder is not None:
                shutil.rmtree(self.folder, ignore_errors=True)
        finally:
            for s, handler in old.items():
                signal.signal(s, handler)

    @staticmethod
    def _reap(proc: subprocess.Popen[Any]) -> None:
        try:
            proc.wait(timeout=STOP_SECONDS)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=STOP_SECONDS)


def serve_hall(preset: str = "default", *, workers: int = 2, host: str = "127.0.0.1", port: int = 8080,
               max_sessions: int = 24, max_watchers: int = 500, allow_origins: tuple[str, ...] = ()) -> None:
    """``shoal hall``: the first line printed is the lecturer's address (its key is printed nowhere
    else), the second the class's."""
    hall = Hall(preset, workers=workers, host=host, port=port, max_sessions=max_sessions,
                max_watchers=max_watchers, allow_origins=allow_origins)
    try:
        hall.start()
    except HallError as err:
        raise SystemExit(f"shoal hall: {err}") from None
    from .command import class_hint

    print(f"lecturer: {hall.lecturer_url}  (keep it to yourself: it drives the class's run)", flush=True)
    print(f"class:    {hall.url}  {class_hint(host, port)}".rstrip(), flush=True)
    ports = ", ".join(str(c.port) for c in hall.pool)
    print(f"Shoal's lecture hall of {preset} is running (Ctrl-C to stop): nginx on port {port}, the lecture on "
          f"loopback port {hall.lecture.port if hall.lecture else '?'}, {workers} worker"
          f"{'' if workers == 1 else 's'} on {ports}", flush=True)
    try:
        hall.run()
    except HallError as err:
        raise SystemExit(f"shoal hall: {err}") from None
    except KeyboardInterrupt:
        print("\nstopping", flush=True)
        hall.stop()
