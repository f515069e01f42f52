"""Quadrotor physics on MuJoCo: vehicle model built in code, propulsion, drag, wind and sensors.

Public API: :class:`World` (``reset``, ``step``, ``advance``) holding :class:`Quadrotor` s
(``apply_pwm``, ``sensors``, ``truth``); :class:`SensorSample` and :class:`Truth` records.
See ``docs/physics.md`` for the model.
"""

# First: imports mujoco without its GLFW context (see mujoco_import.py).
from robosoc.physics import mujoco_import  # noqa: F401
from robosoc.physics.sensors import PositionFix, SensorSample, Truth
from robosoc.physics.world import Quadrotor, World

__all__ = ["PositionFix", "Quadrotor", "SensorSample", "Truth", "World"]
