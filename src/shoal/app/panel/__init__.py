"""The control panel of one tab, without a kind: a :class:`~.panel.Panel` that builds a scene
kind's declarative tabs and folders (:mod:`.spec`) and live plots (:mod:`.plots`) beside the
shared header and sections (Replay, Compare, Export, Notes; the Positions and Selected-robot
folders a kind may add)."""
