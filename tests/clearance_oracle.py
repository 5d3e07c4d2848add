"""Shapely's least distance from a vehicle body along a path to a scene's obstacles and boundary: the independent
measure the footprint planners' clearance claims are tested against."""

from shapely.geometry import LinearRing, Point
from shapely.geometry import Polygon as ShapelyPolygon
from shapely.ops import unary_union

from np_sim.scene import CircleObstacle


def shapely_clearance(scene, rows, body) -> float:
    """Least distance (m) from the body's rectangle at any pose row (x, y, θ, ...) to an obstacle or the boundary
    ring."""
    shapes = [Point(*o.center).buffer(o.radius, 64) if isinstance(o, CircleObstacle) else ShapelyPolygon(o.vertices)
              for o in scene.obstacles]
    obstacles, ring = unary_union(shapes), LinearRing(scene.boundary)
    return min(min(obstacles.distance(fp), ring.distance(fp))
               for fp in (ShapelyPolygon(body.footprint(pose)) for pose in rows[:, :3]))
