"""Scene kinds as plug-ins: one module per kind (:mod:`.swarm`, :mod:`.fleet`, :mod:`.sonar`,
:mod:`.mai`), each an :class:`~.base.AppKind` entry of :mod:`.registry`. Shared app code never
imports a kind module; the registry and the tab (the composition root) do."""
