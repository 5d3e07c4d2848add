"""The compiled ``ParkingVectorEnv`` against the plain per-step oracle ``tests/reference_step.py``.

The oracle is written from the paper (Algorithm 1, eq:arc … eq:terminal-reward, App. A) with Python loops and
shapely predicates, sharing no code with ``np_sim.kernels``. On seeded random multi-step episodes in the example
scenes — both connector modes (81-candidate ensemble, fixed nine) × both collision conventions (reference point,
footprint) — every step is compared: reached pose (1e-9), collision, success, termination/truncation, reward
(1e-6 relative), the LiDAR clearances (1e-6 m), the rest of the observation, and the selected Hermite candidate.
Actions are partly uniform (collisions), partly aimed at the target so that Hermite connections happen, partly
"wandering" away from the heading gate so that episodes last and the history terms (κ change, reversals,
Δκ_eff) are exercised. Every test also asserts that its sample really exercised those branches.

Mismatches are collected and reported together, each with a reproducing case (scene, start pose, the episode's
history, action) and both sides' values.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from np_sim.config import ConnectorConfig, EnvConfig, EpisodeConfig
from np_sim.env import ParkingVectorEnv
from np_sim.examples import example_scenes
from np_sim.kernels import step as K
from np_sim.scene import Scene

_spec = importlib.util.spec_from_file_location("reference_step",
                                               Path(__file__).resolve().parents[1] / "reference_step.py")
ref = importlib.util.module_from_spec(_spec)
sys.modules.setdefault("reference_step", ref)
_spec.loader.exec_module(ref)

POSE_TOL = 1e-9
REWARD_RTOL = 1e-6
LIDAR_TOL = 1e-6
HERMITE_RTOL = 1e-9

CONFIGS = {
    "ensemble/reference_point": EnvConfig(),
    "fixed/reference_point": EnvConfig(connector=ConnectorConfig(mode="fixed")),
    "ensemble/footprint": EnvConfig(collision="footprint"),
    "fixed/footprint": EnvConfig(connector=ConnectorConfig(mode="fixed"), collision="footprint"),
}


# ------------------------------------------------------------------------------------------------ scenes
def _inline_scenes() -> list[Scene]:
    """Two scenes beside the examples: circle obstacles, non-convex polygons, a slanted boundary."""
    bay = {
        "name": "inline_bay",
        "boundary": [[0, 0], [30, 0], [32, 12], [28, 22], [2, 22], [-2, 10]],
        "obstacles": [
            {"polygon": [[10.0, 0.5], [14.5, 0.5], [14.5, 5.2], [10.0, 5.2]]},
            {"polygon": [[18.5, 0.5], [23.0, 0.5], [23.0, 5.2], [18.5, 5.2]]},
            {"polygon": [[4, 12], [9, 12], [9, 14], [6, 14], [6, 17], [4, 17]]},  # non-convex L
            {"circle": [24.0, 14.0, 0.6]},
        ],
        "target": [16.5, 1.6, math.pi / 2],
    }
    lot = {
        "name": "inline_lot",
        "boundary": [[0, 0], [26, -1], [28, 14], [12, 20], [-1, 13]],
        "obstacles": [
            {"polygon": [[4, 3], [8, 2], [9, 5], [7, 4.5], [5, 6]]},  # non-convex
            {"circle": [15.0, 12.0, 0.8]},
            {"circle": [20.0, 4.0, 0.5]},
        ],
        "target": [14.0, 6.0, 0.7],
    }
    return [Scene.from_dict(bay), Scene.from_dict(lot)]


SCENES = example_scenes() + _inline_scenes()
"""The four shipped examples and the two inline scenes; a broken example fails the module loudly."""


# ------------------------------------------------------------------------------------------------ case generation
def _near_target_start(rng, scene: Scene, config: EnvConfig) -> np.ndarray:
    """A start near the target (target-frame box around it), valid under the config's convention by rejection
    against the oracle; headings spread over the circle, biased to face the target row (sin θ̃ > 0 half)."""
    for _ in range(20000):
        xt, yt = rng.uniform(-7.0, 7.0), rng.uniform(-9.0, 11.0)
        tht = rng.uniform(-math.pi, math.pi) if rng.random() < 0.4 else rng.uniform(0.2, math.pi - 0.2)
        xy = ref.from_target(np.array([xt, yt]), scene.target)
        pose = np.array([xy[0], xy[1], ref.wrap(tht + scene.target[2] - 0.5 * math.pi)])
        if ref.reference_pose_valid(scene, pose, config):
            return pose
    raise RuntimeError(f"no valid near-target start in {scene.name}")


def _region_start(rng, scene: Scene) -> np.ndarray:
    """A full-range start like the env's sampler (spec §4.3): position uniform in the start region (default the
    boundary), heading uniform, whole footprint free — by rejection against the oracle's footprint check."""
    from shapely.geometry import Point, Polygon

    region = Polygon(scene.start_region if scene.start_region is not None else scene.boundary)
    lo, hi = np.min(region.exterior.coords, axis=0), np.max(region.exterior.coords, axis=0)
    fp = EnvConfig(collision="footprint")
    for _ in range(100000):
        x, y = rng.uniform(lo, hi)
        pose = np.array([x, y, rng.uniform(-math.pi, math.pi)])
        if region.contains(Point(x, y)) and ref.reference_pose_valid(scene, pose, fp):
            return pose
    raise RuntimeError(f"no free start in {scene.name}")


