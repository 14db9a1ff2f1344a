"""The user's extension modules: imported by name from ``CLEARANCE_EXTENSIONS`` before anything is looked up.

An extension (a clearance joint type, a dissipation model, a friction law, an
integrator, a force element, an analysis: ``docs/architecture.md``, "Extension
points") registers itself when its module is imported. From Python, import it
yourself before building a scene. For the ``clearance`` commands, and for the
processes they start (a sweep's workers, the claims study's), name the modules
in the environment::

    CLEARANCE_EXTENSIONS=my_package.laws,my_package.forces clearance run --scene my_scene.toml

Names are separated by commas (spaces ignored) and must be importable from
``sys.path`` (an installed package, or a folder on ``PYTHONPATH``): a module
that cannot be found, or that fails while it is imported, stops the command
with an :class:`ExtensionError` naming it (exit 2). Each module is imported
once per process (:func:`load_extensions` is idempotent). The processes a
command starts (a sweep's local workers, the claims study's) inherit the
variable with the rest of the environment; workers started elsewhere (``dask
worker`` for ``--scheduler ADDRESS``) need it, and the modules, in their own.
"""

from __future__ import annotations

import importlib
import os
import traceback

from robot.errors import RobotError

#: the environment variable naming the extension modules
VARIABLE = "CLEARANCE_EXTENSIONS"

_LOADED: dict[str, object] = {}


class ExtensionError(RobotError, ImportError):
    """A module named in ``CLEARANCE_EXTENSIONS`` cannot be imported."""


def extension_names(value: str | None = None) -> list[str]:
    """The module names of ``value`` (default: the environment variable), in order, without duplicates."""
    text = os.environ.get(VARIABLE, "") if value is None else value
    names: list[str] = []
    for name in (part.strip() for part in text.split(",")):
        if name and name not in names:
            names.append(name)
    return names


def load_extensions(value: str | None = None) -> list[str]:
    """Import every extension module not imported yet; the names imported (all of them, in order)."""
    names = extension_names(value)
    for name in names:
        if name not in _LOADED:
            _LOADED[name] = _import(name)
    return names


def _import(name: str) -> object:
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        if exc.name is not None and name.startswith(exc.name) and (name == exc.name or name[len(exc.name)] == "."):
            raise ExtensionError(
                f"{VARIABLE}: module {name!r} not found; install its package or add its folder to PYTHONPATH",
                key=VARIABLE, value=name,
            ) from None
        raise ExtensionError(_failure(name, exc), key=VARIABLE, value=name) from None
    except Exception as exc:  # noqa: BLE001 - the user's module failed while it was imported: say where
        raise ExtensionError(_failure(name, exc), key=VARIABLE, value=name) from None


def _failure(name: str, exc: BaseException) -> str:
    """The message of a module that failed while it was imported: the error and the innermost line of its code."""
    frames = traceback.extract_tb(exc.__traceback__)
    where = f" ({frames[-1].filename}:{frames[-1].lineno})" if frames else ""
    return f"{VARIABLE}: importing {name!r} failed: {type(exc).__name__}: {exc}{where}"
