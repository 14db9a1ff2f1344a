"""URDF -> Pinocchio model: mechanism description, closures, kinematics, drives."""
