"""MJCF (MuJoCo XML) generation: the world and each quadrotor, built from :class:`VehicleConfig`.

Per vehicle ``<name>``: a free body ``<name>/body`` whose frame is the body FLU frame (origin at
the rotor plane centre), an explicit ``<inertial>`` (mass, CoM, diagonal inertia; geometry
carries no mass), two capsule skids and the central collision box, plus visual-only arms and rotor
discs (``contype = conaffinity = 0``).  The world has a ground plane at z = 0, gravity 9.8 m/s²
and the 1 ms step.  Propulsion and drag are not MuJoCo actuators: :mod:`robosoc.physics.world`
applies them as a body wrench every step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from xml.sax.saxutils import quoteattr

from robosoc.config.scenario import PHYSICS_DT_S
from robosoc.config.vehicle import VehicleConfig

GRAVITY = 9.8
"""Gravity [m/s²] (quadrotor.md)."""

RENDER_SIZE = (640, 480)
"""Largest offscreen frame (width, height) the model allows."""


def body_name(vehicle: VehicleConfig) -> str:
    """MuJoCo name of the vehicle's free body."""
    return f"{vehicle.name}/body"


def _v(values: Sequence[float]) -> str:
    return " ".join(f"{v:.10g}" for v in values)


def vehicle_xml(vehicle: VehicleConfig) -> str:
    """The ``<body>`` element of one quadrotor."""
    n = vehicle.name
    half_yaw = math.radians(vehicle.spawn_yaw_deg) / 2
    quat = (math.cos(half_yaw), 0.0, 0.0, math.sin(half_yaw))
    skid_z = vehicle.skid_bottom_z + vehicle.skid_radius
    hx = vehicle.skid_half_length
    y = vehicle.skid_offset_y
    arm = vehicle.arm_length
    rotor_r = 0.1
    visual = 'contype="0" conaffinity="0" group="1" mass="0"'
    parts = [
        f'<body name={quoteattr(body_name(vehicle))} pos="{_v(vehicle.spawn_position)}" quat="{_v(quat)}">',
        f"  <freejoint name={quoteattr(n + '/root')}/>",
        f'  <inertial pos="{_v(vehicle.com)}" mass="{vehicle.mass:.10g}" diaginertia="{_v(vehicle.inertia)}"/>',
        f'  <geom name={quoteattr(n + "/hull")} type="box" size="{_v(vehicle.body_half_extents)}" '
        'material="hull" mass="0"/>',
    ]
    for side, sy in (("left", y), ("right", -y)):
        parts.append(
            f'  <geom name={quoteattr(n + "/skid_" + side)} type="capsule" size="{vehicle.skid_radius:.10g}" '
            f'fromto="{_v((-hx, sy, skid_z, hx, sy, skid_z))}" material="skid" mass="0"/>'
        )
        parts.append(
            f'  <geom type="capsule" size="0.004" fromto="{_v((0, sy * 0.8, -0.04, 0, sy, skid_z))}" '
            f'material="skid" {visual}/>'
        )
    for i, (mx, my) in enumerate(((arm, 0.0), (0.0, -arm), (-arm, 0.0), (0.0, arm))):
        parts.append(
            f'  <geom type="capsule" size="0.008" fromto="{_v((0, 0, 0.0, mx, my, 0.0))}" material="arm" {visual}/>'
        )
        material = "rotor_front" if i == 0 else "rotor"
        parts.append(
            f'  <geom name={quoteattr(f"{n}/rotor{i}")} type="cylinder" size="{rotor_r} 0.003" '
            f'pos="{_v((mx, my, 0.02))}" material="{material}" {visual}/>'
        )
    if vehicle.variant == "laser":
        parts.append(f'  <geom type="cylinder" size="0.03 0.03" pos="0 0 -0.07" material="laser" {visual}/>')
    parts.append("</body>")
    return "\n".join(parts)


def world_xml(vehicles: Sequence[VehicleConfig]) -> str:
    """The complete MJCF of a world holding ``vehicles`` (distinct names required).

    Raises:
        ValueError: two vehicles share a name.
    """
    names = [v.name for v in vehicles]
    if len(set(names)) != len(names):
        raise ValueError(f"name: vehicle names must be distinct, got {names}")
    if not vehicles:
        raise ValueError("vehicles: a world needs at least one vehicle")
    width, height = RENDER_SIZE
    bodies = "\n".join(vehicle_xml(v) for v in vehicles)
    first = body_name(vehicles[0])
    return f"""<mujoco model="robosoc">
<compiler angle="radian" autolimits="true"/>
<option timestep="{PHYSICS_DT_S}" gravity="0 0 {-GRAVITY}" integrator="Euler"/>
<visual>
  <global offwidth="{width}" offheight="{height}"/>
  <quality shadowsize="2048"/>
</visual>
<asset>
  <texture name="grid" type="2d" builtin="checker" rgb1=".25 .3 .35" rgb2=".35 .4 .45" width="512" height="512"/>
  <material name="floor" texture="grid" texrepeat="1 1" texuniform="true" reflectance="0"/>
  <material name="hull" rgba=".15 .15 .18 1"/>
  <material name="skid" rgba=".5 .5 .5 1"/>
  <material name="arm" rgba=".2 .2 .25 1"/>
  <material name="rotor" rgba=".7 .7 .75 .5"/>
  <material name="rotor_front" rgba=".9 .3 .2 .6"/>
  <material name="laser" rgba=".1 .3 .8 1"/>
</asset>
<worldbody>
  <light name="sun" pos="0 0 6" dir="0.3 0.2 -1" directional="true" castshadow="false"/>
  <light name="spot" mode="trackcom" pos="0 0 4" dir="0 0 -1" diffuse=".4 .4 .4"/>
  <geom name="ground" type="plane" size="50 50 0.1" material="floor"/>
  <camera name="chase" mode="targetbody" target={quoteattr(first)} pos="-3.0 -3.0 2.2"/>
{bodies}
</worldbody>
</mujoco>
"""
