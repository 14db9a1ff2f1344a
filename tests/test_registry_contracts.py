"""The registries' contracts: force element types, integration methods and analyses registered from outside.

Each registry checks what it is given when it is given it (registration, or the
first look-up of a solver named ``"module:attribute"``) and refuses a broken
extension with the project's own error (a ``robot.Error``: the CLI's bad-input
exit 2) naming the extension and what is wrong; at run time a failing
extension stops the run as a failure with its records kept, naming the culprit.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from robot.analysis import ANALYSES, AnalysisError, Field, register as register_analysis
from robot.analysis.registry import AnalysisRegistry
from robot.cli.common import EXIT_BAD_INPUT, EXIT_RUN_FAILED
from robot.cli.main import main
from robot.dynamics.forces import FORCE_TYPES, ForceElement, register as register_force
from robot.errors import Error, RegistrationError, SceneError
from robot.integration import methods
from robot.integration.dense import HermiteDense
from robot.integration.options import SolverOptions
from robot.integration.simulation import integrate
from robot.integration.solver_base import OdeSolver
from robot.io.results import load_result
from robot.run import build_run
from robot.scene.loader import load_scene

ROOT = Path(__file__).resolve().parents[1]


# --- force elements -------------------------------------------------------------------------


class ElbowLoad(ForceElement):
    """A constant torque on the elbow coordinate that turns NaN (or returns None) from ``fail_after`` s on."""

    KEYS = {"fail_after", "failure"}
    state_dependent = False

    def __init__(self, name: str, fail_after: float, failure: str):
        self.name, self.fail_after, self.failure = name, fail_after, failure

    @classmethod
    def parse(cls, table, where, base_dir):
        return {"fail_after": float(table["fail_after"]), "failure": table.get("failure", "nan")}

    @classmethod
    def build(cls, name, parameters, mechanism, where):
        return cls(name, parameters["fail_after"], parameters["failure"])

    def apply(self, kinematics, t, q, v, out):
        if t < self.fail_after:
            out[1] += 0.1
            return 0.1
        if self.failure == "none":
            return None
        out[1] += math.nan
        return math.nan


@pytest.fixture
def elbow_load():
    register_force("test_elbow_load")(ElbowLoad)
    yield "test_elbow_load"
    FORCE_TYPES.pop("test_elbow_load", None)


def arm_scene(tmp_path: Path, force_table: str) -> Path:
    """The shipped free arm with one more ``[[force]]`` table, over 0.05 s."""
    path = tmp_path / "arm_extra.toml"
    path.write_text(f'extends = "free_two_link_spring"\nname = "arm_extra"\nduration = 0.05\n\n[[force]]\n{force_table}\n')
    return path


def registration_error(cls: type, type_name: str = "test_broken") -> str:
    try:
        with pytest.raises(RegistrationError) as error:
            register_force(type_name)(cls)
    finally:
        FORCE_TYPES.pop(type_name, None)
    assert isinstance(error.value, Error) and type_name not in FORCE_TYPES
    return str(error.value)


def test_a_force_element_without_apply_is_refused_naming_the_class():
    class NoApply(ForceElement):
        KEYS: set[str] = set()
        parse, build = ElbowLoad.parse, ElbowLoad.build

    message = registration_error(NoApply)
    assert "NoApply" in message and "it does not define apply" in message


def test_a_force_element_with_the_wrong_apply_signature_is_refused():
    class NoTime(ElbowLoad):
        def apply(self, kinematics, q, v, out):
            return 0.0

    message = registration_error(NoTime)
    assert "NoTime" in message and "cannot be called as apply(self, kinematics, t, q, v, out)" in message


@pytest.mark.parametrize(
    "attribute, value, expected",
    [("KEYS", ["fail_after"], "KEYS=['fail_after'] must be a set"), ("state_dependent", "yes", "state_dependent='yes' must be True or False")],
)
def test_force_element_attributes_are_checked(attribute, value, expected):
    broken = type("Broken", (ElbowLoad,), {attribute: value})
    assert expected in registration_error(broken)


def test_a_class_that_is_no_force_element_and_a_taken_type_name_are_refused():
    assert "is not a subclass of robot.dynamics.forces.ForceElement" in registration_error(dict)
    with pytest.raises(RegistrationError, match="'spring_damper' is registered twice"):
        register_force("spring_damper")(ElbowLoad)
    assert FORCE_TYPES["spring_damper"].__name__ == "SpringDamper"


def test_a_key_error_in_a_user_parse_is_a_scene_error_naming_the_element_and_key(tmp_path, elbow_load):
    path = arm_scene(tmp_path, f'name = "elbow_load"\ntype = "{elbow_load}"')  # no fail_after
    with pytest.raises(SceneError, match="force 'elbow_load' \\(test_elbow_load\\): key 'fail_after' is missing") as error:
        load_scene(path)
    assert error.value.key == "fail_after"


@pytest.mark.parametrize("failure, expected", [("nan", "gave a non-finite generalized force"), ("none", "returned None from apply")])
def test_a_non_finite_force_element_fails_the_run_naming_it_and_keeps_the_records(tmp_path, capsys, elbow_load, failure, expected):
    path = arm_scene(tmp_path, f'name = "elbow_load"\ntype = "{elbow_load}"\nfail_after = 0.02\nfailure = "{failure}"')
    code = main(["run", "--scene", str(path), "--out", str(tmp_path / "out")])
    assert code == EXIT_RUN_FAILED, capsys.readouterr().err
    result = load_result(tmp_path / "out" / "arm_extra.npz")
    assert result.cause == "solver error"
    assert "force element 'elbow_load'" in result.message and "ElbowLoad" in result.message and expected in result.message
    assert "tip_spring" not in result.message  # the built-in element after it is not blamed
    t = np.asarray(result.t)
    assert 0.015 < t[-1] <= 0.02 and np.isfinite(np.asarray(result.y)).all()  # records up to the failure, all finite


def test_a_non_finite_force_at_the_initial_state_is_bad_input(tmp_path, capsys, elbow_load):
    path = arm_scene(tmp_path, f'name = "elbow_load"\ntype = "{elbow_load}"\nfail_after = 0.0')
    assert main(["run", "--scene", str(path), "--out", str(tmp_path / "out")]) == EXIT_BAD_INPUT
    assert "force element 'elbow_load'" in capsys.readouterr().err


# --- integration methods --------------------------------------------------------------------


class ExplicitEuler(OdeSolver):
    """y+ = y + h f(t, y), fixed step ``first_step``; raises ZeroDivisionError at step ``fail_at`` (0: never)."""

    fail_at = 0

    def __init__(self, fun, t0, y0, t_bound, first_step=None, vectorized=False, **options):
        super().__init__(fun, t0, y0, t_bound, vectorized)
        self.h, self.f, self.previous, self.steps = float(first_step), self.fun(t0, self.y), None, 0

    def _step_impl(self):
        self.steps += 1
        if self.steps == self.fail_at:
            raise ZeroDivisionError("the toy solver divided by zero")
        h = min(self.h, self.t_bound - self.t)
        self.previous = (self.t, self.y, self.f)
        self.t, self.y = self.t + h, self.y + h * self.f
        self.f = self.fun(self.t, self.y)
        return True, None

    def _dense_output_impl(self):
        t_old, y_old, f_old = self.previous
        return HermiteDense(t_old, self.t, y_old, f_old, self.y, self.f)


def euler_traits(name: str = "ToyEulerContract", solver=ExplicitEuler, **traits) -> methods.IntegratorTraits:
    return methods.IntegratorTraits(name, solver, **{"fixed_step": True, "explicit": True, "stages": 1, **traits})


@pytest.fixture
def registered():
    """Register traits for one test, unregistered after it."""
    names = []

    def add(traits: methods.IntegratorTraits) -> str:
        names.append(traits.name)
        methods.register(traits)
        return traits.name

    yield add
    for name in names:
        methods.unregister(name)


@pytest.mark.parametrize(
    "field, value, expected",
    [
        ("stages", -3, r"stages=-3 must be None or an integer in the valid range \[1, inf\)"),
        ("stages", 1.5, r"stages=1.5 must be None or an integer"),
        ("stages", True, r"stages=True must be None or an integer"),
        ("fixed_step", "yes", r"fixed_step='yes' must be True or False"),
        ("step_sizes", (1e-5, 0.0), r"step_sizes=\(1e-05, 0.0\) must be a tuple of step sizes in s, each in the valid range \(0, inf\)"),
        ("available", 3, r"available=3 must be None or a function"),
        ("solver", "no_colon", r"solver='no_colon' must be a class or 'module:attribute'"),
        ("solver", lambda *a, **k: None, r"solver=<function .*> must be a class"),
    ],
)
def test_bad_traits_are_refused_naming_the_field_value_and_range(field, value, expected):
    with pytest.raises(RegistrationError, match=expected) as error:
        methods.register(euler_traits(**{field: value}))
    assert error.value.key == field and "ToyEulerContract" in str(error.value)
    assert "ToyEulerContract" not in methods.names()


def test_a_solver_class_breaking_the_contract_is_refused():
    class NoDense(ExplicitEuler):
        _dense_output_impl = OdeSolver._dense_output_impl

    class NoFirstStep(ExplicitEuler):
        def __init__(self, fun, t0, y0, t_bound):
            super().__init__(fun, t0, y0, t_bound, 1e-5)

    with pytest.raises(RegistrationError, match="NoDense is not an OdeSolver-like class: it does not implement _dense_output_impl"):
        methods.register(euler_traits(solver=NoDense))
    with pytest.raises(RegistrationError, match=r"NoFirstStep\(fun, t0, y0, t_bound\) does not take \(fun, t0, y0, t_bound, first_step=\)"):
        methods.register(euler_traits(solver=NoFirstStep))
    with pytest.raises(RegistrationError, match="is not an OdeSolver-like class: it has no method step\\(\\); it has no method dense_output\\(\\)"):
        methods.register(euler_traits(solver=dict))


def test_an_unimportable_solver_is_bad_input_at_scene_validation(tmp_path, capsys, registered):
    name = registered(euler_traits("ToyMissingModule", "no_such_module_anywhere:Solver"))
    with pytest.raises(RegistrationError, match="method='ToyMissingModule': its solver 'no_such_module_anywhere:Solver' cannot be imported"):
        methods.traits(name).solver_class()
    path = tmp_path / "scene.toml"
    path.write_text(f'extends = "ideal"\nname = "ideal_missing"\n[solver]\nmethod = "{name}"\nfirst_step = 1e-5\n')
    assert main(["run", "--scene", str(path), "--check"]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert "ToyMissingModule" in err and "Traceback" not in err


def test_an_arithmetic_error_of_a_solver_is_a_failed_run_with_its_records(registered):
    class FailsAtTen(ExplicitEuler):
        fail_at = 10

    name = registered(euler_traits("ToyEulerFails", FailsAtTen))
    run = build_run("ideal")
    trajectory = integrate(run.dynamics, run.y0, (0.0, 0.002), SolverOptions(name, first_step=2e-5))
    assert not trajectory.success and trajectory.cause == "solver error"
    assert "ZeroDivisionError: the toy solver divided by zero" in trajectory.message
    assert trajectory.n_steps == 9 and trajectory.t_end == pytest.approx(9 * 2e-5)


def test_the_base_solver_says_what_a_missing_dense_output_is_needed_for():
    class Bare(OdeSolver):
        pass

    solver = Bare(lambda t, y: -y, 0.0, np.ones(1), 1.0)
    with pytest.raises(NotImplementedError, match="Bare does not implement _dense_output_impl.*contact onsets"):
        solver._dense_output_impl()


# --- analyses -------------------------------------------------------------------------------

SERIES = (Field("t", ("time",), "s", "times"), Field("signal", ("time",), "", "values"))
RMS = (Field("rms", (), "", "root mean square"),)


def user_functions(module: str = "user_stats") -> dict:
    """A user module's functions (a new module object per call, as after a reload)."""
    source = (
        "import numpy as np\n"
        "def peak_rms(t, signal):\n    return {'rms': -1.0}\n"
        "def first_values(t, signal, *, count=3, extra=0):\n    return {'values': np.asarray(signal)[: count + extra]}\n"
    )
    namespace = {"__name__": module}
    exec(compile(source, f"{module}.py", "exec"), namespace)
    return namespace


