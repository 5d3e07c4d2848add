"""Ego-aligned bird's-eye-view (BEV) raster of a parking scene (paper App. B, "Controlled Representation Inputs";
spec §7): the image input of the BEV controls of the scene-representation ablation.

Two calls, both returning RGB images as ``uint8`` arrays, channels first (divide by 255 for the network input)::

    render_bev(scene, pose, tail=None, config=BevConfig(), vehicle=VehicleSpec())      -> (3, 64, 64)
    render_bev_batch(arrays, scene_index, poses, tails=None, n_tail=None,
                     config=BevConfig(), vehicle=VehicleSpec())                          -> (N, 3, 64, 64)

``scene`` is a `np_sim.scene.Scene`; ``arrays`` a `np_sim.scene_arrays.SceneArrays` (``pack_scenes``) with
``scene_index`` (N,) naming each image's scene; ``pose`` / ``poses`` are reference-point (rear-axle) poses
(x, y, θ) in the scene's world frame. ``tail`` is the trajectory tail: earlier poses of the episode, oldest
first, not including ``pose``; ``tails`` is (N, T, 3) with ``n_tail`` (N,) valid rows per image (the first
``n_tail[i]`` rows, oldest first). ``tail=None`` or an empty tail draws none.

The raster (facts of HOPE's published renderer, ``jiamiya/HOPE``; our own code): the image is centred on the
centre of the ego footprint and rotated with the ego, so the ego faces +column (right) and its left is −row
(up): pixel (r, c) covers the ego-frame square around x = (c + ½ − W/2)/ppm forward, y = (H/2 − r − ½)/ppm
left. HOPE renders at 12 px/m on a 256 × 256 crop and resizes it to 64 × 64, i.e. 3 px/m over 21.3 m × 21.3 m;
here each pixel is the mean colour of ``supersample``² sample points (4 × 4: the 256-pixel render's pixels; HOPE's
linear resize weighs the central 2 × 2 of them). Layers, later ones covering earlier ones at each sample point:

1. background black (HOPE turns its white background black before the network);
2. the region outside the scene boundary and every obstacle (polygons exactly, circles as exact discs), grey
   (150, 150, 150);
3. the target footprint (the destination), green (69, 139, 0);
4. the ego footprint, dodger blue (30, 144, 255);
5. with a tail: the footprints of the last min(len(tail) + 1, ``tail_poses``) poses, the current one included,
   oldest first, coloured from (10, 10, 10) to (10, 10, 200) as HOPE's 20-step ramp (so the newest, the ego
   itself, is drawn in (10, 10, 200) over the dodger blue, as in HOPE).

A sample point is inside a polygon by the even–odd rule (scanline fill; a sample exactly on an edge counts on one
side only), inside a circle when strictly closer than its radius; the images depend only on the geometry relative
to the ego.
Rendering is compiled (numba) and runs over the images of a batch in parallel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from np_sim.errors import ConfigError
from np_sim.scene import Scene
from np_sim.scene_arrays import (G_BOUNDARY, G_CIRCLE, G_N_BOUNDARY, G_N_CIRCLE, G_N_POLY, G_POLY, G_POLY_NV,
                                 SceneArrays, packed_scene)
from np_sim.vehicle import VehicleSpec

_RGB = tuple[int, int, int]
BACKGROUND, OBSTACLE, TARGET, EGO, TAIL = 0, 1, 2, 3, 4
"""Layer labels of the sample grid; tail pose j of the colour ramp has label TAIL + j."""


@dataclass(frozen=True)
class BevConfig:
    """The BEV raster (paper App. B: ego-aligned 64 × 64 RGB; scale and colours are HOPE's, ``jiamiya/HOPE``)."""

    size_px: int = 64
    """Image width and height (pixels)."""
    pixels_per_m: float = 3.0
    """Raster scale (px/m): HOPE's 12 px/m render resized from 256 to 64 pixels."""
    supersample: int = 4
    """Sample points per pixel along each axis; a pixel is the mean colour of its supersample² points."""
    tail_poses: int = 20
    """Most poses of the trajectory tail drawn, the current pose included (HOPE's TRAJ_RENDER_LEN)."""
    background_rgb: _RGB = (0, 0, 0)
    """Free space."""
    obstacle_rgb: _RGB = (150, 150, 150)
    """Obstacles and everything outside the scene boundary."""
    target_rgb: _RGB = (69, 139, 0)
    """Target (destination) footprint."""
    ego_rgb: _RGB = (30, 144, 255)
    """Ego footprint."""
    tail_oldest_rgb: _RGB = (10, 10, 10)
    """Colour of the oldest of ``tail_poses`` tail footprints."""
    tail_newest_rgb: _RGB = (10, 10, 200)
    """Colour of the newest tail footprint (the current pose)."""

    def __post_init__(self) -> None:
        for name, most in (("size_px", 4096), ("supersample", 64), ("tail_poses", 255 - TAIL)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= most:
                raise ConfigError(f"BevConfig.{name}: expected an integer in [1, {most}], got {value!r}")
        if not (isinstance(self.pixels_per_m, (int, float)) and math.isfinite(self.pixels_per_m)
                and self.pixels_per_m > 0):
            raise ConfigError(f"BevConfig.pixels_per_m: expected a finite positive number, got {self.pixels_per_m!r}")
        for name in ("background_rgb", "obstacle_rgb", "target_rgb", "ego_rgb", "tail_oldest_rgb", "tail_newest_rgb"):
            value = getattr(self, name)
            if len(value) != 3 or not all(isinstance(v, int) and 0 <= v <= 255 for v in value):
                raise ConfigError(f"BevConfig.{name}: expected three integers in [0, 255], got {value!r}")

    @property
    def extent_m(self) -> float:
        """Side of the square the image covers (m)."""
        return self.size_px / self.pixels_per_m

    def palette(self) -> np.ndarray:
        """(TAIL + tail_poses, 3) float64 colour of each layer label; the tail ramp is HOPE's
        ``linspace(oldest, newest, tail_poses)`` truncated to integers."""
        ramp = np.linspace(self.tail_oldest_rgb, self.tail_newest_rgb, self.tail_poses).astype(np.uint8)
        fixed = np.array([self.background_rgb, self.obstacle_rgb, self.target_rgb, self.ego_rgb], float)
        return np.concatenate([fixed, ramp.astype(float)])


# ------------------------------------------------------------------------------------------------ kernels
@njit(cache=True, error_model="numpy")
def _fill_span(label: np.ndarray, j: int, i0: int, i1: int, value: int) -> None:
    """Set ``label[j, i0:i1] = value`` for the clipped span [i0, i1); nothing when i1 <= i0. A loop, not a slice: a
    span wholly left of the grid has i1 < 0, which a slice counts from the right (the band fixed on 2026-12-08)."""
    for i in range(i0, i1):
        label[j, i] = value


@njit(cache=True, error_model="numpy")
def fill_polygon(label: np.ndarray, u: np.ndarray, v: np.ndarray, n: int, value: int, xs: np.ndarray) -> None:
    """Set ``label[j, i] = value`` at every sample (u, v) = (i + ½, j + ½) inside the polygon (u[:n], v[:n]) by the
    even–odd rule (scanline fill); ``xs`` is scratch of length >= n."""
    rows, cols = label.shape
    j0 = max(0, int(math.ceil(v[:n].min() - 0.5)))
    j1 = min(rows - 1, int(math.floor(v[:n].max() - 0.5)))
    for j in range(j0, j1 + 1):
        vc = j + 0.5
        m = 0
        for a in range(n):
            b = a + 1 if a + 1 < n else 0
            if (v[a] <= vc) != (v[b] <= vc):
                crossing = u[a] + (vc - v[a]) * (u[b] - u[a]) / (v[b] - v[a])
                q = m  # insertion sort as the crossings come: a row has a handful (``xs[:m].sort()`` cost 4× more)
                while q > 0 and xs[q - 1] > crossing:
                    xs[q] = xs[q - 1]
                    q -= 1
                xs[q] = crossing
                m += 1
        for p in range(0, m - 1, 2):
            i0 = max(0, int(math.ceil(xs[p] - 0.5)))
            i1 = min(cols, int(math.ceil(xs[p + 1] - 0.5)))
            _fill_span(label, j, i0, i1, value)


@njit(cache=True, error_model="numpy")
def fill_disc(label: np.ndarray, cu: float, cv: float, r: float, value: int) -> None:
    """Set ``label[j, i] = value`` at every sample (i + ½, j + ½) strictly inside the disc of centre (cu, cv) and
    radius r (sample units)."""
    rows, cols = label.shape
    j0 = max(0, int(math.ceil(cv - r - 0.5)))
    j1 = min(rows - 1, int(math.floor(cv + r - 0.5)))
    for j in range(j0, j1 + 1):
        dv = j + 0.5 - cv
        if dv * dv >= r * r:
            continue
        half = math.sqrt(r * r - dv * dv)
        i0 = max(0, int(math.floor(cu - half - 0.5)) + 1)
        i1 = min(cols, int(math.ceil(cu + half - 0.5)))
        _fill_span(label, j, i0, i1, value)


@njit(cache=True, error_model="numpy")
def _to_samples(x: np.ndarray, y: np.ndarray, frame: np.ndarray, u: np.ndarray, v: np.ndarray) -> None:
    """World points (x, y) to sample coordinates: frame = (cx, cy, cos θ, sin θ, samples per m, half size)."""
    cx, cy, c, s, k, h = frame[0], frame[1], frame[2], frame[3], frame[4], frame[5]
    for a in range(x.shape[0]):
        dx = x[a] - cx
        dy = y[a] - cy
        u[a] = h + k * (c * dx + s * dy)
        v[a] = h - k * (-s * dx + c * dy)


@njit(cache=True, error_model="numpy")
def _fill_body(label, pose, local, frame, value, x, y, u, v, xs) -> None:
    """Fill the footprint ``local`` (4, 2) placed at the reference-point ``pose``."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    for a in range(4):
        x[a] = pose[0] + c * local[a, 0] - s * local[a, 1]
        y[a] = pose[1] + s * local[a, 0] + c * local[a, 1]
    _to_samples(x[:4], y[:4], frame, u, v)
    fill_polygon(label, u, v, 4, value, xs)


@njit(cache=True, error_model="numpy")
def _fill_scene(label, geo, k, frame, x, y, u, v, xs) -> None:
    """Layers 1–2: outside the boundary and the obstacles of scene ``k`` over a background label grid."""
    label[:, :] = OBSTACLE
    nb = geo[G_N_BOUNDARY][k]
    boundary = geo[G_BOUNDARY][k]
    _to_samples(boundary[:nb, 0], boundary[:nb, 1], frame, u, v)
    fill_polygon(label, u, v, nb, BACKGROUND, xs)
    for j in range(geo[G_N_POLY][k]):
        nv = geo[G_POLY_NV][k, j]
        poly = geo[G_POLY][k, j]
        _to_samples(poly[:nv, 0], poly[:nv, 1], frame, u, v)
        fill_polygon(label, u, v, nv, OBSTACLE, xs)
    for j in range(geo[G_N_CIRCLE][k]):
        circle = geo[G_CIRCLE][k, j]
        x[0], y[0] = circle[0], circle[1]
        _to_samples(x[:1], y[:1], frame, u, v)
        fill_disc(label, u[0], v[0], circle[2] * frame[4], OBSTACLE)


@njit(cache=True, error_model="numpy")
def _average(label: np.ndarray, palette: np.ndarray, ss: int, out: np.ndarray) -> None:
    """out[ch, r, c] = round(mean palette colour over the ss × ss samples of pixel (r, c))."""
    size = out.shape[1]
    inv = 1.0 / (ss * ss)
    for r in range(size):
        for c in range(size):
            acc0 = acc1 = acc2 = 0.0
            for j in range(r * ss, r * ss + ss):
                for i in range(c * ss, c * ss + ss):
                    q = label[j, i]
                    acc0 += palette[q, 0]
                    acc1 += palette[q, 1]
                    acc2 += palette[q, 2]
            out[0, r, c] = np.uint8(math.floor(acc0 * inv + 0.5))
            out[1, r, c] = np.uint8(math.floor(acc1 * inv + 0.5))
            out[2, r, c] = np.uint8(math.floor(acc2 * inv + 0.5))


@njit(parallel=True, cache=True, error_model="numpy")
def render_kernel(geo, targets, scene_index, poses, tails, n_tail, local, centre, ppm, ss, tail_poses, palette,
                  out) -> None:
    """Every image of the batch (see the module docstring); ``centre`` = footprint centre in the body frame."""
    n_img, size = out.shape[0], out.shape[2]
    n_scratch = max(geo[G_BOUNDARY].shape[1], geo[G_POLY].shape[2], 4)
    for b in prange(n_img):
        k = scene_index[b]
        pose = poses[b]
        c, s = math.cos(pose[2]), math.sin(pose[2])
        frame = np.array([pose[0] + c * centre[0] - s * centre[1], pose[1] + s * centre[0] + c * centre[1],
                          c, s, ppm * ss, 0.5 * size * ss])
        label = np.empty((size * ss, size * ss), np.uint8)
        x, y = np.empty(n_scratch), np.empty(n_scratch)
        u, v, xs = np.empty(n_scratch), np.empty(n_scratch), np.empty(n_scratch)
        _fill_scene(label, geo, k, frame, x, y, u, v, xs)
        _fill_body(label, targets[k], local, frame, TARGET, x, y, u, v, xs)
        _fill_body(label, pose, local, frame, EGO, x, y, u, v, xs)
        if n_tail[b] > 0:
            drawn = min(n_tail[b] + 1, tail_poses)
            for j in range(drawn):
                back = drawn - 1 - j  # 0 = the current pose
                p = pose if back == 0 else tails[b, n_tail[b] - back]
                _fill_body(label, p, local, frame, TAIL + tail_poses - drawn + j, x, y, u, v, xs)
        _average(label, palette, ss, out[b])


# ------------------------------------------------------------------------------------------------ Python API
def _footprint_centre(vehicle: VehicleSpec) -> np.ndarray:
    """Centre of the footprint rectangle in the body frame (the point HOPE centres its crop on)."""
    return np.array([0.5 * (vehicle.front_m - vehicle.rear_overhang_m), 0.0])


def render_bev_batch(arrays: SceneArrays, scene_index, poses, tails=None, n_tail=None,
                     config: BevConfig | None = None, vehicle: VehicleSpec | None = None) -> np.ndarray:
    """(N, 3, size, size) uint8 ego-aligned BEV images of N (scene, pose, tail) triples (module docstring)."""
    config = BevConfig() if config is None else config
    vehicle = VehicleSpec() if vehicle is None else vehicle
    poses = np.ascontiguousarray(np.asarray(poses, np.float64).reshape(-1, 3))
    n = len(poses)
    index = np.broadcast_to(np.asarray(scene_index, np.int64), (n,)).copy()
    if np.any((index < 0) | (index >= arrays.n_scenes)):
        raise ValueError(f"render_bev_batch: scene_index must lie in [0, {arrays.n_scenes}), got {index.tolist()}")
    if not np.all(np.isfinite(poses)):
        raise ValueError("render_bev_batch: poses must be finite")
    if tails is None:
        tails, n_tail = np.zeros((n, 1, 3)), np.zeros(n, np.int64)
    tails = np.ascontiguousarray(np.asarray(tails, np.float64))
    n_tail = np.asarray(n_tail, np.int64)
    if tails.ndim != 3 or tails.shape[0] != n or tails.shape[2] != 3 or n_tail.shape != (n,):
        raise ValueError(f"render_bev_batch: expected tails (N={n}, T, 3) and n_tail (N,), got {tails.shape} and "
                         f"{n_tail.shape}")
    if np.any((n_tail < 0) | (n_tail > tails.shape[1])):
        raise ValueError(f"render_bev_batch: n_tail must lie in [0, {tails.shape[1]}], got {n_tail.tolist()}")
    out = np.empty((n, 3, config.size_px, config.size_px), np.uint8)
    render_kernel(arrays.geometry, arrays.targets, index, poses, tails, n_tail, vehicle.footprint_local(),
                  _footprint_centre(vehicle), float(config.pixels_per_m), config.supersample, config.tail_poses,
                  config.palette(), out)
    return out


def render_bev(scene: Scene, pose, tail=None, config: BevConfig | None = None,
               vehicle: VehicleSpec | None = None) -> np.ndarray:
    """(3, size, size) uint8 ego-aligned BEV image of ``scene`` with the ego at ``pose`` and an optional
    trajectory ``tail`` ((k, 3) earlier poses, oldest first; module docstring)."""
    tail = np.zeros((0, 3)) if tail is None else np.asarray(tail, np.float64).reshape(-1, 3)
    tails = np.zeros((1, max(len(tail), 1), 3))
    tails[0, : len(tail)] = tail
    return render_bev_batch(packed_scene(scene), 0, pose, tails, [len(tail)], config, vehicle)[0]
