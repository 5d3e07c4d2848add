"""A plain, per-step reference implementation of one NeuralParker environment step (test oracle).

Written from the paper (``neuralparker.tex`` §III, Algorithm 1, App. A) and spec §2/§5 the way a per-step
research environment (such as HOPE's) does it: Python loops, numpy and shapely predicates, no numba and no
code shared with ``np_sim.kernels``. It is the oracle the compiled ``np_sim.env.ParkingVectorEnv`` is compared
against in ``tests/np_sim/test_env_reference.py``.

Only the *data* types of ``np_sim`` are used (``Scene`` and its obstacles, ``EnvConfig`` and its settings,
``VehicleSpec.footprint`` for the rectangle corners); every formula is re-derived here:

* arc transition — paper eq:arc, sampled at arc lengths l·j/n, j = 1..n (n = 30);
* collision — the reference-point convention (strictly inside the boundary polygon, not intersecting any
  polygon obstacle, farther than r from a circle centre) or the footprint convention (rectangle contained in
  the boundary, disjoint from polygons, farther than r from circle centres);
* step reward — eq:step-reward (history terms zero on the first arc); effective steering change —
  eq:effective-kappa; success reward — eq:terminal-reward; failure −2501;
* target frame — eq:target-frame;
* Hermite terminal connector — eq:hermite, eq:hermite-kappa, selection eq:mincost (ensemble of 81) or first
  feasible (fixed nine), gated by sin θ̃ > 0;
* observation — ego state, LiDAR clearances eq:lidar-clearance (rays cast with shapely), obstacle and boundary
  slots in the target frame.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from shapely.geometry import LinearRing, LineString, MultiLineString, Point, Polygon

from np_sim.scene import CircleObstacle, PolygonObstacle

TWO_PI = 2.0 * math.pi


# ---------------------------------------------------------------------------------------------------- basics
def wrap(a: float) -> float:
    """Wrap an angle to (−π, π] (spec §2)."""
    return a - TWO_PI * math.ceil((a - math.pi) / TWO_PI)


def sgn(v: float) -> float:
    """Sign of v as −1, 0 or 1."""
    return 1.0 if v > 0 else (-1.0 if v < 0 else 0.0)


def arc_pose(pose, kappa: float, length: float) -> tuple[float, float, float]:
    """Pose after driving the arc (κ, l) from ``pose`` — paper eq:arc, κ = 0 a straight segment.

    r = 1/|κ|, α = |lκ|, δ_l = sgn(l), δ_κ = sgn(κ):
    x' = x + δ_l[r(1−cos α)δ_κ sin θ + r sin α cos θ], y' = y + δ_l[−r(1−cos α)δ_κ cos θ + r sin α sin θ],
    θ' = θ − δ_κ α (returned wrapped to (−π, π]).
    """
    x, y, th = float(pose[0]), float(pose[1]), float(pose[2])
    if kappa == 0.0:
        return x + length * math.cos(th), y + length * math.sin(th), wrap(th)
    r = 1.0 / abs(kappa)
    alpha = abs(length * kappa)
    dl, dk = sgn(length), sgn(kappa)
    nx = x + dl * (r * (1.0 - math.cos(alpha)) * dk * math.sin(th) + r * math.sin(alpha) * math.cos(th))
    ny = y + dl * (-r * (1.0 - math.cos(alpha)) * dk * math.cos(th) + r * math.sin(alpha) * math.sin(th))
    return nx, ny, wrap(th - dk * alpha)


def arc_samples(pose, kappa: float, length: float, n: int = 30) -> list[tuple[float, float, float]]:
    """The n poses at arc lengths l·j/n, j = 1..n, along the arc (κ, l) (eq:arc); the start is not included."""
    return [arc_pose(pose, kappa, length * j / n) for j in range(1, n + 1)]


def to_target(points, target) -> np.ndarray:
    """eq:target-frame for points (..., 2): q̃ = R(π/2 − θ^g)(q − p^g)."""
    q = np.asarray(points, float)
    a = 0.5 * math.pi - float(target[2])
    c, s = math.cos(a), math.sin(a)
    dx, dy = q[..., 0] - float(target[0]), q[..., 1] - float(target[1])
    return np.stack([c * dx - s * dy, s * dx + c * dy], axis=-1)


def from_target(points, target) -> np.ndarray:
    """Inverse of eq:target-frame: q = p^g + R(θ^g − π/2) q̃."""
    q = np.asarray(points, float)
    a = float(target[2]) - 0.5 * math.pi
    c, s = math.cos(a), math.sin(a)
    return np.stack([c * q[..., 0] - s * q[..., 1] + float(target[0]),
                     s * q[..., 0] + c * q[..., 1] + float(target[1])], axis=-1)


def pose_to_target(pose, target) -> tuple[float, float, float]:
    """(x̃, ỹ, θ̃) of a world pose, θ̃ = wrap(θ − θ^g + π/2) (eq:target-frame)."""
    xy = to_target(np.array([pose[0], pose[1]], float), target)
    return float(xy[0]), float(xy[1]), wrap(float(pose[2]) - float(target[2]) + 0.5 * math.pi)


# ---------------------------------------------------------------------------------------------------- collision
class Checker:
    """Shapely geometry of a scene and the two collision conventions (spec §2)."""

    def __init__(self, scene, vehicle):
        self.scene = scene
        self.vehicle = vehicle
        self.boundary = Polygon(np.asarray(scene.boundary, float))
        self.polygons = [Polygon(np.asarray(o.vertices, float)) for o in scene.obstacles
                         if isinstance(o, PolygonObstacle)]
        self.circles = [(float(o.center[0]), float(o.center[1]), float(o.radius)) for o in scene.obstacles
                        if isinstance(o, CircleObstacle)]
        for g in [self.boundary, *self.polygons]:
            shapely.prepare(g)

    # reference point: strictly inside the boundary, outside (not touching) every polygon, d > r for circles
    def points_valid(self, xy: np.ndarray) -> bool:
        """Every point of (n, 2) valid under the reference-point convention."""
        x, y = xy[:, 0], xy[:, 1]
        if not np.all(shapely.contains_xy(self.boundary, x, y)):
            return False
        for poly in self.polygons:
            if np.any(shapely.intersects_xy(poly, x, y)):
                return False
        for cx, cy, r in self.circles:
            if np.any(np.hypot(x - cx, y - cy) <= r):
                return False
        return True

    def rectangles(self, poses: np.ndarray):
        """Shapely rectangles at (n, 3) poses: the vehicle-frame corners (VehicleSpec.footprint_local) rotated by θ
        and translated to (x, y), i.e. VehicleSpec.footprint(pose) for every pose."""
        local = self.vehicle.footprint_local()
        c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
        xs = poses[:, 0:1] + c * local[None, :, 0] - s * local[None, :, 1]
        ys = poses[:, 1:2] + s * local[None, :, 0] + c * local[None, :, 1]
        return shapely.polygons(np.stack([xs, ys], axis=-1))

    def footprints_valid(self, poses: np.ndarray) -> bool:
        """Every pose of (n, 3) valid under the footprint convention."""
        rects = self.rectangles(poses)
        if not np.all(shapely.contains(self.boundary, rects)):
            return False
        for poly in self.polygons:
            if np.any(shapely.intersects(rects, poly)):
                return False
        for cx, cy, r in self.circles:
            if np.any(shapely.distance(rects, Point(cx, cy)) <= r):
                return False
        return True

    def poses_valid(self, poses: np.ndarray, footprint: bool) -> bool:
        """(n, 3) poses valid under the chosen convention."""
        poses = np.asarray(poses, float).reshape(-1, 3)
        return self.footprints_valid(poses) if footprint else self.points_valid(poses[:, :2])


_CHECKERS: dict = {}


def checker(scene, vehicle) -> Checker:
    """Cached `Checker` per (scene, vehicle)."""
    key = (id(scene), vehicle)
    entry = _CHECKERS.get(key)
    if entry is None or entry.scene is not scene:
        entry = _CHECKERS[key] = Checker(scene, vehicle)
    return entry


def reference_pose_valid(scene, pose, config) -> bool:
    """One pose valid under ``config.collision`` (for sampling start poses by rejection)."""
    return checker(scene, config.vehicle).poses_valid(np.asarray(pose, float), config.collision == "footprint")


# ---------------------------------------------------------------------------------------------------- LiDAR
def _ray_edges(scene) -> MultiLineString:
    """All segments the beams can hit: polygon obstacles, circles as 16-vertex rings (App. A), the boundary."""
    rings = [np.asarray(o.vertices, float) if isinstance(o, PolygonObstacle) else o.ring(16) for o in scene.obstacles]
    rings.append(np.asarray(scene.boundary, float))
    segs = []
    for ring in rings:
        for i in range(len(ring)):
            segs.append([tuple(ring[i]), tuple(ring[(i + 1) % len(ring)])])
    return MultiLineString(segs)


def _rays(pose, n_beams: int, max_range: float):
    """Beam i from the reference point at heading θ + 2πi/n (counter-clockwise), length ``max_range``."""
    x, y, th = float(pose[0]), float(pose[1]), float(pose[2])
    ang = th + TWO_PI * np.arange(n_beams) / n_beams
    return [LineString([(x, y), (x + max_range * math.cos(a), y + max_range * math.sin(a))]) for a in ang]


def _first_hit(origin: Point, rays, geometry, max_range: float) -> np.ndarray:
    hits = shapely.intersection(np.array(rays, dtype=object), geometry)
    d = np.full(len(rays), max_range)
    for i, h in enumerate(hits):
        if not h.is_empty:
            d[i] = min(origin.distance(h), max_range)
    return d


def reference_lidar(scene, pose, n_beams: int = 120, max_range: float = 10.0) -> np.ndarray:
    """Raw ranges d_i of eq:lidar-clearance: distance from the reference point to the first crossing of beam i
    with any obstacle or boundary edge, capped at ``max_range`` (shapely ray ∩ segments)."""
    edges = _ray_edges(scene)
    return _first_hit(Point(float(pose[0]), float(pose[1])), _rays(pose, n_beams, max_range), edges, max_range)


def reference_footprint_ranges(vehicle, pose, n_beams: int = 120, max_range: float = 10.0) -> np.ndarray:
    """b_i of eq:lidar-clearance: distance from the reference point to the vehicle rectangle's boundary along
    beam i (shapely ray ∩ rectangle exterior)."""
    ring = LinearRing(vehicle.footprint(pose))
    return _first_hit(Point(float(pose[0]), float(pose[1])), _rays(pose, n_beams, max_range), ring, max_range)


# ---------------------------------------------------------------------------------------------------- observation
def reference_observation(scene, pose, config) -> np.ndarray:
    """Flat observation (float64) at ``pose``: ego (x̃, ỹ, cos θ̃, sin θ̃) per eq:target-frame, then the
    rectified clearances max(d_i − b_i, 0) (eq:lidar-clearance), then 20 × 16 obstacle slots (target-frame
    vertices; circles as octagons; short polygons repeat cyclically) and 10 × 4 boundary segment slots, with the
    sentinel in unused slots (paper §III-B, App. A); streams switched off in the config are absent."""
    ob = config.observation
    xt, yt, tht = pose_to_target(pose, scene.target)
    parts = [np.array([xt, yt, math.cos(tht), math.sin(tht)])]
    if ob.use_lidar:
        d = reference_lidar(scene, pose, ob.n_beams, ob.lidar_range_m)
        b = reference_footprint_ranges(config.vehicle, pose, ob.n_beams, ob.lidar_range_m)
        parts.append(np.maximum(d - b, 0.0))
    if ob.use_obstacles:
        nv = ob.vertices_per_obstacle
        slots = np.full((ob.max_obstacles, 2 * nv), ob.sentinel)
        for j, o in enumerate(scene.obstacles):
            verts = np.asarray(o.vertices, float) if isinstance(o, PolygonObstacle) else o.octagon()
            local = to_target(verts, scene.target)
            for v in range(nv):
                slots[j, 2 * v: 2 * v + 2] = local[v % len(local)]
        parts.append(slots.reshape(-1))
    if ob.use_boundary:
        slots = np.full((ob.max_boundary_segments, 4), ob.sentinel)
        bnd = np.asarray(scene.boundary, float)
        for i in range(len(bnd)):
            slots[i, 0:2] = to_target(bnd[i], scene.target)
            slots[i, 2:4] = to_target(bnd[(i + 1) % len(bnd)], scene.target)
        parts.append(slots.reshape(-1))
    return np.concatenate(parts)


# ---------------------------------------------------------------------------------------------------- Hermite
def hermite_points(g0, g1, d0, d1, n: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """eq:hermite at t_j = j/(n−1): points g(t_j) (n, 2) and the analytic derivatives g'(t_j) (n, 2).

    g(t) = (2t³−3t²+1)g(0) + (3t²−2t³)g(1) + (t³−2t²+t)g'(0) + (t³−t²)g'(1).
    """
    g0, g1, d0, d1 = (np.asarray(v, float).reshape(1, 2) for v in (g0, g1, d0, d1))
    t = (np.arange(n) / (n - 1)).reshape(-1, 1)
    h00, h01 = 2 * t ** 3 - 3 * t ** 2 + 1, 3 * t ** 2 - 2 * t ** 3
    h10, h11 = t ** 3 - 2 * t ** 2 + t, t ** 3 - t ** 2
    pts = h00 * g0 + h01 * g1 + h10 * d0 + h11 * d1
    dh00, dh01 = 6 * t ** 2 - 6 * t, 6 * t - 6 * t ** 2
    dh10, dh11 = 3 * t ** 2 - 4 * t + 1, 3 * t ** 2 - 2 * t
    ders = dh00 * g0 + dh01 * g1 + dh10 * d0 + dh11 * d1
    return pts, ders


def hermite_curvature(points: np.ndarray, kappa0: float) -> tuple[np.ndarray, float, float]:
    """eq:hermite-kappa on n sampled points (Δt = 1/(n−1)):

    v_j = (g_{j+1} − g_j)/Δt, v̂_j = v_j/‖v_j‖, κ̄_j = ‖v̂_{j+1} − v̂_j‖ / (Δt ‖v_j‖) for j = 0..n−3,
    Δκ_H = |κ0 − κ̄_0| + Σ_{j=1}^{n−3} |κ̄_j − κ̄_{j−1}|, and L_H = Σ‖g_{j+1} − g_j‖ (polyline length).
    A zero-speed sample gives NaN curvature (the caller treats it as infeasible).
    """
    n = len(points)
    dt = 1.0 / (n - 1)
    v = (points[1:] - points[:-1]) / dt
    speed = np.hypot(v[:, 0], v[:, 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        vhat = v / speed[:, None]
        kbar = np.hypot(*(vhat[1:] - vhat[:-1]).T) / (dt * speed[:-1])
    dk = abs(kappa0 - kbar[0]) + float(np.sum(np.abs(kbar[1:] - kbar[:-1])))
    seg = points[1:] - points[:-1]
    length = float(np.sum(np.hypot(seg[:, 0], seg[:, 1])))
    return kbar, float(dk), length


def reference_hermite(scene, pose, kappa0: float, config) -> dict | None:
    """The in-loop Hermite terminal connector at a reached world pose (paper §III-D, Algorithm 1).

    Returns None when the heading gate sin θ̃ > 0 fails or no candidate is feasible; otherwise a dict with the
    selected candidate's ``index``, ``length`` (L_H), ``delta_kappa`` (Δκ_H), ``cost`` (eq:mincost),
    ``forward``, the number of feasible candidates ``n_feasible`` and (diagnostics) the ``first_feasible_index``
    and ``cheapest_index``. Candidates in index order: offset (outer), terminal
    heading, start scale s0, end scale s1 (inner); the fixed connector uses s0 = s1 = 1 (nine candidates) and
    takes the first feasible, the ensemble evaluates all 81 and takes the least eq:mincost (ties → lowest index).
    """
    cn = config.connector
    target = scene.target
    xt, yt, tht = pose_to_target(pose, target)
    if cn.heading_gate and not math.sin(tht) > 0.0:
        return None
    forward = yt < 0.0
    sign = 1.0 if forward else -1.0
    g0 = np.array([xt, yt])
    scales = list(cn.scales) if cn.mode == "ensemble" else [1.0]
    chk = checker(scene, config.vehicle)
    footprint = config.collision == "footprint"
    first = cheapest = None
    feasible = 0
    index = -1
    for off in cn.offsets_m:
        g1 = np.array([float(off), 0.0])
        dist = math.hypot(g1[0] - g0[0], g1[1] - g0[1])
        for hdeg in cn.headings_deg:
            phi = math.radians(hdeg)
            for s0 in scales:
                for s1 in scales:
                    index += 1
                    d0 = sign * s0 * dist * np.array([math.cos(tht), math.sin(tht)])
                    d1 = sign * s1 * dist * np.array([math.cos(phi), math.sin(phi)])
                    pts, ders = hermite_points(g0, g1, d0, d1, cn.n_samples)
                    kbar, dk, length = hermite_curvature(pts, kappa0)
                    kmax = float(np.max(kbar))
                    if not kmax <= cn.kappa_max:  # NaN → infeasible
                        continue
                    world = from_target(pts, target)
                    if footprint:
                        hd = np.arctan2(ders[:, 1], ders[:, 0]) + (0.0 if forward else math.pi)
                        hd = hd + float(target[2]) - 0.5 * math.pi
                        ok = chk.poses_valid(np.column_stack([world, hd]), True)
                    else:
                        ok = chk.points_valid(world)
                    if not ok:
                        continue
                    feasible += 1
                    cost = cn.selection_kappa_weight * dk + cn.selection_length_weight * length + cn.selection_constant
                    cand = {"index": index, "length": length, "delta_kappa": dk, "cost": cost, "forward": forward,
                            "points": world, "kbar_max": kmax}
                    if first is None:
                        first = cand
                    if cheapest is None or cost < cheapest["cost"]:
                        cheapest = cand
    if first is None:
        return None
    # every candidate was evaluated in both modes (the extra fields are diagnostics for the tests)
    chosen = dict(first if cn.mode == "fixed" else cheapest)
    chosen["n_feasible"] = feasible
    chosen["first_feasible_index"] = first["index"]
    chosen["cheapest_index"] = cheapest["index"]
    return chosen


# ---------------------------------------------------------------------------------------------------- the step
def reference_step(scene, pose, prev_kappa: float, prev_length: float, first_arc: bool, n_rev: int,
                   dk_eff: float, n_arcs: int, action, config) -> dict:
    """One environment step (paper Algorithm 1, inner loop body) from world ``pose`` with normalised ``action``.

    Arguments ``prev_kappa``/``prev_length`` are the previous policy arc (ignored when ``first_arc``);
    ``n_rev`` (N_rev) and ``dk_eff`` (Δκ_eff, eq:effective-kappa) are the episode's values over the arcs so far;
    ``n_arcs`` the number of arcs already executed in the episode.

    Order: execute the arc (eq:arc) checked at ``samples_per_arc`` points → step reward (eq:step-reward) →
    invalid: −2501, terminated → directly terminal (0.1 m, 10°): eq:terminal-reward with p_H = 0 → else if
    sin θ̃ > 0, the Hermite connector; a feasible connection adds eq:terminal-reward with
    p_H = −(0.05Δκ_H + 10L_H + 5) (floored at −500 for the ensemble) → truncated after ``max_arcs`` arcs.
    """
    ep, rw, cn = config.episode, config.reward, config.connector
    a0, a1 = float(action[0]), float(action[1])
    kappa = a0 * config.vehicle.kappa_max
    length = a1 * ep.max_length_m
    footprint = config.collision == "footprint"

    samples = arc_samples(pose, kappa, length, ep.samples_per_arc)
    new_pose = np.array(samples[-1], float)
    valid = checker(scene, config.vehicle).poses_valid(np.array(samples), footprint)

    # eq:step-reward
    reward = -rw.length_weight * abs(length) - rw.step_penalty
    reward -= rw.short_arc_weight * max(0.0, rw.short_arc_m - abs(length)) ** 2
    if not first_arc:
        reward -= rw.kappa_change_weight * abs(kappa - prev_kappa)
        if length * prev_length < 0:
            reward -= rw.reversal_penalty
    # N_rev and eq:effective-kappa over the policy arcs so far (including this one)
    if not first_arc:
        if length * prev_length < 0:
            n_rev += 1
        dk_eff += abs(sgn(length) * kappa - sgn(prev_length) * prev_kappa)

    out = {"kappa": kappa, "length": length, "pose": new_pose, "valid": bool(valid), "terminated": False,
           "truncated": False, "success": False, "hermite_index": -1, "hermite_length": 0.0,
           "hermite_delta_kappa": 0.0, "hermite_n_feasible": 0, "hermite_first_not_cheapest": False, "n_rev": n_rev,
           "dk_eff": dk_eff, "n_arcs": n_arcs + 1, "direct": False}

    def success_reward(p_h: float) -> float:  # eq:terminal-reward
        return rw.success_bonus - rw.success_reversal_weight * n_rev - rw.success_kappa_weight * dk_eff \
            + rw.hermite_weight * p_h

    if not valid:
        reward += rw.failure_penalty
        out["terminated"] = True
    else:
        target = scene.target
        dist = math.hypot(new_pose[0] - target[0], new_pose[1] - target[1])
        dth = abs(wrap(new_pose[2] - target[2]))
        if dist <= ep.position_tolerance_m and dth <= math.radians(ep.heading_tolerance_deg):
            reward += success_reward(0.0)
            out.update(terminated=True, success=True, direct=True)
        else:
            conn = reference_hermite(scene, new_pose, kappa, config)
            if conn is not None:
                p_h = -(rw.hermite_kappa_weight * conn["delta_kappa"] + rw.hermite_length_weight * conn["length"]
                        + rw.hermite_constant)
                if cn.mode == "ensemble":
                    p_h = max(p_h, rw.hermite_floor)
                reward += success_reward(p_h)
                out.update(terminated=True, success=True, hermite_index=conn["index"],
                           hermite_length=conn["length"], hermite_delta_kappa=conn["delta_kappa"],
                           hermite_n_feasible=conn["n_feasible"],
                           hermite_first_not_cheapest=conn["first_feasible_index"] != conn["cheapest_index"])
    if not out["terminated"] and n_arcs + 1 >= ep.max_arcs:
        out["truncated"] = True
    out["reward"] = reward
    out["obs"] = reference_observation(scene, new_pose, config)
    return out
