"""Studies of the integration itself: speed against accuracy, and where methods fail.

* :mod:`.common`: one run of a scene with given solver options, summarised;
* :mod:`.work_precision`: reference solution, method sweep, error measures, chart;
* :mod:`.stability`: failure boundaries (step size against contact stiffness,
  Baumgarte gains, hidden contact onsets);
* :mod:`.speed`: microseconds per right-hand side and the real-time factor.

``scripts/work_precision.py`` runs them all; ``docs/work-precision.md`` reports.
"""
