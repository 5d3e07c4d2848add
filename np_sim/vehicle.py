"""The vehicle: the single source of footprint and steering geometry for every module (spec §3).

A vehicle is also a JSON file (``VehicleSpec.from_json``, ``load_vehicle``), one object of the dataclass's fields::

    {
      "wheelbase_m": 2.975,        # rear axle to front axle (m)
      "front_overhang_m": 0.9,     # front axle to front bumper (m)
      "rear_overhang_m": 0.875,    # rear axle to rear bumper (m)
      "width_m": 1.85,             # body width, mirrors excluded (m)
      "kappa_max": 0.24,           # largest path curvature of the rear-axle centre (1/m)
      "length_m": 4.75,            # optional: bumper to bumper (m), checked against the sum ...
      "description": "..."         # optional: free text (where the numbers come from)
    }

``length_m`` may also stand in for one of the overhangs (that one is then length − wheelbase − the other); given
with both, it must equal their sum with the wheelbase within 1 mm. Every other key, a missing field, a value that is
not a finite positive number (booleans and strings included), and a wheelbase that leaves no positive overhang in
the given length (a wheelbase longer than the body) are each a ConfigError naming the file and the field. Nothing is
rounded or fixed. Presets ship in ``np_sim/data/vehicles/`` (``PRESETS``): 'sedan' (the default, HOPE's
rectangle) and 'van' (a compact delivery van); ``load_vehicle`` takes a preset name or a file path.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from np_sim.errors import ConfigError

PRESET_DIR = Path(__file__).resolve().parent / "data" / "vehicles"
"""The shipped vehicle files, ``<name>.json``."""
FIELDS = ("wheelbase_m", "front_overhang_m", "rear_overhang_m", "width_m", "kappa_max")
"""The dataclass fields, in the order a description names them."""
OPTIONAL_KEYS = ("length_m", "description")
"""Keys a vehicle file may hold beyond ``FIELDS``."""
LENGTH_TOLERANCE_M = 1e-3
"""How far a given ``length_m`` may lie from overhangs + wheelbase (m)."""


@dataclass(frozen=True)
class VehicleSpec:
    """Rectangular footprint adopted from HOPE, reference point at the rear-axle centre.

    Vehicle frame: x forward along the heading, y to the left, origin at the reference point.
    """

    wheelbase_m: float = 2.8
    """Distance between rear and front axle (m)."""
    front_overhang_m: float = 0.96
    """Front axle to front bumper (m)."""
    rear_overhang_m: float = 0.929
    """Rear axle to rear bumper (m)."""
    width_m: float = 1.942
    """Body width (m)."""
    kappa_max: float = 0.68
    """Largest path curvature the vehicle may drive (1/m); also the action bound |κ|."""

    def __post_init__(self) -> None:
        for name in FIELDS:
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigError(f"VehicleSpec.{name}: expected a finite positive number, got {value!r}")

    @property
    def length_m(self) -> float:
        """Bumper-to-bumper length (m)."""
        return self.rear_overhang_m + self.wheelbase_m + self.front_overhang_m

    @property
    def front_m(self) -> float:
        """Reference point to front bumper (m), the rectangle's +x extent."""
        return self.wheelbase_m + self.front_overhang_m

    @property
    def max_steer_rad(self) -> float:
        """Front-wheel steering angle needed for κ_max on the kinematic bicycle: atan(κ_max · wheelbase)."""
        return math.atan(self.kappa_max * self.wheelbase_m)

    def inflated(self, margin_m: float) -> "VehicleSpec":
        """The same vehicle with ``margin_m`` of clearance added on every side of the footprint (a planner's safety
        margin); kinematics (wheelbase, κ_max) unchanged."""
        if not (math.isfinite(margin_m) and margin_m >= 0):
            raise ConfigError(f"VehicleSpec.inflated: margin must be a finite number >= 0 m, got {margin_m!r}")
        return dataclasses.replace(self, front_overhang_m=self.front_overhang_m + margin_m,
                                   rear_overhang_m=self.rear_overhang_m + margin_m,
                                   width_m=self.width_m + 2.0 * margin_m)

    def footprint_local(self) -> np.ndarray:
        """(4, 2) rectangle corners in the vehicle frame, counter-clockwise from rear-right."""
        half_w = 0.5 * self.width_m
        return np.array(
            [
                [-self.rear_overhang_m, -half_w],
                [self.front_m, -half_w],
                [self.front_m, half_w],
                [-self.rear_overhang_m, half_w],
            ]
        )

    def footprint(self, pose) -> np.ndarray:
        """(4, 2) rectangle corners in the world frame for a reference-point pose (x, y, θ)."""
        from np_sim.frames import place

        return place(self.footprint_local(), np.asarray(pose, float)[:3])

    def describe(self) -> str:
        """One line naming the vehicle: its preset name when it is one, and every dimension."""
        name = preset_name(self)
        return ((f"'{name}' " if name else "") + f"(length {self.length_m:g} m, width {self.width_m:g} m, wheelbase "
                f"{self.wheelbase_m:g} m, overhangs front {self.front_overhang_m:g} / rear {self.rear_overhang_m:g} m, "
                f"kappa_max {self.kappa_max:g} 1/m)")

    def to_dict(self) -> dict[str, float]:
        """The file form of the spec (``FIELDS`` and the derived ``length_m``); ``from_dict`` reads it back."""
        return {**dataclasses.asdict(self), "length_m": self.length_m}

    @classmethod
    def from_dict(cls, data: Any, source: str = "<dict>") -> "VehicleSpec":
        """A spec from the JSON object ``data`` (module docstring); ConfigError naming ``source`` and the field."""
        if not isinstance(data, dict):
            raise ConfigError(f"{source}: expected a JSON object of vehicle fields, got {type(data).__name__}")
        unknown = sorted(set(data) - set(FIELDS) - set(OPTIONAL_KEYS))
        if unknown:
            raise ConfigError(f"{source}: unknown key(s) {unknown}; expected {list(FIELDS)} and optionally "
                              f"{list(OPTIONAL_KEYS)}")
        if not isinstance(data.get("description", ""), str):
            raise ConfigError(f"{source}: description: expected a string, got {data['description']!r}")
        values = {key: _positive(data[key], source, key) for key in (*FIELDS, "length_m") if key in data}
        values = _overhangs(values, source)
        return cls(**{key: values[key] for key in FIELDS})

    @classmethod
    def from_json(cls, path: str | Path) -> "VehicleSpec":
        """The spec in the JSON file ``path`` (module docstring); ConfigError naming the file and the field."""
        path = Path(path)
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError) as error:
            raise ConfigError(f"{path}: cannot read the vehicle file: {error}") from None
        except (ValueError, RecursionError) as error:
            raise ConfigError(f"{path}: not a JSON vehicle file: {error}") from None
        return cls.from_dict(data, str(path))

    @classmethod
    def preset(cls, name: str) -> "VehicleSpec":
        """The vehicle named ``name``: a preset (``PRESETS``) or a vehicle JSON file (`load_vehicle`); lets a
        ``--set ...vehicle=van`` override name one."""
        return load_vehicle(name)


