"""Shoal: PSO control of robot swarms, as an engine, a CLI and a browser app.

Sub-packages, lowest layer first: ``shoal.engine`` (the simulation), ``shoal.presets``
(scenario models and shipped presets), ``shoal.studies`` (thesis reproductions and sweeps)
and ``shoal.app`` (the browser app and the ``shoal`` command); ``shoal.static`` holds the
teaching notes and lessons.
"""

__version__ = "0.1.0"
