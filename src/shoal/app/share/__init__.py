"""Runs anyone can open: one self-contained HTML page that plays a recorded run in any
browser, with no Python and no server.

The page is viser's own static client with the recorded scene inside it (viser's scene
serializer and player), drawn by the app's view of that kind of scene; a panel names the
preset, seed and versions and offers the preset to download.

* :mod:`.frames`: which steps a page keeps (at most :data:`MAX_FRAMES`);
* :mod:`.draw`: the glue to the app's sessions and views (the only module that knows them);
* :mod:`.page`: the private scene recorder and the HTML around viser's client;
* :mod:`.export`: pages from a preset and seed, from recordings or from a session.
"""

from .export import preset_html, recording_html, session_html, write_html
from .frames import MAX_FRAMES
from .page import Busy

__all__ = ["MAX_FRAMES", "Busy", "preset_html", "recording_html", "session_html", "write_html"]
