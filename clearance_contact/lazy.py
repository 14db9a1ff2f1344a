"""Lazy public names of a package (PEP 562): ``import package`` stays cheap, a name loads its module on first use.

Used by ``clearance_contact``, ``robot`` and ``robot.sweep``::

    __getattr__, __dir__ = lazy_exports(__name__, globals(), {"Name": ".module", ...})
"""

from __future__ import annotations

from importlib import import_module
from typing import Any, Callable, Mapping


def lazy_exports(package: str, namespace: dict[str, Any], public: Mapping[str, str]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package``: each name of ``public`` comes from its module (absolute or relative)."""

    def __getattr__(name: str) -> Any:
        if name in public:
            value = getattr(import_module(public[name], package), name)
            namespace[name] = value  # later look-ups are plain attribute reads
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(public))

    return __getattr__, __dir__
