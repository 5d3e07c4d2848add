"""A scene as a MuJoCo world (SPEC §8): ground, extruded obstacles, circle cylinders, boundary walls, the vehicle.

Geom names say what a contact touched: ``obstacle_<i>`` (or ``obstacle_<i>_<k>`` for the k-th convex piece of a
non-convex obstacle ``i`` in scene order), ``wall_<e>_<k>`` for boundary edge ``e`` (vertex e → e+1 as the scene
gives it). Full-footprint contact = any contact of the vehicle's chassis box with one of these geoms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from np_sim.scene import CircleObstacle, Scene
from tracking.config import TrackerConfig
from tracking.geometry import convex_pieces, wall_pieces
from tracking.mjcf import half_track_m, vehicle_xml

_OBSTACLE_BITS = 'contype="2" conaffinity="0"'
"""Collision bits of obstacles and walls (see models/mjcf/vehicle_template.xml)."""


def _prism_mesh(name: str, ring: np.ndarray, height: float) -> tuple[str, np.ndarray]:
    """A mesh asset of the ring extruded from z = 0 to ``height``, vertices relative to the ring's mean point,
    and that point (the geom position)."""
    centre = ring.mean(axis=0)
    local = ring - centre
    verts = np.concatenate([np.column_stack([local, np.zeros(len(local))]),
                            np.column_stack([local, np.full(len(local), height)])])
    text = " ".join(f"{v:.9g}" for v in verts.ravel())
    return f'<mesh name="{name}" vertex="{text}"/>', centre


def scene_xml(scene: Scene, config: TrackerConfig) -> str:
    """World MJCF (including ``vehicle.xml``) for ``scene``: geometry, lights, ground and a top-down camera."""
    wc = config.world
    assets, geoms = [], []

    def prism(name: str, ring: np.ndarray, height: float, rgba: str) -> None:
        mesh, centre = _prism_mesh(name, ring, height)
        assets.append(mesh)
        geoms.append(f'<geom name="{name}" type="mesh" mesh="{name}" pos="{centre[0]:.9g} {centre[1]:.9g} 0" '
                     f'{_OBSTACLE_BITS} rgba="{rgba}"/>')

    for i, obstacle in enumerate(scene.obstacles):
        if isinstance(obstacle, CircleObstacle):
            cx, cy = obstacle.center
            geoms.append(f'<geom name="obstacle_{i}" type="cylinder" size="{obstacle.radius:.9g} '
                         f'{0.5 * wc.obstacle_height_m:.9g}" pos="{cx:.9g} {cy:.9g} {0.5 * wc.obstacle_height_m:.9g}" '
                         f'{_OBSTACLE_BITS} rgba="0.3 0.4 0.8 1"/>')
            continue
        pieces = convex_pieces(obstacle.vertices)
        for k, piece in enumerate(pieces):
            name = f"obstacle_{i}" if len(pieces) == 1 else f"obstacle_{i}_{k}"
            prism(name, piece, wc.obstacle_height_m, "0.3 0.4 0.8 1")
    counts: dict[int, int] = {}
    for edge, piece in wall_pieces(scene.boundary, wc.wall_thickness_m):
        k = counts[edge] = counts.get(edge, -1) + 1
        prism(f"wall_{edge}_{k}", piece, wc.wall_height_m, "0.55 0.55 0.55 1")

    lo, hi = scene.boundary.min(axis=0), scene.boundary.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo) + wc.wall_thickness_m + 1.0
    fovy_deg = 60.0
    # top-down camera height so that the larger half-extent fits the vertical field of view (4:3 frames)
    height = max(half[1], half[0] * 0.75) / math.tan(math.radians(0.5 * fovy_deg))
    return f"""<mujoco model="neuralparker_world">
  <include file="vehicle.xml"/>
  <visual>
    <quality shadowsize="0"/>
    <global offwidth="{config.executor.render_width}" offheight="{config.executor.render_height}"/>
    <map znear="0.05" zfar="{4 * height + 100:.1f}"/>
  </visual>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.82 0.82 0.8" rgb2="0.74 0.74 0.72" width="64" height="64"/>
    <material name="ground" texture="grid" texrepeat="1 1" texuniform="true"/>
    {" ".join(assets)}
  </asset>
  <worldbody>
    <light name="sun" pos="{centre[0]:.3f} {centre[1]:.3f} {height + 20:.1f}" dir="0 0 -1" directional="true"/>
    <geom name="ground" type="plane" size="0 0 1" material="ground" contype="1" conaffinity="0" condim="3"/>
    <camera name="topdown" pos="{centre[0]:.6g} {centre[1]:.6g} {height:.6g}" xyaxes="1 0 0 0 1 0" fovy="{fovy_deg}"/>
    {"".join(geoms)}
  </worldbody>
