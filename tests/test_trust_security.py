"""Where the app listens, who may talk to it, what it reads and what it writes.

- ``shoal serve`` binds to loopback unless ``--host`` says otherwise, and warns when it does;
- only the server's own pages get a session: a websocket upgrade or HTTP request whose
  ``Origin`` or ``Host`` is another site's is refused (403) before viser sees it, unless
  ``--allow-origin`` names it;
- a value from the browser never becomes a file path: the preset dropdown loads only the
  shipped presets and those uploaded into that tab (held in memory), and anything else is
  refused without touching the file system or echoing a file;
- uploads (presets, replays) are size-limited and read in memory: nothing the client sends is
  ever written to disk, and a name the client chose (file name or preset ``name``) never
  becomes a path: downloads and ``shoal run`` folders use a sanitised stem.

The hostile messages go over a real websocket (``viser_wire.WireClient``), as a client that
is not a browser would send them.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request

import pytest
from websockets.exceptions import InvalidStatus

from shoal.app.cli import build_parser
from shoal.app.server import is_loopback, start_server
from shoal.app.session.upload import MAX_UPLOAD_BYTES
from shoal.presets import io as presets_io
from shoal.presets.io import PresetError, file_stem

from app_helpers import hand_tab
from browser.browser_helpers import wait_until  # noqa: E402  (tests/ is on sys.path)
from viser_wire import WireClient

EVIL_NAMES = ["../../x.toml", "/etc/passwd.toml", "..\\..\\x.json", "a\x00b.toml", "x.toml\x00.png",
              "~/.bashrc.toml", "C:\\Windows\\x.toml", "." * 300 + ".toml"]
CLI = [sys.executable, "-m", "shoal"]


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
    from shoal.app.session.upload import parse_upload

    with pytest.raises(presets_io.PresetError, match="KiB limit"):
        parse_upload("x.json", b"{" * (MAX_UPLOAD_BYTES + 1))  # would be a nesting bomb if it were parsed


# ------------------------------------------------------------------ the preset dropdown is no path
class Touches:
    """Every path under ``root`` this process opens (any mode) or lists while active (audit hooks)."""

    def __init__(self) -> None:
        self.root: str | None = None
        self.seen: list[tuple[str, str]] = []
        sys.addaudithook(self._hook)

    def _hook(self, event: str, args: tuple) -> None:
        if self.root is None or event not in ("open", "os.listdir", "os.scandir", "os.mkdir", "os.remove"):
            return
        path = args[0] if args else None
        if isinstance(path, (str, bytes, os.PathLike)) and str(os.fsdecode(path)).startswith(self.root):
            self.seen.append((event, os.fsdecode(path)))


TOUCHES = Touches()
TOKEN = "api-token-0123456789"


@pytest.fixture
def secrets(tmp_path, monkeypatch):
    """A folder of files a hostile page would like to read, and the process run from deep below it."""
    folder = tmp_path / "private"
    folder.mkdir()
    (folder / "secret.json").write_text(json.dumps({"api_token": TOKEN}), encoding="utf-8")
    (folder / "secret.toml").write_text(f'api_token = "{TOKEN}"\n', encoding="utf-8")
    (folder / "valid.toml").write_text(presets_io.to_toml(presets_io.load("default", ["sim.robots=3"]))
                                       .replace('name = "default"', 'name = "stolen"'), encoding="utf-8")
    deep = tmp_path / "a" / "b" / "c" / "d"
    deep.mkdir(parents=True)
    monkeypatch.chdir(deep)
    TOUCHES.seen.clear()
    TOUCHES.root = str(folder)
    yield folder
    TOUCHES.root = None


def _hostile_choices(folder) -> list[str]:
    return [str(folder / "secret.json"), str(folder / "secret.toml"), str(folder / "valid.toml"),
            str(folder / "secret"), "../../../../private/secret.json", "../../../../private/valid.toml",
            "../../../../private/valid", "default.toml", "default/../default", "./default", "x" * 100_000,
            "default\x00", "~/.ssh/id_rsa"]


def test_the_shipped_loader_takes_only_shipped_names(secrets):
    for choice in _hostile_choices(secrets):
        with pytest.raises(PresetError, match="no shipped preset named") as err:
            presets_io.load_shipped(choice)
        assert TOKEN not in str(err.value) and len(str(err.value)) < 1500
    assert TOUCHES.seen == []
    assert presets_io.load_shipped("rastrigin").name == "rastrigin"


def test_a_command_line_user_may_still_name_a_file(secrets):
    assert presets_io.load(str(secrets / "valid.toml")).name == "stolen"
    with pytest.raises(PresetError, match="longer than 4096 characters"):
        presets_io.load("x" * 100_000)
    with pytest.raises(PresetError, match="no preset or file named"):
        presets_io.load("y" * 300 + ".toml")  # a name the file system cannot hold: no OSError


def test_the_panels_refuse_a_path_as_a_preset_choice(tab, secrets):
    """The panel's own check, behind the input guard: a value that reached it is still only a choice."""
    scenario = tab.session.scenario
    for choice in _hostile_choices(secrets):
        assert not tab.panels.load_preset(choice)
        title, body, color = tab.messages[-1]
        assert color == "red" and "not one of this tab's presets" in body and TOKEN not in body, body
        assert len(body) < 300
    assert tab.session.scenario is scenario and TOUCHES.seen == []


