"""One tab's simulation, without viser: :class:`~.session.Session` composed of a
:class:`~.history.History`, a :class:`~.timeline.Timeline`, an optional :class:`~.twin.Twin`
(swarm B) and the scene kind's :class:`~.driver.Driver`. Nothing here imports the view, the
panels or a scene kind."""