def _arc_ok(scene, config, pose, a) -> tuple[bool, np.ndarray]:
    kappa, length = float(a[0]) * config.vehicle.kappa_max, float(a[1]) * config.episode.max_length_m
    samples = np.array(ref.arc_samples(pose, kappa, length, config.episode.samples_per_arc))
    ok = ref.checker(scene, config.vehicle).poses_valid(samples, config.collision == "footprint")
    return ok, samples[-1]


def _choose_action(rng, scene: Scene, config: EnvConfig, pose) -> np.ndarray:
    """Uniform (collisions), aimed (valid, lands facing the target, as close to it as possible → Hermite
    connections) or wandering (valid, lands with sin θ̃ ≤ 0 → the episode goes on)."""
    u = rng.random()
    if u < 0.25:
        return rng.uniform(-1.0, 1.0, 2).astype(np.float32)
    cands = rng.uniform(-1.0, 1.0, (24, 2)).astype(np.float32)
    cands[:, 1] *= np.float32(0.6)  # mostly moderate lengths
    scored = []
    for a in cands:
        ok, end = _arc_ok(scene, config, pose, a)
        if not ok:
            continue
        xt, yt, tht = ref.pose_to_target(end, scene.target)
        scored.append((a, math.hypot(xt, yt), math.sin(tht)))
    if not scored:
        return cands[0]
    if u < 0.55:  # aimed
        facing = [s for s in scored if s[2] > 0.0]
        pool = facing if facing else scored
        return min(pool, key=lambda s: s[1])[0]
    away = [s for s in scored if s[2] <= 0.0]  # wander
    pool = away if away else scored
    return pool[int(rng.integers(len(pool)))][0]


# ------------------------------------------------------------------------------------------------ comparison
@dataclasses.dataclass
class EpisodeState:
    """The oracle's per-env episode state, carried across steps."""

    scene_index: int
    scene: Scene
    start: np.ndarray
    pose: np.ndarray
    prev_kappa: float = 0.0
    prev_length: float = 0.0
    first_arc: bool = True
    n_rev: int = 0
    dk_eff: float = 0.0
    n_arcs: int = 0
    actions: list = dataclasses.field(default_factory=list)

    def case(self, action) -> str:
        return (f"scene={self.scene.name!r} (index {self.scene_index}), start={self.start.tolist()}, "
                f"actions before={[a.tolist() for a in self.actions]}, pose={self.pose.tolist()}, "
                f"prev_kappa={self.prev_kappa!r}, prev_length={self.prev_length!r}, first_arc={self.first_arc}, "
                f"n_rev={self.n_rev}, dk_eff={self.dk_eff!r}, n_arcs={self.n_arcs}, "
                f"action={np.asarray(action).tolist()}")


