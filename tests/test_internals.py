"""The private parts of other libraries Shoal relies on are still where it reads them.

Each entry of :data:`INTERNALS` names a library, an internal of it and who reads it. A new
release that moves one fails here by name, not somewhere deep in a guard or a kernel; and each
such library has an upper bound in pyproject.toml, so an install never gets a release nobody has
checked (lift it after this file passes with the new release: ``.ci/newest``).
"""

from __future__ import annotations

import time
import tomllib
from pathlib import Path

import pytest
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]

INTERNALS = {
    "numba": [
        ("numba.np.random._constants: fi_double, ki_double, wi_double, ziggurat_nor_r, ziggurat_nor_inv_r",
         "engine/core/compiled_draws.py (numpy's normal ziggurat, compiled)"),
    ],
    "viser": [
        ("viser._messages: RunJavascriptMessage, RemoveNotificationMessage, GuiUpdateMessage, "
         "FileTransferStartUpload, FileTransferPart", "app/panel/keys.py, app/upload_guard.py, app/input_guard.py"),
        ("GuiApi._websock_interface (queue_message, register_handler, unregister_handler, _incoming_handlers)",
         "app/panel/keys.py, app/upload_guard.py, app/input_guard.py"),
        ("GuiApi._current_file_upload_states", "app/upload_guard.py (an upload dropped while it arrives)"),
        ("GuiApi._gui_input_handle_from_uuid, GuiApi._handle_gui_updates", "app/input_guard.py"),
        ("ViserServer starts websockets.asyncio.server.serve(process_request=...)", "app/origin_guard.py"),
        ("GuiApi._websock_interface.get_message_buffer().sanctioned_dead_writes()",
         "app/server.py:expect_late_writes (a tab closed mid-update)"),
        ("a handle's _impl.props and _impl.removed, SceneNodeHandle._queue_update and _on_prop_assigned",
         "app/view/node_update.py (an array sent without the setter's casts), app/panel/plot_stream.py"),
    ],
    "pymunk": [
        ("Chipmunk's point and swept-disc query arithmetic", "engine/robots/queries.py repeats it to the bit "
         "(tests/test_kernels.py, tests/test_physics.py compare)"),
    ],
}


def test_every_library_with_internals_has_an_upper_bound():
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["dependencies"]
    specs = {Requirement(d).name: Requirement(d).specifier for d in deps}
    for lib, used in INTERNALS.items():
        assert any(s.operator in ("<", "<=", "~=", "==") for s in specs[lib]), (
            f"pyproject.toml: {lib} needs an upper bound: Shoal reads its internals " + "; ".join(u for u, _ in used))


def test_numba_ziggurat_tables():
    try:
        from numba.np.random import _constants as c
    except ImportError as err:
        pytest.fail(f"numba {_version('numba')} moved numba.np.random._constants (the ziggurat tables "
                    f"engine/core/compiled_draws.py reads): {err}")
    for name in ("fi_double", "ki_double", "wi_double"):
        table = getattr(c, name, None)
        assert table is not None and len(table) == 256, f"numba.np.random._constants.{name}: moved or not 256 long"
    assert abs(c.ziggurat_nor_r - 3.654152885361009) < 1e-15, "numba.np.random._constants.ziggurat_nor_r changed"
    assert abs(c.ziggurat_nor_inv_r * c.ziggurat_nor_r - 1.0) < 1e-15


def test_viser_messages():
    from viser import _messages

    for name in ("RunJavascriptMessage", "RemoveNotificationMessage", "GuiUpdateMessage", "FileTransferStartUpload",
                 "FileTransferPart"):
        assert hasattr(_messages, name), f"viser {_version('viser')} moved viser._messages.{name}"
    fields = _messages.FileTransferStartUpload.__annotations__
    assert {"transfer_uuid", "size_bytes"} <= set(fields), "viser._messages.FileTransferStartUpload fields moved"


def test_viser_client_gui_internals():
    import viser

    from shoal.app.input_guard import guard_inputs
    from shoal.app.upload_guard import guard_uploads

    from viser_wire import WireClient

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    tab = None
    try:
        tab = WireClient(server.get_port())
        deadline = time.monotonic() + 20
        while not server.get_clients() and time.monotonic() < deadline:
            time.sleep(0.05)
        gui = next(iter(server.get_clients().values())).gui
        interface = getattr(gui, "_websock_interface", None)
        assert interface is not None, f"viser {viser.__version__} moved GuiApi._websock_interface"
        for name in ("queue_message", "register_handler", "unregister_handler", "_incoming_handlers"):
            assert hasattr(interface, name), f"viser {viser.__version__} moved GuiApi._websock_interface.{name}"
        assert isinstance(getattr(gui, "_current_file_upload_states", None), dict), (
            f"viser {viser.__version__} moved GuiApi._current_file_upload_states (app/upload_guard.py)")
        assert isinstance(getattr(gui, "_gui_input_handle_from_uuid", None), dict), (
            f"viser {viser.__version__} moved GuiApi._gui_input_handle_from_uuid (app/input_guard.py)")
        assert guard_inputs(gui, lambda *_: None), f"viser {viser.__version__} moved GuiApi._handle_gui_updates"
        buffer = interface.get_message_buffer()
        assert callable(getattr(buffer, "sanctioned_dead_writes", None)), (
            f"viser {viser.__version__} moved AsyncMessageBuffer.sanctioned_dead_writes (app/server.py)")
        assert guard_uploads(gui, 10, 20, lambda *_: None)
    finally:
        if tab is not None:
            tab.close()
        server.stop()


def test_viser_serves_through_the_guarded_websockets_server():
    from shoal.app.origin_guard import OriginPolicy, guarded_viser

    server = guarded_viser("127.0.0.1", 0, OriginPolicy("127.0.0.1"))  # RuntimeError names viser if it moved
    server.stop()


def _version(lib: str) -> str:
    from importlib.metadata import version

    return version(lib)


def test_viser_scene_handle_internals():
    import numpy as np
    import viser

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        node = server.scene.add_point_cloud("/p", np.zeros((2, 3), np.float32), colors=(0, 0, 0), point_size=0.1)
        impl = getattr(node, "_impl", None)
        assert impl is not None and isinstance(getattr(getattr(impl, "props", None), "points", None), np.ndarray), (
            f"viser {viser.__version__} moved a scene handle's _impl.props (app/view/node_update.py)")
        assert getattr(impl, "removed", None) is False, f"viser {viser.__version__} moved _impl.removed"
        for name in ("_queue_update", "_on_prop_assigned"):
            assert callable(getattr(node, name, None)), f"viser {viser.__version__} moved SceneNodeHandle.{name}"
    finally:
        server.stop()