def _positive(value: Any, source: str, key: str) -> float:
    """``value`` as a float when it is a finite number > 0 (not a boolean); ConfigError naming the field."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value) and value > 0):
        raise ConfigError(f"{source}: {key}: expected a finite positive number (m, or 1/m for kappa_max), "
                          f"got {value!r}")
    return float(value)


def _overhangs(values: dict[str, float], source: str) -> dict[str, float]:
    """``values`` with both overhangs: one may come from ``length_m``; ConfigError on a missing field, a length
    that disagrees with the sum, or a wheelbase that leaves no positive overhang."""
    length = values.get("length_m")
    missing = [key for key in FIELDS if key not in values]
    if length is not None and missing in (["front_overhang_m"], ["rear_overhang_m"]) and "wheelbase_m" in values:
        other = "rear_overhang_m" if missing == ["front_overhang_m"] else "front_overhang_m"
        rest = length - values["wheelbase_m"] - values[other]
        if not rest > 0:
            raise ConfigError(f"{source}: wheelbase_m: the wheelbase {values['wheelbase_m']:g} m and {other} "
                              f"{values[other]:g} m leave no {missing[0]} in length_m {length:g} m; expected a "
                              "wheelbase shorter than the body")
        return {**values, missing[0]: rest}
    if missing:
        raise ConfigError(f"{source}: missing field(s) {missing}; expected all of {list(FIELDS)} (length_m may "
                          "stand in for one overhang)")
    if length is not None:
        total = values["wheelbase_m"] + values["front_overhang_m"] + values["rear_overhang_m"]
        if values["wheelbase_m"] >= length:
            raise ConfigError(f"{source}: wheelbase_m: {values['wheelbase_m']:g} m is not shorter than the body "
                              f"(length_m {length:g} m); expected a wheelbase shorter than the body")
        if abs(total - length) > LENGTH_TOLERANCE_M:
            raise ConfigError(f"{source}: length_m: {length:g} m, but rear overhang + wheelbase + front overhang = "
                              f"{total:g} m; expected them to agree within {LENGTH_TOLERANCE_M * 1e3:g} mm")
    return values


PRESETS = tuple(sorted(p.stem for p in PRESET_DIR.glob("*.json")))
"""Names of the shipped vehicles (files ``PRESET_DIR/<name>.json``)."""


def load_vehicle(name_or_path: str | Path) -> VehicleSpec:
    """A preset by name ('sedan', 'van': ``PRESETS``) or the vehicle JSON file at a path; ConfigError naming what
    was given and the presets when it is neither."""
    text = str(name_or_path)
    if text in PRESETS:
        return _preset(text)
    path = Path(text)
    if not path.is_file():
        raise ConfigError(f"vehicle {text!r}: neither a preset ({', '.join(PRESETS)}) nor a vehicle JSON file")
    return VehicleSpec.from_json(path)


def preset_name(spec: VehicleSpec) -> str | None:
    """The name of the preset equal to ``spec``, or None."""
    return next((name for name in PRESETS if _preset(name) == spec), None)


@functools.cache
def _preset(name: str) -> VehicleSpec:
    return VehicleSpec.from_json(PRESET_DIR / f"{name}.json")