class Tally:
    def __init__(self):
        self.counts = dict(steps=0, hermite=0, direct=0, collision=0, history=0, reversal=0, truncated=0,
                           multi_feasible=0, gate_closed=0, connector_failed=0, hermite_nonzero_index=0,
                           success_after_reversal=0, first_not_cheapest=0)
        self.mismatches: list[str] = []

    def check(self, what: str, ok: bool, case: str, env_value, ref_value):
        if not ok:
            self.mismatches.append(f"{what}: env={env_value!r} reference={ref_value!r}\n    case: {case}")

    def report(self, label: str) -> str:
        head = f"{label}: {len(self.mismatches)} mismatch(es) in {self.counts['steps']} steps; coverage {self.counts}"
        return "\n".join([head, *self.mismatches[:12]] + (["    ..."] if len(self.mismatches) > 12 else []))


def compare_step(tally: Tally, config: EnvConfig, st: EpisodeState, action, r: dict, env_row: dict):
    """Compare one env row of a vector step with the oracle's result ``r``."""
    case = st.case(action)
    c = tally.counts
    c["steps"] += 1
    c["hermite"] += r["hermite_index"] >= 0
    c["direct"] += r["direct"]
    c["collision"] += not r["valid"]
    c["history"] += not st.first_arc
    c["reversal"] += (not st.first_arc) and r["length"] * st.prev_length < 0
    c["truncated"] += r["truncated"]
    c["multi_feasible"] += r["hermite_n_feasible"] > 1
    c["hermite_nonzero_index"] += r["hermite_index"] > 0
    c["first_not_cheapest"] += r["hermite_first_not_cheapest"]
    c["success_after_reversal"] += r["success"] and r["n_rev"] > 0
    if r["valid"] and not r["success"]:
        tht = ref.pose_to_target(r["pose"], st.scene.target)[2]
        c["connector_failed"] += math.sin(tht) > 0
        c["gate_closed"] += math.sin(tht) <= 0
    pose = env_row["pose"]
    dpos = max(abs(pose[0] - r["pose"][0]), abs(pose[1] - r["pose"][1]))
    dth = abs(ref.wrap(pose[2] - r["pose"][2]))
    tally.check("reached pose", dpos <= POSE_TOL and dth <= POSE_TOL, case, pose.tolist(), r["pose"].tolist())
    tally.check("collision", env_row["collision"] == (not r["valid"]), case, env_row["collision"], not r["valid"])
    tally.check("success", env_row["success"] == r["success"], case, env_row["success"], r["success"])
    tally.check("terminated", env_row["terminated"] == r["terminated"], case, env_row["terminated"], r["terminated"])
    tally.check("truncated", env_row["truncated"] == r["truncated"], case, env_row["truncated"], r["truncated"])
    tally.check("hermite_index", env_row["hermite_index"] == r["hermite_index"], case, env_row["hermite_index"],
                r["hermite_index"])
    tally.check("reward", math.isclose(env_row["reward"], r["reward"], rel_tol=REWARD_RTOL, abs_tol=1e-9), case,
                env_row["reward"], r["reward"])
    if env_row["hermite_index"] >= 0 and env_row["hermite_index"] == r["hermite_index"]:
        for key in ("hermite_length", "hermite_delta_kappa"):
            tally.check(key, math.isclose(env_row[key], r[key], rel_tol=HERMITE_RTOL, abs_tol=1e-12), case,
                        env_row[key], r[key])
    obs, robs = env_row["obs"].astype(np.float64), r["obs"]
    nb = config.observation.n_beams
    lid = np.abs(obs[4:4 + nb] - robs[4:4 + nb])
    tally.check("lidar", bool(np.all(lid <= LIDAR_TOL)), case,
                f"max |Δ| {lid.max():.3e} m at beam {int(lid.argmax())}: env {obs[4 + int(lid.argmax())]!r}",
                robs[4 + int(lid.argmax())])
    rest = np.r_[0:4, 4 + nb:len(robs)]
    close = np.isclose(obs[rest], robs[rest], rtol=1e-6, atol=1e-6)
    tally.check("observation (ego/slots)", bool(np.all(close)), case,
                f"first differing entries {rest[~close][:5].tolist()}: {obs[rest][~close][:5].tolist()}",
                robs[rest][~close][:5].tolist())


