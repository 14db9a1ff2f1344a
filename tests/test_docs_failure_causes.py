"""Every failure cause and every record kind in the code is documented.

The failure causes are plain strings (no constants): they are collected from the
source with ``ast`` (no import, so the test does not depend on the numerical
stack), wherever the code can set one:

* the first argument of ``_Failure(...)`` (``robot/simulation.py``), including
  ``getattr(solver, "failure_cause", None) or "step size collapse"``;
* assignments to a name or attribute called ``cause`` / ``failure_cause``,
  also inside tuple assignments (``status, cause, message = FAILED, "...", ...``)
  and conditional expressions (``"a" if flag else "b"``);
* ``cause=`` keyword arguments.

Each must be a row ``| `cause` | ... |`` of the failure-cause table in
``docs/dynamics.md`` (and the table lists nothing else). Record kinds are the
module-level ``RECORD_*`` constants of ``robot/simulation.py``; each must be
documented in ``robot/results.py``'s docstring (``* N ``RECORD_X``: ...``) and in
``docs/dynamics.md`` (``| N | `RECORD_X` | ...``).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "robot"
DYNAMICS_DOC = ROOT / "docs" / "dynamics.md"
RESULTS = PACKAGE / "io" / "results.py"
SIMULATION = PACKAGE / "integration" / "records.py"  # the record kinds' module
#: modules outside robot/ the simulation can get a cause from (none today; robot/ is scanned whole)
EXTRA_SOURCES: tuple[Path, ...] = ()
CAUSE_NAMES = {"cause", "failure_cause"}
FAILURE_EXCEPTIONS = {"_Failure"}
#: causes known when this test was written: the parser must at least find these (guards the parser itself)
KNOWN_CAUSES = {
    "non-finite state",
    "penetration beyond physical bound",
    "constraint drift",
    "step size collapse",
    "event chattering",
    "integration stalled",
    "wall time",
    "unphysical pose",
    "Newton divergence",
    "solver error",
    "interrupted",
}


def _strings(node: ast.AST | None) -> set[str]:
    """The string values an expression can take (constants, ``a or b``, ``a if c else b``); calls and names give none."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return {node.value}
    if isinstance(node, ast.BoolOp):
        return set().union(*(_strings(v) for v in node.values))
    if isinstance(node, ast.IfExp):
        return _strings(node.body) | _strings(node.orelse)
    return set()


def _target_name(target: ast.AST) -> str | None:
    if isinstance(target, ast.Name):
        return target.id
    if isinstance(target, ast.Attribute):
        return target.attr
    return None


def _call_name(func: ast.AST) -> str | None:
    return func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else None


def causes_in(source: str) -> dict[str, int]:
    """Cause strings set in ``source`` -> first line number."""
    found: dict[str, int] = {}

    def add(values: set[str], node: ast.AST) -> None:
        for value in values:
            found.setdefault(value, node.lineno)

    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call):
            if _call_name(node.func) in FAILURE_EXCEPTIONS and node.args:
                add(_strings(node.args[0]), node)
            for keyword in node.keywords:
                if keyword.arg in CAUSE_NAMES:
                    add(_strings(keyword.value), node)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for target in targets:
                if _target_name(target) in CAUSE_NAMES:
                    add(_strings(node.value), node)
                elif isinstance(target, ast.Tuple) and isinstance(node.value, ast.Tuple) and len(target.elts) == len(node.value.elts):
                    for element, value in zip(target.elts, node.value.elts):
                        if _target_name(element) in CAUSE_NAMES:
                            add(_strings(value), node)
    return found


def code_causes() -> dict[str, str]:
    """Every cause string in the package -> where it is set (``file:line``)."""
    out: dict[str, str] = {}
    for path in sorted(PACKAGE.rglob("*.py")) + list(EXTRA_SOURCES):
        if "validation" in path.relative_to(ROOT).parts:
            continue  # the validation's own event loop reports messages, not simulation causes
        for cause, line in causes_in(path.read_text(encoding="utf-8")).items():
            out.setdefault(cause, f"{path.relative_to(ROOT)}:{line}")
    return out


