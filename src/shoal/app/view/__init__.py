"""The arena of one tab, without a kind: a :class:`~.canvas.Canvas` (scene nodes under one
root frame, world ↔ scene coordinates), shared :mod:`.layers` (robots, trails, bests, swarm B,
ghosts…) and the :class:`~.view.View` that draws a kind's layers from snapshots."""
