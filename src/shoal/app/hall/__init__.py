"""The lecture hall: one run shown to a class (``shoal serve --lecture``), take-over, prediction
rounds, and a class across processes behind nginx (``shoal hall``)."""
