"""A scene as a MuJoCo world (spec §8): ground, extruded obstacles, circle cylinders, boundary walls, the vehicle.

Geom names say what a contact touched: ``obstacle_<i>`` (or ``obstacle_<i>_<k>`` for the k-th convex piece of a
non-convex obstacle ``i`` in scene order), ``wall_<e>_<k>`` for boundary edge ``e`` (vertex e → e+1 as the scene
gives it), ``<mover name>`` (or ``<mover name>_<k>``) for a moving object (`tracking.movers.Mover`, a mocap body
whose pose `World.move_objects` sets). Full-footprint contact = any contact of the vehicle's chassis box with one
of these geoms. With ``WorldConfig.solid_obstacles=False`` these geoms only detect: contacts are listed, no force.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from np_sim.scene import CircleObstacle, Scene
from tracking.config import TrackerConfig
from tracking.errors import TrackingError
from tracking.geometry import convex_pieces, wall_pieces
from tracking.mjcf import half_track_m, vehicle_xml
from tracking.movers import Mover

_OBSTACLE_BITS = 'contype="2" conaffinity="0"'
"""Collision bits of obstacles and walls (see models/mjcf/vehicle_template.xml)."""
_TOUCHABLE = ("obstacle_", "wall_", "mover_")
"""Name prefixes of the geoms whose chassis contacts are body contacts."""


_DETECTION_BITS = 'contype="0" conaffinity="0"'
"""Detection-only obstacles and walls collide with nothing; `World.body_contacts` measures their overlaps."""


def _obstacle_attributes(config: TrackerConfig) -> str:
    """Collision attributes of obstacles, movers and walls: solid, or detection only (no collision)."""
    return _OBSTACLE_BITS if config.world.solid_obstacles else _DETECTION_BITS


def _prism_mesh(name: str, ring: np.ndarray, height: float) -> tuple[str, np.ndarray]:
    """A mesh asset of the ring extruded from z = 0 to ``height``, vertices relative to the ring's mean point,
    and that point (the geom position)."""
    centre = ring.mean(axis=0)
    local = ring - centre
    verts = np.concatenate([np.column_stack([local, np.zeros(len(local))]),
                            np.column_stack([local, np.full(len(local), height)])])
    text = " ".join(f"{v:.9g}" for v in verts.ravel())
    return f'<mesh name="{name}" vertex="{text}"/>', centre


def scene_xml(scene: Scene, config: TrackerConfig, movers: tuple[Mover, ...] = ()) -> str:
    """World MJCF (including ``vehicle.xml``) for ``scene`` and ``movers`` (mocap bodies at their first pose):
    geometry, lights, ground and a top-down camera. Off-screen frames have no shadows and no multisampling (Mesa
    renders on the CPU, and 4× multisampling about doubled the cost of a frame)."""
    wc = config.world
    bits = _obstacle_attributes(config)
    assets, geoms = [], []

    def prism(name: str, ring: np.ndarray, height: float, rgba: str, into: list[str] = geoms) -> None:
        mesh, centre = _prism_mesh(name, ring, height)
        assets.append(mesh)
        into.append(f'<geom name="{name}" type="mesh" mesh="{name}" pos="{centre[0]:.9g} {centre[1]:.9g} 0" '
                    f'{bits} rgba="{rgba}"/>')

    for i, obstacle in enumerate(scene.obstacles):
        if isinstance(obstacle, CircleObstacle):
            cx, cy = obstacle.center
            geoms.append(f'<geom name="obstacle_{i}" type="cylinder" size="{obstacle.radius:.9g} '
                         f'{0.5 * wc.obstacle_height_m:.9g}" pos="{cx:.9g} {cy:.9g} {0.5 * wc.obstacle_height_m:.9g}" '
                         f'{bits} rgba="0.3 0.4 0.8 1"/>')
            continue
        pieces = convex_pieces(obstacle.vertices)
        for k, piece in enumerate(pieces):
            name = f"obstacle_{i}" if len(pieces) == 1 else f"obstacle_{i}_{k}"
            prism(name, piece, wc.obstacle_height_m, "0.3 0.4 0.8 1")
    counts: dict[int, int] = {}
    for edge, piece in wall_pieces(scene.boundary, wc.wall_thickness_m):
        k = counts[edge] = counts.get(edge, -1) + 1
        prism(f"wall_{edge}_{k}", piece, wc.wall_height_m, "0.55 0.55 0.55 1")
    for mover in movers:
        if not mover.name.startswith("mover_"):
            raise TrackingError(f"scene_xml: mover names must start with 'mover_', got {mover.name!r}")
        x, y, yaw = mover.poses[0]
        body: list[str] = []
        pieces = convex_pieces(mover.outline)
        for k, piece in enumerate(pieces):
            prism(mover.name if len(pieces) == 1 else f"{mover.name}_{k}", piece, wc.obstacle_height_m,
                  "0.8 0.3 0.6 1", body)
        geoms.append(f'<body name="{mover.name}" mocap="true" pos="{x:.9g} {y:.9g} 0" '
                     f'quat="{math.cos(0.5 * yaw):.9g} 0 0 {math.sin(0.5 * yaw):.9g}">{"".join(body)}</body>')

    lo, hi = scene.boundary.min(axis=0), scene.boundary.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo) + wc.wall_thickness_m + 1.0
    fovy_deg = 60.0
    # top-down camera height so that the larger half-extent fits the vertical field of view (4:3 frames)
    height = max(half[1], half[0] * 0.75) / math.tan(math.radians(0.5 * fovy_deg))
    return f"""<mujoco model="neuralparker_world">
  <include file="vehicle.xml"/>
  <visual>
    <quality shadowsize="0" offsamples="0"/>
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
    """Total vehicle mass m (kg), of the nominal vehicle when ``config.plant`` carries a payload (the masses the
    controllers assume)."""
    com_ahead_m: float
    """Distance a of the vehicle's centre of mass ahead of the reference point (m)."""
    yaw_inertia_kgm2: float
    """Vehicle moment of inertia about the vertical axis through its centre of mass, I_z (kg·m²)."""
    steer_qpos: tuple[int, int]
    """qpos addresses of the left and right steering hinges."""
    movers: tuple[Mover, ...] = ()
    """Moving objects."""
    mocap_ids: tuple[int, ...] = ()
    """Mocap index of each mover's body."""

    def move_objects(self, t: float) -> None:
        """Place every mover's mocap body at its pose at sim time ``t`` (s)."""
        for k, mover in zip(self.mocap_ids, self.movers):
            x, y, yaw = mover.pose_at(t)
            self.data.mocap_pos[k, :2] = (x, y)
            self.data.mocap_quat[k] = (math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw))

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
        """(geom name, world contact position) of every current chassis contact with an obstacle, mover or wall.

        Solid obstacles: MuJoCo's contacts of the chassis. Detection only: every touchable geom whose bounding
        sphere meets the chassis's is measured with ``mj_geomDistance``; a negative signed distance (overlap) is a
        contact at the midpoint of the penetration segment."""
        if not self.config.world.solid_obstacles:
            return self._overlaps()
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

    def _overlaps(self) -> list[tuple[str, np.ndarray]]:
        m, d, chassis = self.model, self.data, self.chassis_geom
        ids = np.fromiter(self.geom_names, dtype=int, count=len(self.geom_names))
        if len(ids) == 0:
            return []
        reach = m.geom_rbound[ids] + m.geom_rbound[chassis]
        near = ids[np.sum((d.geom_xpos[ids] - d.geom_xpos[chassis]) ** 2, axis=1) < reach * reach]
        out = []
        fromto = np.zeros(6)
        for g in near:
            if mujoco.mj_geomDistance(m, d, chassis, int(g), 0.0, fromto) < 0.0:
                out.append((self.geom_names[int(g)], 0.5 * (fromto[:3] + fromto[3:])))
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