def advance(st: EpisodeState, action, r: dict) -> None:
    st.actions.append(np.asarray(action))
    st.pose = r["pose"]
    st.prev_kappa, st.prev_length = r["kappa"], r["length"]
    st.first_arc = False
    st.n_rev, st.dk_eff, st.n_arcs = r["n_rev"], r["dk_eff"], r["n_arcs"]


def env_rows(obs, reward, terminated, truncated, info, i) -> dict:
    done = bool(terminated[i] or truncated[i])
    row_obs = info["final_obs"][i] if done else obs[i]
    if done:
        assert info["_final_obs"][i]
    return {"pose": np.asarray(info["pose"][i], float), "collision": bool(info["collision"][i]),
            "success": bool(info["success"][i]), "terminated": bool(terminated[i]), "truncated": bool(truncated[i]),
            "hermite_index": int(info["hermite_index"][i]), "hermite_length": float(info["hermite_length"][i]),
            "hermite_delta_kappa": float(info["hermite_delta_kappa"][i]), "reward": float(reward[i]),
            "obs": np.asarray(row_obs)}


def run_episodes(config: EnvConfig, seed: int, num_envs: int, n_steps: int, tally: Tally) -> None:
    """``num_envs`` envs placed at near-target starts, stepped ``n_steps`` times with chosen actions; ended
    episodes continue from the env's own autoreset start (full-range sampler), with fresh oracle state."""
    rng = np.random.default_rng(seed)
    env = ParkingVectorEnv(SCENES, num_envs, config, seed=seed)
    kidx = rng.integers(len(SCENES), size=num_envs)
    starts = np.stack([_near_target_start(rng, SCENES[k], config) for k in kidx])
    obs, info = env.reset(options={"scene_index": kidx, "start": starts})
    states = [EpisodeState(int(k), SCENES[k], starts[i].copy(), starts[i].copy()) for i, k in enumerate(kidx)]
    for i, st in enumerate(states):  # reset observation
        robs = ref.reference_observation(SCENES[st.scene_index], st.pose, config)
        tally.check("reset observation", bool(np.allclose(obs[i], robs, rtol=1e-6, atol=1e-6)),
                    st.case([]), obs[i][:8].tolist(), robs[:8].tolist())
    for _ in range(n_steps):
        actions = np.stack([_choose_action(rng, SCENES[st.scene_index], config, st.pose) for st in states])
        results = [ref.reference_step(SCENES[st.scene_index], st.pose, st.prev_kappa, st.prev_length, st.first_arc,
                                      st.n_rev, st.dk_eff, st.n_arcs, actions[i], config)
                   for i, st in enumerate(states)]
        obs, reward, terminated, truncated, info = env.step(actions)
        for i, st in enumerate(states):
            r = results[i]
            compare_step(tally, config, st, actions[i], r, env_rows(obs, reward, terminated, truncated, info, i))
            if terminated[i] or truncated[i]:
                # autoreset: the env drew a new start (read back as test_env does); the oracle starts afresh
                new = env.core.S[i, K.S_X:K.S_TH + 1].copy()
                k = int(env.core.S[i, K.S_SCENE])
                states[i] = EpisodeState(k, SCENES[k], new, new.copy())
                robs = ref.reference_observation(SCENES[k], new, config)
                tally.check("autoreset observation", bool(np.allclose(obs[i], robs, rtol=1e-6, atol=1e-6)),
                            states[i].case([]), obs[i][:8].tolist(), robs[:8].tolist())
            else:
                advance(st, actions[i], r)


