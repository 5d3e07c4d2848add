"""The vehicle MJCF, filled from `VehicleSpec` and `VehicleModelConfig` (spec §3, §8), and its Ackermann geometry.

``python -m tracking.mjcf [--vehicle sedan|van|FILE] [-o FILE]`` writes a vehicle (default the sedan,
`np_sim.vehicle`) as a loadable MJCF (for the MuJoCo viewer).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from string import Template

import numpy as np

from np_sim.cli import cli_boundary, vehicle_spec
from np_sim.vehicle import VehicleSpec
from tracking.config import PlantConfig, VehicleModelConfig
from tracking.errors import TrackingError

TEMPLATE_PATH = Path(__file__).resolve().parents[1] / "models" / "mjcf" / "vehicle_template.xml"
"""The vehicle MJCF template (placeholders ``${name}``)."""


def half_track_m(spec: VehicleSpec, model: VehicleModelConfig) -> float:
    """Lateral offset of each wheel centre from the vehicle axis: width/2 − wheel inset (m)."""
    half = 0.5 * spec.width_m - model.wheel_inset_m
    if not half > 0:
        raise TrackingError(f"VehicleModelConfig.wheel_inset_m = {model.wheel_inset_m} leaves no track on a "
                            f"{spec.width_m} m wide vehicle; expected an inset below half the width")
    return half


def ackermann_angles(steer_curvature, wheelbase_m: float, half_track: float):
    """(left, right) front-wheel angles of exact Ackermann steering for the rear-axle path curvature c.

    The turn centre lies on the rear axle line at lateral offset 1/c; a front wheel at lateral offset y sits at
    wheelbase L ahead, so its angle is atan2(L·c, 1 − c·y) (y = +half_track left, −half_track right). For c = 0
    both are 0; the bicycle angle atan(L·c) lies between them.
    """
    c = np.asarray(steer_curvature, dtype=float)
    return (np.arctan2(wheelbase_m * c, 1.0 - c * half_track), np.arctan2(wheelbase_m * c, 1.0 + c * half_track))


def steer_curvature_max(spec: VehicleSpec, model: VehicleModelConfig) -> float:
    """Largest steering curvature of the mechanism: (1 + steer_margin)·κ_max (1/m)."""
    if not model.steer_margin >= 0:
        raise TrackingError(f"VehicleModelConfig.steer_margin: expected >= 0, got {model.steer_margin}")
    return (1.0 + model.steer_margin) * spec.kappa_max


def max_steer_rad(spec: VehicleSpec, model: VehicleModelConfig) -> float:
    """Largest bicycle steering angle atan(c_max·L) (`VehicleSpec.max_steer_rad` when the margin is 0)."""
    return math.atan(steer_curvature_max(spec, model) * spec.wheelbase_m)


def steer_joint_max_rad(spec: VehicleSpec, model: VehicleModelConfig) -> float:
    """Steering hinge range: the inner wheel's Ackermann angle at the largest steering curvature."""
    left, _ = ackermann_angles(steer_curvature_max(spec, model), spec.wheelbase_m, half_track_m(spec, model))
    return float(left)


def _box_inertia(mass: float, length: float, width: float, height: float) -> dict[str, float]:
    """Principal inertia of a uniform solid box: I_xx = m(w² + h²)/12, I_yy = m(l² + h²)/12, I_zz = m(l² + w²)/12."""
    return {"chassis_ixx": mass * (width**2 + height**2) / 12, "chassis_iyy": mass * (length**2 + height**2) / 12,
            "chassis_izz": mass * (length**2 + width**2) / 12}


def _payload_values(spec: VehicleSpec, model: VehicleModelConfig, plant: PlantConfig) -> dict[str, float]:
    """Chassis mass, centre-of-mass x and inertia with ``plant``'s payload: the uniform box of the nominal
    footprint plus a point mass m_p at x_p on the centre line at the centre-of-mass height, so that
    M = m_c + m_p, x_c = (m_c·x_b + m_p·x_p)/M and, by the parallel-axis theorem, I_yy and I_zz gain
    m_c·(x_b − x_c)² + m_p·(x_p − x_c)² (I_xx is unchanged)."""
    box_x = 0.5 * (spec.front_m - spec.rear_overhang_m)
    values = {"chassis_mass_kg": model.chassis_mass_kg, "com_x_m": box_x,
              **_box_inertia(model.chassis_mass_kg, spec.length_m, spec.width_m,
                             model.body_height_m - model.ground_clearance_m)}
    if plant.payload_kg:
        mass = model.chassis_mass_kg + plant.payload_kg
        com = (model.chassis_mass_kg * box_x + plant.payload_kg * plant.payload_x_m) / mass
        shift = model.chassis_mass_kg * (box_x - com) ** 2 + plant.payload_kg * (plant.payload_x_m - com) ** 2
        values.update(chassis_mass_kg=mass, com_x_m=com, chassis_iyy=values["chassis_iyy"] + shift,
                      chassis_izz=values["chassis_izz"] + shift)
    return values