def documented_causes() -> set[str]:
    """Causes in the failure-cause table of docs/dynamics.md (rows ``| `cause` | trigger | action |``)."""
    text = DYNAMICS_DOC.read_text(encoding="utf-8")
    section = re.search(r"^## Failure causes\n(.*?)(?=^## )", text, re.S | re.M)
    assert section, "docs/dynamics.md has no '## Failure causes' section"
    rows = re.findall(r"^\| `([^`]+)` \|(.*)\|\s*$", section.group(1), re.M)
    for cause, rest in rows:
        cells = [c.strip() for c in rest.split("|")]
        assert len(cells) == 2 and all(cells), f"docs/dynamics.md: the row of {cause!r} needs a trigger and an action"
    return {cause for cause, _ in rows}


def record_kinds() -> dict[str, int]:
    """Module-level ``RECORD_* = value`` (also ``A, B = 0, 1``) of robot/simulation.py."""
    kinds: dict[str, int] = {}
    for node in ast.parse(SIMULATION.read_text(encoding="utf-8")).body:
        if not isinstance(node, ast.Assign):
            continue
        for target in node.targets:
            pairs = (
                zip(target.elts, node.value.elts)
                if isinstance(target, ast.Tuple) and isinstance(node.value, ast.Tuple)
                else [(target, node.value)]
            )
            for name, value in pairs:
                if isinstance(name, ast.Name) and name.id.startswith("RECORD_"):
                    assert isinstance(value, ast.Constant) and isinstance(value.value, int), f"{name.id} is not an integer literal"
                    kinds[name.id] = value.value
    return kinds


def test_the_parser_finds_the_known_causes():
    causes = code_causes()
    assert KNOWN_CAUSES <= set(causes), f"parser missed {sorted(KNOWN_CAUSES - set(causes))}"
    # the parser's rules, on a sample with every form the code uses
    sample = '''
raise _Failure("a", "m")
raise _Failure(getattr(s, "failure_cause", None) or "b", "m")
status, cause, message = FAILED, "c", "m"
self.failure_cause = "d" if x in (-3, -4) else "e"
Trajectory(cause="f")
cause = None
'''
    assert set(causes_in(sample)) == {"a", "b", "c", "d", "e", "f"}


def test_every_failure_cause_is_documented():
    causes = code_causes()
    documented = documented_causes()
    missing = {cause: where for cause, where in causes.items() if cause not in documented}
    assert not missing, f"failure causes set in the code but not in docs/dynamics.md's 'Failure causes' table: {missing}"
    stale = documented - set(causes)
    assert not stale, f"docs/dynamics.md documents causes the code no longer sets: {sorted(stale)}"


def test_every_record_kind_is_documented():
    kinds = record_kinds()
    assert {"RECORD_STEP", "RECORD_ONSET", "RECORD_PEAK", "RECORD_START", "RECORD_OUTPUT"} <= set(kinds)
    assert len(set(kinds.values())) == len(kinds), f"two record kinds share a code: {kinds}"
    docstring = ast.get_docstring(ast.parse(RESULTS.read_text(encoding="utf-8"))) or ""
    in_results = {name: int(code) for code, name in re.findall(r"^\* (\d+) ``(RECORD_\w+)``", docstring, re.M)}
    table = re.search(r"^## Record kinds\n(.*?)(?=^## )", DYNAMICS_DOC.read_text(encoding="utf-8"), re.S | re.M)
    assert table, "docs/dynamics.md has no '## Record kinds' section"
    in_docs = {name: int(code) for code, name in re.findall(r"^\| (\d+) \| `(RECORD_\w+)` \|", table.group(1), re.M)}
    assert in_results == kinds, f"robot/results.py docstring documents {in_results}, the code defines {kinds}"
    assert in_docs == kinds, f"docs/dynamics.md 'Record kinds' documents {in_docs}, the code defines {kinds}"
