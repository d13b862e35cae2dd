"""Kinematics of the robot models: forward and inverse kinematics, Jacobians, tools, URDF.

A layer between the models and everything that needs to know where the tool is: the
controller (TCP pose and speed, register outputs) and the client (``tcp_pose``, Cartesian
moves) both import it, so the client never needs the controller's code. It may import
``models`` and ``protocol`` only (tests/test_layers.py).

The numerical work is done by Pinocchio (the ``pin`` package), a maintained rigid-body
library whose forward kinematics and frame Jacobians are analytic and run in C++.
"""

from __future__ import annotations

from pymotoros.kinematics.chain import (
    BASE,
    BASE_LINK,
    Chain,
    chain_for,
    interpolate_pose,
    matrix_to_pose,
    pose_to_matrix,
    rotation_angle,
)
from pymotoros.kinematics.urdf import urdf_for

__all__ = [
    "BASE",
    "BASE_LINK",
    "Chain",
    "chain_for",
    "interpolate_pose",
    "matrix_to_pose",
    "pose_to_matrix",
    "rotation_angle",
    "urdf_for",
]