# ------------------------------------------------------------------------------------------------ tests
@pytest.mark.parametrize("label", list(CONFIGS))
def test_env_matches_reference_on_random_episodes(label):
    config = CONFIGS[label]
    tally = Tally()
    seed = 1000 + list(CONFIGS).index(label)
    run_episodes(config, seed, num_envs=16, n_steps=18, tally=tally)
    c = tally.counts
    # the sample must exercise every branch (a test that never reaches one is worthless)
    assert c["hermite"] >= 5, tally.report(label) + "\n(too few Hermite connections in the sample)"
    assert c["collision"] >= 5, tally.report(label) + "\n(too few collisions in the sample)"
    assert c["history"] >= 40 and c["reversal"] >= 5, tally.report(label) + "\n(history terms not exercised)"
    assert c["gate_closed"] >= 5, tally.report(label) + "\n(heading gate never closed)"
    assert c["connector_failed"] >= 5, tally.report(label) + "\n(gate open but no feasible candidate: never)"
    assert c["success_after_reversal"] >= 1, tally.report(label) + "\n(no success reward with N_rev > 0)"
    # the selection rule matters: some connections where the first feasible candidate is not the cheapest
    assert c["first_not_cheapest"] >= 1, tally.report(label) + "\n(first feasible was always the cheapest)"
    if CONFIGS[label].connector.mode == "ensemble":
        assert c["multi_feasible"] >= 3, tally.report(label) + "\n(ensemble selection never had a choice)"
    assert not tally.mismatches, tally.report(label)


@pytest.mark.parametrize("label", list(CONFIGS))
def test_direct_terminal_success_matches_reference(label):
    """Starts that retrace onto the target exactly ((κ, l) retraced by (−κ, −l), spec §2): direct success with
    p_H = 0, no Hermite candidate; compared to the oracle including the reward and the final observation."""
    config = CONFIGS[label]
    rng = np.random.default_rng(77)
    cases = []
    while len(cases) < 8:
        k = int(rng.integers(len(SCENES)))
        scene = SCENES[k]
        a = np.array([rng.uniform(-0.6, 0.6), rng.choice([-1, 1]) * rng.uniform(0.08, 0.3)], np.float32)
        kappa, length = float(a[0]) * 0.68, float(a[1]) * 10.0
        start = np.array(ref.arc_pose(scene.target, -kappa, -length))
        if not ref.reference_pose_valid(scene, start, config):
            continue
        r = ref.reference_step(scene, start, 0.0, 0.0, True, 0, 0.0, 0, a, config)
        if r["success"] and r["hermite_index"] == -1:
            cases.append((k, start, a, r))
    env = ParkingVectorEnv(SCENES, len(cases), config, seed=0)
    env.reset(options={"scene_index": np.array([c[0] for c in cases]), "start": np.stack([c[1] for c in cases])})
    out = env.step(np.stack([c[2] for c in cases]))
    tally = Tally()
    for i, (k, start, a, r) in enumerate(cases):
        assert r["direct"]
        compare_step(tally, config, EpisodeState(k, SCENES[k], start, start.copy()), a, r, env_rows(*out, i))
    assert not tally.mismatches, tally.report(label)


