"""quadwalk's scene in MuJoCo: a second engine to check policies in.

The robot is quadwalk's own Laikago (the URDF quadwalk builds its rapier
model from, ``quadwalk.LAIKAGO_URDF``: primitive collision shapes, 25.6 kg)
on a free joint, its twelve joints driven by MuJoCo position actuators with
quadwalk's PD gains and effort limits (tau = kp (q* - q) - kd q', clipped
to the URDF's effort), friction as quadwalk's ``[physics]``; the ground is a
plane, or quadwalk's elastic tiles: 19.8 cm boxes on a 20 cm pitch, each on
a vertical slide joint with MuJoCo's joint spring k = m g / (4 d) (m the
robot's mass, d the named sink), damping c = 2 zeta sqrt(k (m_tile + m /
4)), a 15 cm travel, and a spring reference that rests an unloaded tile at
the surface. Time step 1/240 s, the implicit-fast integrator.

``MujocoRobot`` has the interface of ``quadwalk.Sim`` (``reset``,
``state``, ``step``), so ``quadwalk.Controller`` drives either: the
state's feet come from the joint angles by quadwalk's forward kinematics,
as on a robot. ``fall()`` applies quadwalk's termination rules (mean hip
height below ``min_base_height_m``, pitch beyond ``max_pitch_deg``, a
contact of a link other than a lower leg or toe with the ground).

Needs the ``mujoco`` package (``pip install quadwalk[mujoco]``).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from . import LAIKAGO_URDF

G = 9.81
ROBOT, TERRAIN = (1, 2), (2, 1)  # (contype, conaffinity): the robot touches the terrain only


def _parse_terrain(spec: str) -> float | None:
    """The sink of ``elastic:Xcm`` in metres, None for ``rigid``."""
    if spec == "rigid":
        return None
    if spec.startswith("elastic:") and spec.endswith("cm"):
        try:
            depth_cm = float(spec[len("elastic:"):-2])
        except ValueError:
            depth_cm = float("nan")
        if depth_cm > 0:
            return depth_cm / 100.0
    raise ValueError(f"terrain {spec!r}: the MuJoCo scene has rigid and elastic:<depth>cm")


class MujocoRobot:
    """quadwalk's robot and ground in MuJoCo, stepped at quadwalk's 240 Hz."""

    #: one step, s (what ``quadwalk.run_phase`` checks against the controller's)
    dt_secs = 1.0 / 240.0

    def __init__(
        self,
        terrain: str = "rigid",
        kp_n_m_per_rad: float = 600.0,
        kd_n_m_s_per_rad: float = 8.0,
        friction: float = 1.0,
        length_m: float = 24.0,
        back_m: float = 2.0,
        width_m: float = 1.6,
        tile_pitch_m: float = 0.2,
        tile_gap_m: float = 0.002,
        tile_mass_kg: float = 0.5,
        tile_damping_ratio: float = 0.5,
        tile_travel_m: float = 0.15,
        settle_secs: float = 0.5,
        min_base_height_m: float = 0.2,
        max_pitch_deg: float = 15.0,
    ):
        self.terrain = terrain
        self.sink_m = _parse_terrain(terrain)
        self.settle_secs = settle_secs
        self.min_base_height_m = min_base_height_m
        self.max_pitch_deg = max_pitch_deg
        spec = mujoco.MjSpec.from_string(LAIKAGO_URDF)
        spec.body("chassis").add_freejoint()
        spec.option.timestep = self.dt_secs
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        for g in spec.geoms:
            g.contype, g.conaffinity = ROBOT
            g.friction = [friction, 0.005, 0.0001]
        self.joint_names = [j.name for j in spec.joints if j.type == mujoco.mjtJoint.mjJNT_HINGE]
        efforts = {j.name: 100.0 for j in spec.joints}
        for name in self.joint_names:
            a = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
            a.set_to_position(kp=kp_n_m_per_rad, kv=kd_n_m_s_per_rad)
            a.forcelimited, a.forcerange = True, [-efforts[name], efforts[name]]
        self.robot_mass_kg = float(spec.compile().body_subtreemass[1])
        wb = spec.worldbody
        self.tile_centres = np.zeros((0, 2))
        if self.sink_m is None:
            wb.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[length_m + back_m, width_m, 0.1],
                        contype=TERRAIN[0], conaffinity=TERRAIN[1], friction=[friction, 0.005, 0.0001])
        else:
            k = self.robot_mass_kg * G / (4 * self.sink_m)
            c = 2 * tile_damping_ratio * math.sqrt(k * (tile_mass_kg + self.robot_mass_kg / 4))
            self.stiffness_n_per_m, self.damping_n_s_per_m = k, c
            half = (tile_pitch_m - tile_gap_m) / 2
            xs = np.arange(-back_m + tile_pitch_m / 2, length_m, tile_pitch_m)
            ys = np.arange(-width_m / 2 + tile_pitch_m / 2, width_m / 2, tile_pitch_m)
            self.tile_centres = np.array([(x, y) for x in xs for y in ys])
            self._grid = (xs[0], ys[0], tile_pitch_m, len(xs), len(ys))
            for i, (x, y) in enumerate(self.tile_centres):
                b = wb.add_body(name=f"tile{i}", pos=[x, y, -0.05])
                b.add_joint(name=f"tile{i}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1],
                            stiffness=k, damping=c, springref=tile_mass_kg * G / k,
                            limited=True, range=[-tile_travel_m, tile_mass_kg * G / k])
                b.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[half, half, 0.05], mass=tile_mass_kg,
                           contype=TERRAIN[0], conaffinity=TERRAIN[1], friction=[friction, 0.005, 0.0001])
        self.m = spec.compile()
        self.d = mujoco.MjData(self.m)
        self._qadr = np.array([self.m.joint(n).qposadr[0] for n in self.joint_names])
        self._vadr = np.array([self.m.joint(n).dofadr[0] for n in self.joint_names])
        self._act = [self.joint_names.index(self.m.actuator(i).name) for i in range(self.m.nu)]
        self._tile_qadr = np.array([self.m.joint(f"tile{i}").qposadr[0] for i in range(len(self.tile_centres))],
                                   dtype=int)
        self.chassis = self.m.body("chassis").id
        feet_bodies = {self.m.body(n).id for n in range(self.m.nbody)
                       if self.m.body(n).name.endswith("lower_leg")}
        self._robot_geoms = {g for g in range(self.m.ngeom) if self.m.geom_contype[g] == ROBOT[0]}
        self._foot_geoms = {g for g in self._robot_geoms if self.m.geom_bodyid[g] in feet_bodies}
        self._toes = [g for g in sorted(self._robot_geoms) if self.m.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE]

    # --- the ground -------------------------------------------------------

    def surface_height_m(self, x: float, y: float) -> float:
        """The ground's height under (x, y): 0 on the plane; the top of the
        nearest tile (negative where it sank)."""
        if self.sink_m is None:
            return 0.0
        x0, y0, pitch, nx, ny = self._grid
        ix = min(max(round((x - x0) / pitch), 0), nx - 1)
        iy = min(max(round((y - y0) / pitch), 0), ny - 1)
        return float(self.d.qpos[self._tile_qadr[ix * ny + iy]])

    def foot_sinks_m(self) -> list[float]:
        """How far the tile under each toe sank (0 on the plane), m."""
        return [-self.surface_height_m(*self.d.geom_xpos[g][:2]) for g in self._toes]

    # --- the interface of quadwalk.Sim ------------------------------------

    def reset(self, start_xy_m, squat_rad, hips_in_base_m=None):
        """The robot in its squat (``squat_rad``, quadwalk's joint order) at
        ``start_xy_m`` heading +x, toes 2 mm above the ground, tiles at rest,
        held there for ``settle_secs`` as quadwalk's episode start does."""
        d = self.d
        mujoco.mj_resetData(self.m, d)
        d.qpos[self._qadr] = squat_rad
        d.qpos[3:7] = [1, 0, 0, 0]
        d.qpos[0:3] = [start_xy_m[0], start_xy_m[1], 1.0]
        mujoco.mj_kinematics(self.m, d)
        lowest = min(d.geom_xpos[g][2] - self.m.geom_size[g][0] for g in self._toes)
        d.qpos[2] -= lowest - 0.002
        d.ctrl[:] = [squat_rad[i] for i in self._act]
        mujoco.mj_forward(self.m, d)
        for _ in range(round(self.settle_secs * 240)):
            mujoco.mj_step(self.m, d)
        self.hips_in_base_m = np.asarray(hips_in_base_m) if hips_in_base_m is not None else None

    def step(self, targets_rad):
        """Sets the PD targets (rad, quadwalk's joint order) and takes one 1/240 s step."""
        self.d.ctrl[:] = [targets_rad[i] for i in self._act]
        mujoco.mj_step(self.m, self.d)

    def base_pose(self):
        """The chassis position and rotation matrix (world)."""
        return self.d.xpos[self.chassis].copy(), self.d.xmat[self.chassis].reshape(3, 3).copy()

    def state(self) -> dict:
        """The measured state ``quadwalk.Controller`` reads (feet from the
        joint angles; hip heights from ``hips_in_base_m`` given to ``reset``)."""
        d = self.d
        w, x, y, z = d.qpos[3:7]
        position, rotation = self.base_pose()
        hips = position + (rotation @ self.hips_in_base_m.T).T
        return {
            "base_position_m": position,
            "base_orientation_xyzw": [x, y, z, w],
            "base_linear_velocity_m_per_s": d.qvel[0:3].copy(),
            # a free joint's angular velocity is in the body frame
            "base_angular_velocity_rad_per_s": rotation @ d.qvel[3:6],
            "joint_angles_rad": d.qpos[self._qadr].copy(),
            "joint_velocities_rad_per_s": d.qvel[self._vadr].copy(),
            "hip_heights_m": [h[2] - self.surface_height_m(h[0], h[1]) for h in hips],
            "centre_of_mass_m": d.subtree_com[self.chassis].copy(),
        }

    def fall(self) -> str | None:
        """quadwalk's termination rules on the current state: the cause, or None."""
        s = self.state()
        height = float(np.mean(s["hip_heights_m"]))
        if height < self.min_base_height_m:
            return "base_too_low"
        _, rotation = self.base_pose()
        pitch = math.degrees(math.asin(max(-1.0, min(1.0, -rotation[2, 0]))))
        if abs(pitch) > self.max_pitch_deg:
            return "pitch_too_large"
        for c in self.d.contact[: self.d.ncon]:
            for g in (c.geom1, c.geom2):
                if g in self._robot_geoms and g not in self._foot_geoms:
                    other = c.geom2 if g == c.geom1 else c.geom1
                    if other not in self._robot_geoms:
                        return "non_foot_contact"
        return None
