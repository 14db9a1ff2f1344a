"""Pictures of a sweep (placeholder; drawing functions follow)."""

from __future__ import annotations

FIGURES: dict = {}


def check_figures(spec) -> None:
    return None
