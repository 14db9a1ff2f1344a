"""Equations of motion: Lagrange multipliers, Baumgarte, contact forces, Jacobians."""
