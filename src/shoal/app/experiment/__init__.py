"""Experiments from the page: a sweep of the tab's scene over one or two fields, run on the
server with the machinery of ``shoal sweep``, its medians shown as the cells come in.

* :mod:`.request`: what a tab may ask for, checked against the scene and the server's limits;
* :mod:`.service`: the server's queue, the thread that runs it, Cancel, one experiment per tab;
* :mod:`.figure`: the plot in the page and the PNG to download;
* :mod:`.panel`: the Sweep tab's handles.
"""

from .request import AxisRequest, ExperimentRequest, Limits, Refused
from .service import Experiment, ExperimentService, experiment_pool

__all__ = ["AxisRequest", "Experiment", "ExperimentRequest", "ExperimentService", "Limits", "Refused",
           "experiment_pool"]
