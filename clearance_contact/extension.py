"""Import a compiled extension module from a file (the kernel library's, scipy's LAPACK module), not from ``sys.path``."""

from __future__ import annotations

import importlib.machinery
import importlib.util
from pathlib import Path

__all__ = ["import_extension"]


def import_extension(name: str, path: Path):
    """Import the extension module file ``path`` as ``name`` (not entered in ``sys.modules``).

    ``name``'s last part must be the one the module was compiled with (its ``PyInit_``
    function). Raises ``ImportError`` or ``OSError`` as the import system does.
    """
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    module = importlib.util.module_from_spec(importlib.util.spec_from_file_location(name, path, loader=loader))
    loader.exec_module(module)
    return module
