"""Four hand-made example scenes shipped as JSON beside this module (spec §4 format).

- ``reverse_bay``: a row of parked cars with one empty perpendicular bay; the car reverses in.
- ``parallel_slot``: a kerb-side parallel slot (about 7 m) between two parked cars.
- ``clutter_random``: irregular clutter (non-convex polygons, bins) and an arbitrary target heading.
- ``enclosed_target``: the target sealed inside a pocket of walls: footprint free but unreachable ("no path").
"""

from __future__ import annotations

from pathlib import Path

from np_sim.errors import ConfigError
from np_sim.scene import Scene


def example_names() -> list[str]:
    """Names (file stems) of the shipped example scenes, sorted."""
    return sorted(path.stem for path in Path(__file__).parent.glob("*.json"))


def example_path(name: str) -> Path:
    """Path of the example scene ``name`` (with or without the ``.json`` suffix); ConfigError if unknown."""
    stem = name[: -len(".json")] if name.endswith(".json") else name
    names = example_names()
    if stem not in names:
        raise ConfigError(f"example_path: unknown example scene {name!r}; expected one of {', '.join(names)}")
    return Path(__file__).parent / f"{stem}.json"


def example_scenes() -> list[Scene]:
    """All example scenes, loaded and validated with the default vehicle, in `example_names` order."""
    return [Scene.load(example_path(name)) for name in example_names()]
