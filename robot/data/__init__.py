"""Files shipped with the package: the mechanism files (URDF) of the repository's ``urdf/`` folder.

``urdf/`` stays a top-level folder of the repository; the build maps it onto the
subpackage ``robot.data.urdf`` (``pyproject.toml``: ``package-dir``), so an
installed wheel carries it. :func:`shipped_urdf_dir` finds it either way: through
``importlib.resources`` when the package is installed, else beside the ``robot``
package in a checkout (``PYTHONPATH=.``, where ``robot/data/urdf`` does not exist).
"""

from __future__ import annotations

import importlib.resources
from pathlib import Path

#: the checkout's folder of mechanism files (``<repository>/urdf``)
CHECKOUT_URDF_DIR = Path(__file__).resolve().parents[2] / "urdf"


def shipped_urdf_dir() -> Path:
    """The folder of the shipped mechanism files (installed package data, or the checkout's ``urdf/``)."""
    installed = Path(str(importlib.resources.files(__name__) / "urdf"))
    if installed.is_dir() and any(installed.glob("*.urdf")):
        return installed
    return CHECKOUT_URDF_DIR


def shipped_urdf(name: str) -> Path:
    """The shipped mechanism file ``name`` (e.g. ``"ups_rps.urdf"``); may not exist (callers check)."""
    return shipped_urdf_dir() / Path(name).name


def shipped_urdf_names() -> list[str]:
    return sorted(p.name for p in shipped_urdf_dir().glob("*.urdf"))
