"""Matplotlib drawing of scenes and paths (kept apart from every algorithm; STYLE §1)."""

from __future__ import annotations

import math

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.patches import Circle
from matplotlib.patches import Polygon as PolygonPatch

from np_sim.scene import CircleObstacle, Scene
from np_sim.vehicle import VehicleSpec


def target_marker(pose, vehicle: VehicleSpec) -> tuple[np.ndarray, np.ndarray]:
    """The T-marker of a pose: a bar across it (vehicle width) and a stem along its heading (wheelbase).

    Returns ``(bar, stem)``, each a (2, 2) array of world-frame end points (m).
    """
    x, y, th = float(pose[0]), float(pose[1]), float(pose[2])
    heading = np.array([math.cos(th), math.sin(th)])
    left = np.array([-heading[1], heading[0]])
    centre = np.array([x, y])
    half_bar = 0.5 * vehicle.width_m
    bar = np.stack([centre - half_bar * left, centre + half_bar * left])
    stem = np.stack([centre, centre + vehicle.wheelbase_m * heading])
    return bar, stem


def plot_scene(ax: Axes, scene: Scene, path=None, vehicle: VehicleSpec | None = None) -> Axes:
    """Draw ``scene`` on ``ax``: boundary, obstacles, start region, target T-marker and footprint, optional path.

    Parameters
    ----------
    ax
        Matplotlib axes to draw on (left with equal aspect, metres on both axes, the scene name as title).
    scene
        The scene, world frame.
    path
        Optional (N, 2) or (N, 3) array of reference-point positions (θ column ignored) drawn as a line.
    vehicle
        Vehicle whose footprint is outlined at the target; default `VehicleSpec()`.

    Returns
    -------
    The same ``ax``.
    """
    vehicle = vehicle if vehicle is not None else VehicleSpec()
    ax.add_patch(
        PolygonPatch(scene.boundary, closed=True, fill=False, edgecolor="black", linewidth=1.5, label="boundary")
    )
    if scene.start_region is not None:
        ax.add_patch(
            PolygonPatch(
                scene.start_region,
                closed=True,
                facecolor="tab:green",
                alpha=0.15,
                hatch="//",
                edgecolor="tab:green",
                linewidth=0.8,
                label="start region",
            )
        )
    for index, obstacle in enumerate(scene.obstacles):
        style = dict(facecolor="0.55", edgecolor="0.25", linewidth=0.8, label="obstacles" if index == 0 else None)
        if isinstance(obstacle, CircleObstacle):
            ax.add_patch(Circle(tuple(obstacle.center), obstacle.radius, **style))
        else:
            ax.add_patch(PolygonPatch(obstacle.vertices, closed=True, **style))
    ax.add_patch(
        PolygonPatch(
            vehicle.footprint(scene.target),
            closed=True,
            fill=False,
            edgecolor="tab:red",
            linestyle="--",
            linewidth=1.0,
            label="target footprint",
        )
    )
    bar, stem = target_marker(scene.target, vehicle)
    ax.plot(bar[:, 0], bar[:, 1], color="tab:red", linewidth=2.0, label="target")
    ax.plot(stem[:, 0], stem[:, 1], color="tab:red", linewidth=2.0)
    extent = scene.boundary
    if path is not None:
        points = np.asarray(path, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] not in (2, 3):
            raise ValueError(f"plot_scene: path must have shape (N, 2) or (N, 3), got {points.shape}")
        ax.plot(points[:, 0], points[:, 1], color="tab:blue", linewidth=1.5, label="path")
        ax.plot(points[:1, 0], points[:1, 1], "o", color="tab:blue", markersize=4)
        extent = np.concatenate([extent, points[:, :2]])
    ax.set_aspect("equal")
    xmin, ymin = extent.min(axis=0)
    xmax, ymax = extent.max(axis=0)
    margin = 0.03 * max(xmax - xmin, ymax - ymin)
    ax.set_xlim(xmin - margin, xmax + margin)
    ax.set_ylim(ymin - margin, ymax + margin)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(scene.name or "(unnamed scene)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small", frameon=False)
    return ax


def plot_clip(ax: Axes, clip, frames=None, vehicle: VehicleSpec | None = None) -> Axes:
    """Draw a delivery-site clip: `plot_scene` of frame 0's detection scene (boundary, nearest ten detections,
    target), plus spot outlines, the ground truth of frame 0, the detections of several frames with fading colour
    (older = paler), mover tracks and the start T-marker. Returns ``ax``."""
    vehicle = VehicleSpec() if vehicle is None else vehicle
    frames = list(np.linspace(0, clip.n_frames - 1, 6).astype(int)) if frames is None else list(frames)
    plot_scene(ax, clip.frame_scene(0), vehicle=vehicle)
    for spot in clip.site.spots:
        ax.add_patch(PolygonPatch(vehicle.footprint(spot.pose), closed=True, fill=False, edgecolor="0.8",
                                  linewidth=0.5, linestyle=":"))
    for k, obj in enumerate(clip.objects):
        ax.add_patch(PolygonPatch(obj.polygon(0), closed=True, facecolor="none", edgecolor="black", linewidth=0.7,
                                  label="ground truth (frame 0)" if k == 0 else None))
        if obj.moving:
            ax.plot(obj.poses[:, 0], obj.poses[:, 1], color="tab:purple", linewidth=0.8, alpha=0.7,
                    label="mover track" if not any(o.moving for o in clip.objects[:k]) else None)
    cmap = colormaps["Oranges"]
    for n, frame in enumerate(frames):
        shade = cmap(0.35 + 0.6 * (n + 1) / len(frames))
        _, polygons = clip.detections(clip.detection_frame(frame))
        for j, poly in enumerate(polygons):
            ax.add_patch(PolygonPatch(poly, closed=True, facecolor="none", edgecolor=shade, linewidth=0.6,
                                      label=f"detections t = {frame * clip.frame_dt_s:.1f} s" if j == 0 else None))
    bar, stem = target_marker(clip.start, vehicle)
    ax.plot(bar[:, 0], bar[:, 1], color="tab:green", linewidth=2.0, label="start")
    ax.plot(stem[:, 0], stem[:, 1], color="tab:green", linewidth=2.0)
    ax.add_patch(PolygonPatch(vehicle.footprint(clip.start), closed=True, fill=False, edgecolor="tab:green",
                              linestyle="--", linewidth=1.0))
    reasons = ", ".join(clip.difficulty.reasons) or "not difficult"
    ax.set_title(f"{clip.name}: target {clip.site.spots[clip.target_spot].name}, difficulty: {reasons}\n"
                 "grey: the ten detections nearest the start at t = 0 s (the planner's input)", fontsize="medium")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small", frameon=False)
    return ax