def template_values(spec: VehicleSpec, model: VehicleModelConfig,
                    plant: PlantConfig | None = None) -> dict[str, float]:
    """Every placeholder of the template, derived from the spec (geometry), the model config (physics) and the
    plant's differences (``plant``, default none: a payload, a longer chassis box)."""
    plant = PlantConfig() if plant is None else plant
    body = plant.body(spec)
    if not model.body_height_m > model.ground_clearance_m >= 0:
        raise TrackingError(f"VehicleModelConfig: expected body_height_m > ground_clearance_m >= 0, got "
                            f"{model.body_height_m} and {model.ground_clearance_m}")
    if not 0 < model.ground_clearance_m < 2 * model.wheel_radius_m:
        raise TrackingError(f"VehicleModelConfig.ground_clearance_m = {model.ground_clearance_m}: expected a value in "
                            f"(0, wheel diameter {2 * model.wheel_radius_m}) so the chassis clears the ground")
    pitch = math.radians(model.chase_pitch_deg)
    r = model.wheel_radius_m
    return {
        "timestep_s": model.timestep_s,
        "wheel_radius_m": r,
        "wheel_mass_kg": model.wheel_mass_kg,
        "knuckle_mass_kg": model.knuckle_mass_kg,
        "knuckle_inertia": 0.4 * model.knuckle_mass_kg * 0.2**2,
        "half_tyre_width_m": 0.5 * model.tyre_width_m,
        "tyre_friction": model.tyre_friction,
        "wheel_damping": model.wheel_damping,
        "wheel_armature": model.wheel_armature,
        "steer_joint_max_rad": steer_joint_max_rad(spec, model),
        "steer_damping": model.steer_damping,
        "steer_armature": model.steer_armature,
        "steer_kp": model.steer_kp,
        "steer_kv": model.steer_kv,
        "drive_torque_max_nm": model.drive_torque_max_nm,
        "chassis_cx_m": 0.5 * (body.front_m - body.rear_overhang_m),
        "chassis_cz_m": 0.5 * (model.ground_clearance_m + model.body_height_m) - r,
        "chassis_half_length_m": 0.5 * body.length_m,
        "chassis_half_width_m": 0.5 * spec.width_m,
        "chassis_half_height_m": 0.5 * (model.body_height_m - model.ground_clearance_m),
        "com_z_m": model.com_height_m - r,
        **_payload_values(spec, model, plant),
        "wheelbase_m": spec.wheelbase_m,
        "half_track_m": half_track_m(spec, model),
        "chase_back_m": -model.chase_back_m,
        "chase_up_m": model.chase_up_m,
        "chase_look_x": math.sin(pitch),
        "chase_look_z": math.cos(pitch),
    }


def vehicle_xml(spec: VehicleSpec | None = None, model: VehicleModelConfig | None = None,
                plant: PlantConfig | None = None) -> str:
    """The vehicle MJCF text for ``spec``, ``model`` and ``plant`` (defaults: the HOPE rectangle, default
    physics, no plant difference)."""
    spec = VehicleSpec() if spec is None else spec
    model = VehicleModelConfig() if model is None else model
    if not TEMPLATE_PATH.is_file():
        raise TrackingError(f"vehicle MJCF template not found at {TEMPLATE_PATH}; run from a checkout of the repo")
    values = {key: repr(float(value)) for key, value in template_values(spec, model, plant).items()}
    return Template(TEMPLATE_PATH.read_text()).substitute(values)


@cli_boundary
def main(argv=None) -> Path:
    """Write a vehicle's MJCF to a file (an unwritable path or a bad vehicle prints one ``error:`` line, exit
    status 2)."""
    parser = argparse.ArgumentParser(prog="python -m tracking.mjcf", description=__doc__)
    parser.add_argument("--vehicle", type=vehicle_spec, default=VehicleSpec(),
                        help="a preset (sedan, the default; van) or a vehicle JSON file (docs/vehicles.md)")
    parser.add_argument("-o", "--out", type=Path, default=Path("vehicle.xml"), help="output MJCF file")
    args = parser.parse_args(argv)
    args.out.write_text(vehicle_xml(args.vehicle))
    print(f"wrote {args.out}")
    return args.out


if __name__ == "__main__":
    main()
