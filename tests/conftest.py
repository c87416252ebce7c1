"""Test-wide settings: hypothesis checks behaviour, not speed, on a shared 2-core machine."""

from hypothesis import settings

settings.register_profile("shoal", deadline=None)
settings.load_profile("shoal")

import signal  # noqa: E402

# A suite started in the background of a shell without job control (``.ci/run &``) inherits
# SIGINT ignored, and so would every command the tests start: ``shoal serve`` and the plug-in
# checks would then never see the Ctrl-C they are tested with. Catching it here gives the
# children the default a terminal gives (exec resets a caught signal, not an ignored one).
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


import pytest  # noqa: E402

from app_helpers import hand_tab  # noqa: E402
from plugin_env import install_example  # noqa: E402


@pytest.fixture(scope="session")
def example_plugin(tmp_path_factory):
    """A folder with the example plug-in installed (for child processes: :mod:`plugin_env`)."""
    return install_example(tmp_path_factory.mktemp("plugin"))


@pytest.fixture(scope="module")
def server(request):
    """An app server on a free port showing the test module's ``APP_PRESET`` (default "default")."""
    from shoal.app.server import start_server

    srv = start_server(getattr(request.module, "APP_PRESET", "default"), port=0)
    yield srv
    srv.stop()


@pytest.fixture
def tab(server):
    """A hand-ticked tab (see :func:`app_helpers.hand_tab`)."""
    with hand_tab(server) as t:
        yield t
