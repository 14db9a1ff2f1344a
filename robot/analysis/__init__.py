"""Analyses of simulation results, for single runs and parameter sweeps.

Study-level modules: :mod:`.paper` (the seed paper's study, figures and
``summary.json``), :mod:`.claims` (the paper's claims measured),
:mod:`.studies` (work-precision, stability, speed).

Each analysis lives in its own module, with its definition and source in the
module docstring, as a pure function of arrays (numpy/scipy); the per-run ones
are registered by name in :data:`ANALYSES` (see :mod:`.registry` for the
declaration of inputs, parameters and fixed-shape outputs):

* :mod:`.poincare`: stroboscopic sections (one sample per drive period) and
  hyperplane crossings (``poincare_stroboscopic``, ``poincare_crossing``);
* :mod:`.bifurcation`: Poincare samples against a swept parameter, distinct-point
  counts (period detection);
* :mod:`.spectra`: FFT amplitude spectrum and Welch power spectral density
  (``amplitude_spectrum``, ``power_spectral_density``);
* :mod:`.lyapunov_benettin`: largest Lyapunov exponent of a :class:`Flow`
  (two trajectories, periodic renormalisation; not a function of recorded
  arrays, so not in the registry);
* :mod:`.simulator_flow` and :mod:`.lyapunov_simulator`: the simulator as a
  Benettin flow (tangent-space distance, perturbations on the closures) and the
  registered per-run exponent (``lyapunov_benettin``, needs the run);
* :mod:`.lyapunov_rosenstein`: largest Lyapunov exponent of a time series
  (``lyapunov_rosenstein``);
* :mod:`.orbits`: journal / ball centre in the bearing / socket frame (``orbit``);
* :mod:`.statistics`: peak, RMS and mean over a window (``peak_rms``);
* :mod:`.wear`: Archard wear depth around the bearing (``archard_wear``);
* :mod:`.figures`: PNG pictures (bifurcation diagram, 2-D map, spectrum
  waterfall, orbit plot), written atomically.

Importing this package imports only the registry (no scipy, matplotlib or
pinocchio); the analysis modules load on the registry's first lookup.
Definitions, sources and validations: ``docs/analyses.md``.
"""

from .errors import AnalysisError, UnknownAnalysisError
from .registry import ANALYSES, Analysis, Field, register

__all__ = ["ANALYSES", "Analysis", "AnalysisError", "Field", "UnknownAnalysisError", "register"]
