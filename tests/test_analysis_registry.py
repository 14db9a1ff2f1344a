"""The analysis registry: lazy loading, declared outputs, errors, a light package import."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from robot.analysis import ANALYSES, AnalysisError, Field, UnknownAnalysisError, register
from robot.analysis.registry import BUILTIN_MODULES, AnalysisRegistry

EXPECTED = {
    "poincare_stroboscopic", "poincare_crossing", "amplitude_spectrum", "power_spectral_density",
    "peak_rms", "orbit", "archard_wear", "lyapunov_rosenstein",
}


def test_package_import_is_light():
    code = (
        "import sys, robot.analysis as a; "
        "heavy = [m for m in ('scipy', 'matplotlib', 'pinocchio', 'numba', 'robot.analysis.spectra') if m in sys.modules]; "
        "print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_builtin_analyses_are_registered_with_documented_fields():
    assert EXPECTED <= set(ANALYSES)
    for name in EXPECTED:
        analysis = ANALYSES[name]
        assert analysis.name == name and analysis.source
        assert analysis.function.__module__.split(".")[-1] in BUILTIN_MODULES
        for field in analysis.inputs + analysis.outputs:
            assert field.unit and field.description, (name, field.name)
        # every input is an argument of the function
        arguments = set(__import__("inspect").signature(analysis.function).parameters)
        assert {f.name for f in analysis.inputs} <= arguments


def test_unknown_name_lists_the_registered_ones():
    with pytest.raises(UnknownAnalysisError, match="no analysis named 'lyapunov'; registered: .*'lyapunov_rosenstein'"):
        ANALYSES["lyapunov"]
    with pytest.raises(KeyError):  # also a KeyError, as a mapping's lookup should raise
        ANALYSES["nothing"]


def test_register_checks_the_declared_outputs_and_duplicate_names():
    registry = AnalysisRegistry(())  # a registry of its own: the test leaves ANALYSES as it was

    @register(
        "test_mean_only",
        inputs=(Field("signal", ("time",), "[signal]", "a signal"),),
        outputs=(Field("mean", (), "[signal]", "mean"), Field("count", (), "1", "samples")),
        source="test",
        registry=registry,
    )
    def mean_only(signal, *, scale: float = 1.0):
        return {"mean": scale * np.mean(signal)}

    with pytest.raises(AnalysisError, match=r"returned \['mean'\], declared \['count', 'mean'\]"):
        registry["test_mean_only"](signal=[1.0, 2.0])
    assert registry["test_mean_only"].parameters == {"scale": 1.0}
    assert "test_mean_only" not in ANALYSES
    with pytest.raises(AnalysisError, match="an analysis named 'peak_rms' is already registered"):
        register("peak_rms", inputs=(), outputs=(), source="test")(mean_only)


def test_output_shapes_need_the_input_sizes():
    with pytest.raises(AnalysisError, match=r"input_sizes must give the dimension\(s\) \['component'\]"):
        ANALYSES["poincare_crossing"].output_shapes({}, normal=[1.0])
    shapes = ANALYSES["archard_wear"].output_shapes({"time": 10}, n_bins=36)
    assert shapes["depth"] == (36,) and shapes["volume"] == ()
    assert ANALYSES["lyapunov_rosenstein"].output_shapes({}, n_steps=50)["divergence"] == (51,)