def test_truncation_matches_reference():
    """With a short episode (max_arcs = 4), wandering arcs that neither collide nor connect are truncated on the
    fourth arc, with the step reward only; every step is compared to the oracle."""
    config = EnvConfig(episode=EpisodeConfig(max_arcs=4))
    rng = np.random.default_rng(5)
    tally = Tally()
    n = 6
    env = ParkingVectorEnv(SCENES, n, config, seed=5)
    kidx = rng.integers(len(SCENES), size=n)
    starts = np.stack([_region_start(rng, SCENES[int(k)]) for k in kidx])
    env.reset(options={"scene_index": kidx, "start": starts})
    states = [EpisodeState(int(k), SCENES[k], starts[i].copy(), starts[i].copy()) for i, k in enumerate(kidx)]
    alive = np.ones(n, bool)
    for _ in range(4):
        actions = []
        for st in states:
            scene = SCENES[st.scene_index]
            for _ in range(200):  # wander: valid, heading gate closed at the end
                a = np.array([rng.uniform(-1, 1), rng.uniform(-0.3, 0.3)], np.float32)
                ok, end = _arc_ok(scene, config, st.pose, a)
                if ok and math.sin(ref.pose_to_target(end, scene.target)[2]) <= 0:
                    break
            actions.append(a)
        actions = np.stack(actions)
        results = [ref.reference_step(SCENES[st.scene_index], st.pose, st.prev_kappa, st.prev_length, st.first_arc,
                                      st.n_rev, st.dk_eff, st.n_arcs, actions[i], config)
                   for i, st in enumerate(states)]
        out = env.step(actions)
        for i, st in enumerate(states):
            if alive[i]:
                compare_step(tally, config, st, actions[i], results[i], env_rows(*out, i))
                advance(st, actions[i], results[i])
                if out[2][i] or out[3][i]:
                    alive[i] = False
    assert tally.counts["truncated"] >= 3, tally.report("truncation") + "\n(too few truncations)"
    assert not tally.mismatches, tally.report("truncation")


# ------------------------------------------------------------------------------------------------ targeted cases
def _single_steps(scene: Scene, config: EnvConfig, cases) -> Tally:
    """Place one env per (start, action) case in ``scene``, step once, compare each row with the oracle."""
    env = ParkingVectorEnv([scene], len(cases), config, seed=0)
    env.reset(options={"scene_index": np.zeros(len(cases), np.int64),
                       "start": np.array([c[0] for c in cases], float)})
    acts = np.array([c[1] for c in cases], np.float32)
    out = env.step(acts)
    tally = Tally()
    for i, (start, _) in enumerate(cases):
        start = np.asarray(start, float)
        r = ref.reference_step(scene, start, 0.0, 0.0, True, 0, 0.0, 0, acts[i], config)
        compare_step(tally, config, EpisodeState(0, scene, start, start.copy()), acts[i], r, env_rows(*out, i))
    return tally


OPEN_LOT = Scene.from_dict({"name": "open_lot", "boundary": [[-80, -80], [80, -80], [80, 80], [-80, 80]],
                            "obstacles": [{"circle": [-40.0, 30.0, 1.0]}], "target": [3.0, -2.0, 0.4]})


@pytest.mark.parametrize("label", list(CONFIGS))
def test_hermite_score_floor_only_in_the_ensemble(label):
    """A long Hermite connection (L_H ≈ 59 m, p_H ≈ −600): the ensemble floors p_H at −500, the fixed connector
    keeps the unclipped score (eq:terminal-reward)."""
    config = CONFIGS[label]
    xy = ref.from_target(np.array([4.3, 58.0]), OPEN_LOT.target)
    start = np.array([xy[0], xy[1], ref.wrap(1.3 + OPEN_LOT.target[2] - 0.5 * math.pi)])
    action = np.array([0.05, 0.1], np.float32)
    r = ref.reference_step(OPEN_LOT, start, 0.0, 0.0, True, 0, 0.0, 0, action, config)
    p_h = -(0.05 * r["hermite_delta_kappa"] + 10.0 * r["hermite_length"] + 5.0)
    assert r["hermite_index"] >= 0 and p_h < -500.0  # the case really reaches the floor
    tally = _single_steps(OPEN_LOT, config, [(start, action)])
    assert not tally.mismatches, tally.report(label)


