"""Where the app listens and what it writes.

- ``shoal serve`` binds to loopback unless ``--host`` says otherwise, and warns when it does;
- uploads (presets, replays) are size-limited and read in memory: nothing the client sends is
  ever written to disk, and a name the client chose (file name or preset ``name``) never
  becomes a path: downloads and ``shoal run`` folders use a sanitised stem.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from shoal.app.base_session import MAX_UPLOAD_BYTES
from shoal.app.cli import build_parser
from shoal.app.server import is_loopback, start_server
from shoal.presets import io as presets_io
from shoal.presets.io import file_stem

from app_helpers import hand_tab

EVIL_NAMES = ["../../x.toml", "/etc/passwd.toml", "..\\..\\x.json", "a\x00b.toml", "x.toml\x00.png",
              "~/.bashrc.toml", "C:\\Windows\\x.toml", "." * 300 + ".toml"]
CLI = [sys.executable, "-c", "from shoal.app.cli import main; raise SystemExit(main())"]


# ------------------------------------------------------------------ listening
def _listening_addresses(port: int) -> list[str]:
    """Local IPv4/IPv6 addresses with a listening TCP socket on ``port`` (from /proc/net)."""
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = open(table).read().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            local, state = line.split()[1], line.split()[3]
            addr, p = local.split(":")
            if state == "0A" and int(p, 16) == port:
                found.append(addr)
    return found


def test_serve_defaults_to_loopback():
    assert build_parser().parse_args(["serve"]).host == "127.0.0.1"
    if not os.path.exists("/proc/net/tcp"):
        pytest.skip("needs /proc/net/tcp to see the bound address")
    srv = start_server("default", port=0)
    try:
        addrs = _listening_addresses(srv.port)
        assert addrs and all(a in ("0100007F", "00000000000000000000000001000000") for a in addrs), addrs
    finally:
        srv.stop()


@pytest.mark.parametrize("host, loop", [("127.0.0.1", True), ("127.0.0.2", True), ("localhost", True), ("::1", True),
                                        ("0.0.0.0", False), ("::", False), ("192.168.1.10", False),
                                        ("example.org", False)])
def test_loopback_hosts_are_told_apart(host, loop):
    assert is_loopback(host) is loop


def _serve(host: str) -> tuple[str, str]:
    """Start ``shoal serve --host HOST --port 0``, wait until it is up, stop it with Ctrl-C."""
    proc = subprocess.Popen([*CLI, "serve", "--host", host, "--port", "0"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    out: list[str] = []
    reader = threading.Thread(target=lambda: out.extend(proc.stdout), daemon=True)  # type: ignore[arg-type]
    reader.start()
    try:
        end = time.monotonic() + 120
        while time.monotonic() < end and not any("Shoal is running" in line for line in out):
            assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
            time.sleep(0.1)
        assert any("Shoal is running" in line for line in out), out
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            _, err = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()
            _, err = proc.communicate()
    reader.join(timeout=10)
    return "".join(out), err


def test_serving_beyond_loopback_prints_a_warning_and_loopback_does_not():
    out, err = _serve("0.0.0.0")
    assert "warning: serving on 0.0.0.0" in err and "anyone who can reach this machine" in err
    out, err = _serve("127.0.0.1")
    assert "warning" not in err and "http://127.0.0.1:" in out


# ------------------------------------------------------------------ nothing written
class Writes:
    """Every file this process opens for writing (or creates, renames, removes) while active,
    seen through Python's audit hooks (they cannot be removed, so the hook checks a flag)."""

    def __init__(self) -> None:
        self.active = False
        self.seen: list[tuple[str, tuple]] = []
        sys.addaudithook(self._hook)

    def _hook(self, event: str, args: tuple) -> None:
        if not self.active:
            return
        if event == "open" and len(args) >= 2 and isinstance(args[0], (str, bytes, os.PathLike)):
            mode, flags = args[1], args[2] if len(args) > 2 else 0
            if (isinstance(mode, str) and any(c in mode for c in "wax+")) or (
                    isinstance(flags, int) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT)):
                self.seen.append((event, args[:2]))
        elif event in ("os.rename", "os.remove", "os.mkdir", "shutil.rmtree", "os.symlink", "os.link"):
            self.seen.append((event, args[:2]))


