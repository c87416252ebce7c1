"""Shoal: PSO control of robot swarms, as an engine, a CLI and a browser app.

The code lives in the top-level folders ``engine/``, ``presets/``, ``app/`` and
``static/``; the installer maps them to ``shoal.engine``, ``shoal.presets``,
``shoal.app`` and ``shoal.static``.
"""

__version__ = "0.1.0"
