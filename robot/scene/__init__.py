"""Scenes: TOML files and run configuration (no Pinocchio)."""