# ------------------------------------------------------------------ origins and hosts
def _refused(port: int, **headers) -> int:
    with pytest.raises(InvalidStatus) as err:
        WireClient(port, decode=True, **headers)
    return err.value.response.status_code


FOREIGN = [dict(origin="http://evil.example"), dict(origin="null"), dict(origin="http://localhost:1"),
           dict(origin="https://127.0.0.1"), dict(host="evil.example"),
           dict(origin="http://rebound.example:{port}", host="rebound.example:{port}")]


@pytest.mark.parametrize("headers", FOREIGN, ids=lambda h: ",".join(f"{k}={v}" for k, v in h.items()))
def test_a_foreign_origin_or_host_gets_no_session_and_no_messages(server, headers, capfd):
    headers = {k: v.format(port=server.port) for k, v in headers.items()}
    assert _refused(server.port, **headers) == 403
    time.sleep(0.3)
    assert not server.tabs and not server.turned_away and not server.viser.get_clients()
    assert "refused a connection" in capfd.readouterr().err


@pytest.mark.parametrize("origin", ["http://127.0.0.1:{port}", "http://localhost:{port}", "http://[::1]:{port}", None])
def test_the_servers_own_pages_and_plain_clients_get_a_session(server, origin):
    client = WireClient(server.port, origin=origin and origin.format(port=server.port))
    try:
        wait_until(lambda: len(server.tabs) == 1, what="a session")
    finally:
        client.close()
    wait_until(lambda: not server.tabs, what="the session to go")


def test_a_page_reached_through_a_tunnel_is_its_own_origin(server):
    """``ssh -L 9000:localhost:PORT``: the page is http://localhost:9000 and its websocket says so."""
    client = WireClient(server.port, origin="http://localhost:9000", host="localhost:9000")
    try:
        wait_until(lambda: len(server.tabs) == 1, what="a session")
    finally:
        client.close()
    assert _refused(server.port, origin="http://localhost:9000", host=f"localhost:{server.port}") == 403


def _get(port: int, **headers) -> int:
    request = urllib.request.Request(f"http://127.0.0.1:{port}/", headers=headers)
    try:
        with urllib.request.urlopen(request, timeout=30) as r:
            return r.status
    except urllib.error.HTTPError as err:
        return err.code


def test_http_requests_of_foreign_hosts_or_origins_are_refused(server):
    assert _get(server.port) == 200
    assert _get(server.port, Host=f"localhost:{server.port}") == 200
    assert _get(server.port, Host=f"rebound.example:{server.port}") == 403  # DNS rebinding
    assert _get(server.port, Origin="http://evil.example") == 403


def test_allow_origin_lets_a_named_origin_in_and_no_other():
    srv = start_server("default", port=0, allow_origins=("https://shoal.example.org",))
    try:
        client = WireClient(srv.port, origin="https://shoal.example.org", host="shoal.example.org")
        try:
            wait_until(lambda: len(srv.tabs) == 1, what="a session through the allowed origin")
        finally:
            client.close()
        assert _refused(srv.port, origin="https://other.example.org", host="shoal.example.org") == 403
        assert _refused(srv.port, origin="https://shoal.example.org", host="other.example.org") == 403
    finally:
        srv.stop()