EDGE_PROBE = Scene.from_dict({
    "name": "edge_probe", "boundary": [[0, 0], [40, 0], [40, 30], [0, 30]],
    "obstacles": [{"polygon": [[10, 0.5], [14, 0.5], [14, 5.2], [10, 5.2]]},
                  {"polygon": [[20, 8], [20.1, 8], [20.1, 14], [20, 14]]},  # thin wall
                  {"circle": [30.0, 20.0, 1.0]}],
    "target": [25.0, 22.0, math.pi / 2]})


def test_exact_contacts_follow_the_reference_point_convention():
    """Reference-point convention at exact contacts (spec §2): a sample exactly on an obstacle edge or vertex, or
    exactly on the boundary, is a collision; 5 cm off the edge is valid. (Straight arcs along an axis with
    exactly representable lengths land exactly on the edge: 7.7 − 2.5 == 5.2 in binary64.)"""
    up = math.pi / 2
    cases = [((12.0, 7.7, up), (0.0, -0.25)),    # lands on the top edge y = 5.2
             ((14.0, 7.7, up), (0.0, -0.25)),    # lands on the vertex (14, 5.2)
             ((30.0, 2.5, up), (0.0, -0.25)),    # lands on the boundary y = 0
             ((12.0, 7.75, up), (0.0, -0.25)),   # lands 5 cm above the edge: valid
             ((5.0, 12.5, 0.0), (0.0, 0.5))]     # open space: valid
    tally = _single_steps(EDGE_PROBE, CONFIGS["ensemble/reference_point"], cases)
    assert tally.counts["collision"] == 3
    # the LiDAR of the three terminal (collided) states whose reference point lies *on* an edge is a ray-origin
    # convention: shapely counts the origin itself as an intersection (d = 0 for every beam), the env's caster
    # requires t > 0 (App. A "strict" tests). Terminal observations of failed episodes are never bootstrapped
    # from, so only the LiDAR of those three states is exempt; everything else is compared.
    bad = [m for m in tally.mismatches if not m.startswith("lidar")]
    assert not bad, tally.report("exact contacts")
    for m in tally.mismatches:
        assert "start=[12.0, 7.75" not in m and "start=[5.0, 12.5" not in m, m


def test_thin_wall_between_samples_is_the_sampled_convention():
    """Learned arcs are checked at the 30 sampled reference points only (App. A): a straight 9 m arc whose
    samples (0.3 m apart) straddle a 0.1 m wall is valid; shifted so that a sample lands in the wall it
    collides. Both under the reference-point convention."""
    a = (0.0, 0.9)  # l = 9 m (float32 0.9 → 8.99999976 m)
    cases = [((15.05, 11.0, 0.0), a),   # samples at ≈ 19.85, 20.15: straddle x ∈ [20, 20.1]
             ((15.25, 11.0, 0.0), a)]   # sample at ≈ 20.05 lands inside the wall
    tally = _single_steps(EDGE_PROBE, CONFIGS["ensemble/reference_point"], cases)
    r0 = ref.reference_step(EDGE_PROBE, np.array(cases[0][0]), 0, 0, True, 0, 0.0, 0, np.float32(a), CONFIGS[
        "ensemble/reference_point"])
    r1 = ref.reference_step(EDGE_PROBE, np.array(cases[1][0]), 0, 0, True, 0, 0.0, 0, np.float32(a), CONFIGS[
        "ensemble/reference_point"])
    assert r0["valid"] and not r1["valid"]  # the cases mean what they say
    assert not tally.mismatches, tally.report("thin wall")