</mujoco>"""


@dataclass
class World:
    """A compiled scene world with the vehicle, and the ids the executor needs."""

    model: mujoco.MjModel
    data: mujoco.MjData
    scene: Scene
    config: TrackerConfig
    chassis_geom: int
    """Geom id of the chassis box (the footprint)."""
    geom_names: dict[int, str]
    """Obstacle and wall geom id → name."""
    half_track_m: float
    """Lateral offset of the wheel centres (m), for the Ackermann angles."""
    mass_kg: float
    """Total vehicle mass m (kg)."""
    com_ahead_m: float
    """Distance a of the vehicle's centre of mass ahead of the reference point (m)."""
    yaw_inertia_kgm2: float
    """Vehicle moment of inertia about the vertical axis through its centre of mass, I_z (kg·m²)."""
    steer_qpos: tuple[int, int]
    """qpos addresses of the left and right steering hinges."""

    def pose(self) -> np.ndarray:
        """[x, y, θ] of the reference point (the free joint origin) and its yaw."""
        q = self.data.qpos
        w, x, y, z = q[3], q[4], q[5], q[6]
        return np.array([q[0], q[1], math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))])

    def speed(self, heading: float) -> float:
        """Signed speed of the reference point along the heading (m/s); negative in reverse."""
        v = self.data.qvel
        return v[0] * math.cos(heading) + v[1] * math.sin(heading)

    def effective_mass(self, steer_curvature: float) -> float:
        """Inertia felt along the path by the rear-axle speed v at steering curvature c (kg).

        Without slip the yaw rate is ω = v·c and the centre of mass, a ahead of the rear axle, moves at
        v·√(1 + a²c²), so the kinetic energy ½m v²(1 + a²c²) + ½I_z v²c² gives m_eff = m(1 + a²c²) + I_z c².
        """
        c2 = steer_curvature * steer_curvature
        return self.mass_kg * (1.0 + self.com_ahead_m ** 2 * c2) + self.yaw_inertia_kgm2 * c2

    def set_pose(self, pose) -> None:
        """Place the vehicle at rest at the reference-point pose (x, y, θ), wheels on the ground, straight steering."""
        x, y, th = (float(v) for v in pose)
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:7] = [x, y, self.config.model.wheel_radius_m, math.cos(0.5 * th), 0.0, 0.0, math.sin(0.5 * th)]
        mujoco.mj_forward(self.model, self.data)

    def apply(self, steer_curvature: float, wheel_torque_nm: float) -> None:
        """Set the two steering servos to the Ackermann angles of ``steer_curvature`` and both rear drive torques."""
        lc = self.config.vehicle.wheelbase_m * steer_curvature  # scalar form of ackermann_angles
        ct = steer_curvature * self.half_track_m
        self.data.ctrl[:] = (math.atan2(lc, 1.0 - ct), math.atan2(lc, 1.0 + ct), wheel_torque_nm, wheel_torque_nm)

    def steer_angle(self) -> float:
        """Bicycle steering angle atan(L·c) of the current front-wheel joint angles (mean of their curvatures)."""
        L, t = self.config.vehicle.wheelbase_m, self.half_track_m
        left, right = self.data.qpos[self.steer_qpos[0]], self.data.qpos[self.steer_qpos[1]]
        # invert atan2(L c, 1 ∓ c t) per wheel: c = tan δ / (L ± t tan δ)
        c = 0.5 * (math.tan(left) / (L + t * math.tan(left)) + math.tan(right) / (L - t * math.tan(right)))
        return math.atan(L * c)

    def body_contacts(self) -> list[tuple[str, np.ndarray]]:
        """(geom name, world contact position) of every current chassis contact with an obstacle or wall."""
        d = self.data
        if d.ncon == 0:
            return []
        pairs = d.contact.geom
        hits = np.flatnonzero((pairs[:, 0] == self.chassis_geom) | (pairs[:, 1] == self.chassis_geom))
        out = []
        for h in hits:
            other = int(pairs[h, 1] if pairs[h, 0] == self.chassis_geom else pairs[h, 0])
            out.append((self.geom_names.get(other, mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_GEOM, other)),
                        d.contact.pos[h].copy()))
        return out


def _mass_properties(model: mujoco.MjModel, data: mujoco.MjData) -> tuple[float, float, float]:
    """(m, a, I_z) of the vehicle's bodies at the model's rest pose (vehicle at the origin, heading +x, wheels
    straight): total mass, centre-of-mass x, and Σ (I_zz,b + m_b·((x_b − a)² + y_b²)) (parallel-axis theorem)."""
    mujoco.mj_resetData(model, data)
    mujoco.mj_forward(model, data)
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "vehicle")
    bodies = [b for b in range(model.nbody) if model.body_rootid[b] == root]
    m = model.body_mass[bodies]
    com = data.xipos[bodies, :2] - data.xpos[root, :2]
    mass = float(m.sum())
    a = float(m @ com[:, 0] / mass)
    inertia_z = np.array([(data.ximat[b].reshape(3, 3) @ np.diag(model.body_inertia[b])
                           @ data.ximat[b].reshape(3, 3).T)[2, 2] for b in bodies])
    yaw = float(inertia_z.sum() + m @ ((com[:, 0] - a) ** 2 + com[:, 1] ** 2))
    return mass, a, yaw


def build_world(scene: Scene, start, config: TrackerConfig | None = None) -> World:
    """Compile ``scene`` with the vehicle of ``config`` at rest at ``start`` (reference-point pose)."""
    config = TrackerConfig() if config is None else config
    assets = {"vehicle.xml": vehicle_xml(config.vehicle, config.model).encode()}
    model = mujoco.MjModel.from_xml_string(scene_xml(scene, config), assets=assets)
    data = mujoco.MjData(model)
    names = {}
    for g in range(model.ngeom):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or ""
        if name.startswith(("obstacle_", "wall_")):
            names[g] = name
    mass, com_ahead, yaw_inertia = _mass_properties(model, data)
    world = World(model=model, data=data, scene=scene, config=config,
                  chassis_geom=mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "chassis"), geom_names=names,
                  half_track_m=half_track_m(config.vehicle, config.model), mass_kg=mass, com_ahead_m=com_ahead,
                  yaw_inertia_kgm2=yaw_inertia,
                  steer_qpos=tuple(int(model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j)])
                                   for j in ("steer_fl", "steer_fr")))
    world.set_pose(start)
    return world