def test_a_user_function_under_a_builtin_name_is_refused_and_the_builtin_stays():
    builtin = ANALYSES["peak_rms"].function
    with pytest.raises(AnalysisError, match=r"'peak_rms' is already registered \(robot.analysis.statistics.peak_rms\); register user_stats.peak_rms under another name"):
        register_analysis("peak_rms", inputs=SERIES, outputs=RMS, source="user")(user_functions()["peak_rms"])
    assert ANALYSES["peak_rms"].function is builtin


def test_the_same_function_registered_again_replaces_itself():
    registry = AnalysisRegistry(())
    for functions in (user_functions(), user_functions()):  # a module reloaded: new objects, same module and name
        register_analysis("my_rms", inputs=SERIES, outputs=RMS, source="user", registry=registry)(functions["peak_rms"])
    with pytest.raises(AnalysisError, match="already registered"):
        register_analysis("my_rms", inputs=SERIES, outputs=RMS, source="user", registry=registry)(user_functions("other")["peak_rms"])


def test_a_user_registration_before_the_first_lookup_keeps_every_builtin():
    code = (
        "from robot.analysis import ANALYSES, AnalysisError, Field, register\n"
        "F = (Field('t', ('time',), 's', ''), Field('signal', ('time',), '', ''))\n"
        "try:\n"
        "    register('peak_rms', inputs=F, outputs=(Field('rms', (), '', ''),), source='x')(lambda t, signal: {'rms': 0.0})\n"
        "except AnalysisError as e:\n"
        "    print('refused', 'already registered' in str(e))\n"
        "print(sorted(ANALYSES))\n"
        "print(ANALYSES['peak_rms'].function.__module__)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT).stdout.splitlines()
    assert out[0] == "refused True"
    assert {"orbit", "archard_wear", "lyapunov_rosenstein", "peak_rms", "power_spectral_density"} <= set(eval(out[1]))
    assert out[2] == "robot.analysis.statistics"


def test_a_failed_builtin_import_is_not_marked_loaded():
    registry = AnalysisRegistry(("no_such_analysis_module",))
    for _ in range(2):  # the second lookup tries again and fails the same way, instead of answering from half a registry
        with pytest.raises(ModuleNotFoundError):
            registry["anything"]


def test_an_output_of_the_wrong_shape_is_refused_naming_analysis_output_and_shapes():
    registry = AnalysisRegistry(())
    values = (Field("values", ("value",), "", "the first values"),)
    register_analysis("first_values", inputs=SERIES, outputs=values, source="user", sizes=lambda *, count=3, extra=0: {"value": count}, registry=registry)(
        user_functions()["first_values"]
    )
    t = np.linspace(0.0, 1.0, 11)
    assert registry["first_values"](t=t, signal=t, count=4)["values"].shape == (4,)
    with pytest.raises(AnalysisError, match=r"analysis 'first_values': output 'values' has shape \(6,\), declared \(4,\)"):
        registry["first_values"](t=t, signal=t, count=4, extra=2)


@pytest.mark.parametrize(
    "inputs, outputs, function, sizes, expected",
    [
        (("t", "signal"), RMS, lambda t, signal: {"rms": 0.0}, None, "inputs must be Field"),
        (SERIES, RMS, 42, None, "register\\(\\) decorates a function, got 42"),
        (SERIES, RMS, lambda t, signal, threshold=0.0: {"rms": 0.0}, None, "argument\\(s\\) \\['threshold'\\] are neither inputs nor keyword-only"),
        (SERIES, RMS, lambda t: {"rms": 0.0}, None, "does not take the input\\(s\\) \\['signal'\\]"),
        (SERIES, (Field("v", ("peak",), "", ""),), lambda t, signal: {"v": 0}, None, "output dimension\\(s\\) \\['peak'\\] are no input dimension"),
        (SERIES, RMS + RMS, lambda t, signal: {"rms": 0.0}, None, "outputs names \\['rms', 'rms'\\] are not distinct"),
    ],
)
def test_a_broken_analysis_declaration_is_refused_at_registration(inputs, outputs, function, sizes, expected):
    registry = AnalysisRegistry(())
    extra = {} if sizes is None else {"sizes": sizes}
    with pytest.raises(AnalysisError, match=expected):
        register_analysis("broken", inputs=inputs, outputs=outputs, source="user", registry=registry, **extra)(function)
    assert "broken" not in registry