VERTEX_PROBE = Scene.from_dict({
    "name": "vertex_probe", "boundary": [[0, 0], [40, 0], [40, 30], [0, 30]],
    "obstacles": [{"polygon": [[12, 5], [14, 3], [16, 5], [14, 7]]},       # diamond, vertex (12, 5) on y = 5
                  {"polygon": [[10, 15], [14, 15], [14, 17], [10, 17]]}],  # rectangle, edges on y = 15, 17
    "target": [25.0, 22.0, math.pi / 2]})


def _lidar_mismatches(scene, poses, beams_of_interest):
    config = EnvConfig()
    env = ParkingVectorEnv([scene], len(poses), config, seed=0)
    obs, _ = env.reset(options={"scene_index": np.zeros(len(poses), np.int64), "start": np.array(poses)})
    lines = []
    for i, pose in enumerate(poses):
        robs = ref.reference_observation(scene, pose, config)
        d_ref = ref.reference_lidar(scene, pose)
        for beam in range(config.observation.n_beams):
            e, rv = float(obs[i, 4 + beam]), float(robs[4 + beam])
            if abs(e - rv) > LIDAR_TOL:
                lines.append(f"pose={list(pose)} beam {beam}: env clearance {e:.6f}, reference {rv:.6f} "
                             f"(reference d = {d_ref[beam]:.6f} m; {beams_of_interest.get((i, beam), '')})")
    return lines


def test_lidar_beam_through_a_vertex_is_not_lost():
    """A beam that enters an obstacle exactly through a vertex (or leaves the drivable region exactly through a
    boundary corner) still has a first intersection: d_i is the distance to that vertex (eq:lidar-clearance,
    "the reference-point distance to the first obstacle or boundary intersection"; the oracle intersects the ray
    with closed segments in shapely, as the test brief fixes).

    Known mismatch: the env's ``ray_segment_distance`` accepts a hit only for 0 < u < 1 *strictly* on the
    segment, so at a vertex both adjacent edges are rejected and the beam sees through the obstacle (d = 10 m
    instead of 7 m here) or out of the drivable region. Paper App. A does say the benchmark caster uses "strict,
    zero-tolerance segment-bound tests"; whether that wording was meant to include this see-through case is for
    the maintainers to decide (closed bounds 0 ≤ u ≤ 1 agree with the oracle and change nothing off vertices).
    """
    poses = [[5.0, 5.0, 0.0]]  # beam 0 along y = 5 through the diamond's vertex (12, 5); beam 75 at corner (0, 0)
    lines = _lidar_mismatches(VERTEX_PROBE, poses, {(0, 0): "enters the diamond through vertex (12, 5)",
                                                    (0, 75): "leaves the boundary through corner (0, 0)"})
    assert not lines, ("LiDAR loses intersections at vertices (strict 0 < u < 1 segment bounds in "
                       "np_sim.kernels.geometry.ray_segment_distance):\n" + "\n".join(lines))


def test_lidar_beam_grazing_an_edge():
    """A beam collinear with an obstacle edge touches the obstacle at the edge's near vertex: the oracle (shapely
    closed segments) reports that distance (5 m here).

    Known mismatch: the env never hits parallel segments and rejects the vertex hit on the adjacent edge
    (strict bounds), so it reports no hit (10 m). This is the literal reading of App. A's "strict,
    zero-tolerance segment-bound tests"; a grazing beam does not enter the obstacle, so this one is a pure
    convention question for the maintainers.
    """
    poses = [[5.0, 17.0, 0.0], [5.0, 15.0, 0.0]]  # beam 0 runs along the rectangle's top / bottom edge
    lines = _lidar_mismatches(VERTEX_PROBE, poses, {(0, 0): "runs along the top edge y = 17 from (10, 17)",
                                                    (1, 0): "runs along the bottom edge y = 15 from (10, 15)"})
    assert not lines, ("LiDAR ignores grazing contacts (parallel segments never hit, strict vertex bounds in "
                       "np_sim.kernels.geometry.ray_segment_distance):\n" + "\n".join(lines))