def build_world(scene: Scene, start, config: TrackerConfig | None = None, movers: tuple[Mover, ...] = ()) -> World:
    """Compile ``scene`` and ``movers`` with the vehicle of ``config`` at rest at ``start`` (reference-point pose)."""
    config = TrackerConfig() if config is None else config
    movers = tuple(movers)
    assets = {"vehicle.xml": vehicle_xml(config.vehicle, config.model, config.plant).encode()}
    model = mujoco.MjModel.from_xml_string(scene_xml(scene, config, movers), assets=assets)
    data = mujoco.MjData(model)
    names = {}
    for g in range(model.ngeom):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or ""
        if name.startswith(_TOUCHABLE):
            names[g] = name
    if config.plant.payload_kg:  # the controllers' feed-forward keeps the nominal vehicle's masses
        nominal = mujoco.MjModel.from_xml_string(vehicle_xml(config.vehicle, config.model))
        mass, com_ahead, yaw_inertia = _mass_properties(nominal, mujoco.MjData(nominal))
    else:
        mass, com_ahead, yaw_inertia = _mass_properties(model, data)
    world = World(model=model, data=data, scene=scene, config=config,
                  chassis_geom=mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "chassis"), geom_names=names,
                  half_track_m=half_track_m(config.vehicle, config.model), mass_kg=mass, com_ahead_m=com_ahead,
                  yaw_inertia_kgm2=yaw_inertia,
                  steer_qpos=tuple(int(model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j)])
                                   for j in ("steer_fl", "steer_fr")), movers=movers,
                  mocap_ids=tuple(int(model.body_mocapid[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, m.name)])
                                  for m in movers))
    world.set_pose(start)
    return world