WRITES = Writes()


@pytest.fixture
def tab(server, tmp_path, monkeypatch):
    """A hand-ticked tab of the shared ``server`` (conftest.py), run from an empty folder."""
    monkeypatch.chdir(tmp_path)
    with hand_tab(server) as t:
        yield t


def _evil_preset(name: str, filename: str) -> bytes:
    sc = presets_io.validate({**presets_io.load("default", ["sim.robots=5"]).model_dump(mode="json"), "name": name})
    return (presets_io.to_json(sc) if filename.lower().endswith(".json") else presets_io.to_toml(sc)).encode()


def test_the_write_watch_sees_a_write(tmp_path):
    WRITES.seen.clear()
    WRITES.active = True
    try:
        (tmp_path / "seen.txt").write_text("x")
    finally:
        WRITES.active = False
    assert any(str(tmp_path) in str(args[0]) for _, args in WRITES.seen)


@pytest.mark.parametrize("filename", EVIL_NAMES)
def test_uploads_and_downloads_write_no_file_and_use_no_client_name_as_a_path(tab, tmp_path, filename):
    evil_name = "../../" + filename.replace("\x00", "")[:60]
    WRITES.seen.clear()
    WRITES.active = True
    try:
        good = tab.panels.upload_preset(filename, _evil_preset(evil_name, filename))
        tab.panels.upload_preset(filename, b"#" * (MAX_UPLOAD_BYTES + 1))
        tab.panels.upload_preset(filename, b"\x00\xff garbage")
        tab.session.step(3)
        tab.tick(1.0)
        for button in (tab.panels.export_csv, tab.panels.export_json, tab.panels.download):
            button.value = True  # a click from Python runs the same callback
        replay = getattr(tab.panels, "replay_gui", None)
        if replay is not None:
            replay.export.value = True
            replay.load(filename, tab.downloads[-1][1])
    finally:
        WRITES.active = False
    assert good, tab.messages[-1]
    assert WRITES.seen == [], WRITES.seen
    assert list(tmp_path.iterdir()) == []
    names = [name for name, _ in tab.downloads]
    assert len(names) >= 3
    for name in names:
        assert "/" not in name and "\\" not in name and "\x00" not in name and not name.startswith("."), name
        assert name.startswith(file_stem(evil_name)), name


@pytest.mark.parametrize("name", ["../../x", "/etc/cron.d/x", "a\x00b", "..", "", "x/../../y", "C:\\x"])
def test_file_stem_is_never_a_path(name):
    stem = file_stem(name)
    assert stem and all(c.isalnum() or c in "-_" for c in stem)
    assert os.path.basename(stem) == stem and stem not in (".", "..")


def test_shoal_run_puts_its_output_inside_out_whatever_the_preset_name(tmp_path):
    preset = tmp_path / "p.toml"
    text = presets_io.to_toml(presets_io.load("default", ["sim.robots=3", "sim.steps=2"]))
    preset.write_text(text.replace('name = "default"', 'name = "../../escaped"'), encoding="utf-8")
    work = tmp_path / "work"
    work.mkdir()
    out = subprocess.run([*CLI, "run", str(preset)], cwd=work, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert not (tmp_path / "escaped-seed0").exists() and not (work.parent.parent / "escaped-seed0").exists()
    made = list((work / "out").iterdir())
    assert len(made) == 1 and made[0].name.startswith("______escaped-seed") and (made[0] / "run.json").is_file()


def test_the_size_limit_is_checked_before_parsing():
    from shoal.app.base_session import parse_upload

    with pytest.raises(presets_io.PresetError, match="KiB limit"):
        parse_upload("x.json", b"{" * (MAX_UPLOAD_BYTES + 1))  # would be a nesting bomb if it were parsed
