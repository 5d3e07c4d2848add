"""Tests of np_policy/distill.py: the replayed observations are the ones the policy acted on (its torch mean gives
back the mean rollout's arcs), the imitation loss against hand values, the fit lowering its loss on replayed
pairs, and a small collection whose counts add up and whose pairs replay accepted plans."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from np_policy.config import FOOTPRINT_ANYTIME
from np_policy.distill import collect, distill, fit, imitation_loss, replay_observations
from np_policy.planner import NeuralParkerPlanner, Policy
from np_sim.clips import find_clip

CHECKPOINT = Path("checkpoints/site_np_footprint.pt")
pytestmark = pytest.mark.skipif(not CHECKPOINT.exists(), reason="no shipped footprint-aware site checkpoint")


@pytest.fixture(scope="module")
def planner():
    return NeuralParkerPlanner(Policy.load(CHECKPOINT, "site"), FOOTPRINT_ANYTIME)


@pytest.fixture(scope="module")
def clip():
    return find_clip("train-0000009")


def _mean_rollout(planner, clip):
    scene = clip.frame_scene(0, pose=np.asarray(clip.start, float), vehicle=planner.body)
    start = np.asarray(clip.start, float)
    return scene, start, planner.mean(scene, start)[0]


def test_replayed_observations_give_back_the_mean_rollouts_arcs(planner, clip):
    scene, start, plan = _mean_rollout(planner, clip)
    scale = np.array([planner.env_config.vehicle.kappa_max, planner.env_config.episode.max_length_m])
    actions = np.asarray(plan.arcs) / scale
    if not plan.success:
        pytest.skip("this clip's mean rollout fails; the replay needs a success")
    obs = replay_observations(planner, scene, start, actions)
    assert obs.shape[0] == len(actions)
    with torch.no_grad():
        torch_mean = planner.model.mean_action(torch.from_numpy(obs)).numpy()
    np.testing.assert_allclose(torch_mean, actions, atol=1e-4)
    # a different first action is another episode: no longer the same success of the same length
    changed = actions.copy()
    changed[0] = -changed[0]
    other = replay_observations(planner, scene, start, changed)
    assert other is None or not np.array_equal(other, obs)


def test_imitation_loss_against_hand_values():
    mean = torch.tensor([[0.5, 1.2], [1.2, -0.3]])
    target = torch.tensor([[0.0, 1.0], [0.5, -1.0]])
    # entries: 0.25, 0 (target at +1 and mean beyond it), 0.49, 0.49 → mean over four
    assert float(imitation_loss(mean, target)) == pytest.approx((0.25 + 0.0 + 0.49 + 0.49) / 4)


def test_collection_counts_add_up_and_the_fit_lowers_the_loss(planner, clip):
    obs, actions, owner, counts = collect(planner, [clip], 6, seed=0, progress=False)
    assert counts["accepted"] + counts["not_accepted"] + counts["start_in_collision"] + counts["replay_mismatch"] == 6
    assert counts["accepted"] >= 1 and counts["replay_mismatch"] == 0
    assert len(obs) == len(actions) and actions.shape[1] == 2 and np.all(np.abs(actions) <= 1 + 1e-9)
    assert len(np.unique(owner)) == counts["accepted"]
    # targets the policy does not play yet (halved arcs): the fit must move its mean towards them
    policy = Policy.load(CHECKPOINT, "site")
    rows = fit(policy, obs, actions * 0.5, owner, epochs=30, learning_rate=1e-3, seed=0, progress=False)
    assert rows[-1]["train_loss"] < 0.5 * rows[1]["train_loss"]
    assert rows[-1]["held_out_loss"] is None  # six resets: a tenth rounds down to none held out


def test_distill_writes_a_run_folder_whose_policy_loads(tmp_path, clip):
    summary = distill(CHECKPOINT, tmp_path, resets=3, epochs=2, seed=1, progress=False, clips=[clip])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["best.pt", "config.json", "distill.json",
                                                          "metrics.jsonl", "pairs.npz"]
    policy = Policy.load(tmp_path / "best.pt", "site")
    source = Policy.load(CHECKPOINT, "site")
    assert policy.train == source.train  # same env rules: the planner plays it exactly like the source
    assert len((tmp_path / "metrics.jsonl").read_text().splitlines()) == 3  # epoch 0 and two fitted epochs
    pairs = np.load(tmp_path / "pairs.npz")
    assert len(pairs["obs"]) == summary["pairs"] == len(pairs["actions"])
    # a refit from those pairs plans nothing and fits the same data
    (tmp_path / "refit").mkdir()
    again = distill(CHECKPOINT, tmp_path / "refit", epochs=1, progress=False, pairs=tmp_path / "pairs.npz", clips=[])
    assert again["pairs"] == summary["pairs"] and again["counts"]["accepted"] == summary["counts"]["accepted"]
    np.testing.assert_array_equal(np.load(tmp_path / "refit" / "pairs.npz")["obs"], pairs["obs"])


def test_cli_refuses_a_used_folder_and_a_bad_count_in_one_line(tmp_path, capsys):
    from cli_helpers import one_error_line
    from np_policy.distill import main

    (tmp_path / "used").mkdir()
    (tmp_path / "used" / "best.pt").write_bytes(b"")
    assert "used" in one_error_line(capsys, main, ["--out", str(tmp_path / "used")])
    assert "--resets" in one_error_line(capsys, main, ["--out", str(tmp_path / "new"), "--resets", "0"])
