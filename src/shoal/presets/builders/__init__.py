"""One module per scene kind that turns a validated :class:`~shoal.presets.models.Scenario` into
its engine (:mod:`.swarm`, :mod:`.fleet`, :mod:`.sonar`, :mod:`.slo`), with the keywords that
retune a running one; :mod:`.world` lays out a ``[world]`` and :mod:`.positions` says where a
host swarm gets its positions. The kinds' registry (:mod:`shoal.presets.kinds`) names each
builder by string, so building one kind imports no other."""