def test_allow_origin_is_a_checked_serve_option():
    args = build_parser().parse_args(["serve", "--allow-origin", "http://a.lan:8080", "--allow-origin", "https://b"])
    assert args.allow_origin == ["http://a.lan:8080", "https://b"]
    out = subprocess.run([*CLI, "serve", "--port", "0", "--allow-origin", "evil.example"], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 2 and "--allow-origin 'evil.example': expected an origin" in out.stderr


# ------------------------------------------------------------------ hostile choices over the wire
def test_hostile_dropdown_values_over_the_wire_read_no_file(server, secrets, capfd):
    client = WireClient(server.port, decode=True)
    try:
        wait_until(lambda: client.uuid_of("preset") and len(server.tabs) == 1, what="the tab's preset dropdown")
        session = next(iter(server.sessions.values()))
        scenario = session.scenario
        for choice in _hostile_choices(secrets):
            before = len(client.notifications())
            client.set_value("preset", choice)
            wait_until(lambda n=before: len(client.notifications()) > n, what=f"the refusal of {choice[:40]!r}")
            title, body, color = client.notifications()[-1]
            assert color == "red" and "not one of the choices" in body, (title, body)
            wait_until(lambda: client.value_of(client.uuid_of("preset")) == "default", what="the dropdown back")
        assert next(iter(server.sessions.values())) is session and session.scenario is scenario
        assert not any(TOKEN in t or "stolen" in t for t in client.texts)
        assert TOUCHES.seen == [], TOUCHES.seen
    finally:
        client.close()
    assert "Traceback" not in capfd.readouterr().err


def test_an_uploaded_preset_stays_a_choice_of_its_tab_only(server):
    data = presets_io.to_toml(presets_io.load("rastrigin", ["sim.robots=7"])).replace(
        'name = "rastrigin"', 'name = "mine"').encode()
    a, b = WireClient(server.port, decode=True), WireClient(server.port, decode=True)
    try:
        wait_until(lambda: a.uuid_of("Upload preset") and b.uuid_of("Upload preset") and len(server.tabs) == 2,
                   what="two tabs")
        cid_a, cid_b = sorted(server.tabs)  # (the tabs' ids in the order they connected)
        a.upload("Upload preset", "mine.toml", data)
        wait_until(lambda: server.sessions[cid_a].scenario.name == "mine", what="the upload loaded")
        wait_until(lambda: a.value_of(a.uuid_of("preset")) == "mine (uploaded)", what="the upload shown as a choice")
        a.set_value("preset", "default")
        wait_until(lambda: server.sessions[cid_a].scenario.name == "default", what="back to default")
        a.set_value("preset", "mine (uploaded)")
        wait_until(lambda: server.sessions[cid_a].scenario.name == "mine" and server.sessions[cid_a].sim.robots == 7,
                   what="the uploaded preset chosen again, from memory")
        assert "mine (uploaded)" not in server.tabs[cid_b].panels.preset.options
        before = len(b.notifications())
        b.set_value("preset", "mine (uploaded)")
        wait_until(lambda: len(b.notifications()) > before, what="the other tab's refusal")
        assert "not one of the choices" in b.notifications()[-1][1]
        assert server.sessions[cid_b].scenario.name == "default"
    finally:
        a.close()
        b.close()


def test_hostile_file_names_over_the_wire_write_nothing_and_name_no_download(server, tmp_path, monkeypatch):
    """Upload and replay names, and a preset ``name`` of path pieces, from a real websocket
    client: nothing is written, and every download the server sends has a plain name."""
    monkeypatch.chdir(tmp_path)
    client = WireClient(server.port, decode=True)
    try:
        wait_until(lambda: client.uuid_of("Export replay") and len(server.tabs) == 1, what="the tab's panels")
        cid = max(server.tabs)
        WRITES.seen.clear()
        WRITES.active = True
        try:
            for filename in EVIL_NAMES:
                before = len(client.notifications())
                client.upload("Upload preset", filename, _evil_preset("../../" + filename.replace("\x00", "")[:60],
                                                                      filename))
                wait_until(lambda n=before: len(client.notifications()) > n,
                           what=f"the upload of {filename[:30]!r}")
                assert client.notifications()[-1][2] == "green", client.notifications()[-1]
            for label in ("Export CSV", "Export JSON", "Download preset", "Export replay"):
                client.set_value(label, True)  # a click
            wait_until(lambda: len(client.downloads) >= 4, what="four downloads")
            before = len(client.notifications())
            client.upload("Load replay", EVIL_NAMES[0], server.tabs[cid].downloads[-1][1])
            wait_until(lambda: len(client.notifications()) > before, what="the replay loaded")
        finally:
            WRITES.active = False
    finally:
        client.close()
    assert WRITES.seen == [] and list(tmp_path.iterdir()) == []
    for name in client.downloads:
        assert "/" not in name and "\\" not in name and "\x00" not in name and not name.startswith("."), name
