"""A float64 geometry branch, for the record: its cost in the shared update and the accuracy of its gradient.

    python docs/results/2026-12-06-shared-geometry/float64_branch.py > docs/results/2026-12-06-shared-geometry/float64_branch.txt

Not part of the package: ``SceneEncoder.geometry_token`` is replaced here by a version that runs the shared branch
on float64 copies of its weights (casts, so autograd reaches the float32 parameters) and returns a float32 token.
One real Factorial collect (as ``gradient_accuracy.py``), an untrained network, random advantages and returns.
Timed with the other jobs on the machine paused.
"""

import copy
import statistics
import sys
import time
from pathlib import Path

import torch
from torch.func import functional_call

sys.path.insert(0, str(Path(__file__).resolve().parent))
from gradient_accuracy import chunk_batch, collect_obs  # noqa: E402
from np_policy.config import PPOConfig  # noqa: E402
from np_policy.network import SceneEncoder  # noqa: E402
from np_policy.ppo import accumulate_minibatch_gradient, make_optimizer, ppo_update  # noqa: E402

FLOAT32_TOKEN = SceneEncoder.geometry_token
NOISY = ("encoder.obstacle.0.weight", "encoder.boundary.0.weight", "encoder.geometry_attention.qkv.weight")


def _float64(module, x):
    return functional_call(module, {n: p.double() for n, p in module.named_parameters()}, (x,))


def float64_token(self, slots, shared=False):
    distinct, row = torch.unique(slots, dim=0, return_inverse=True)
    d, oc = distinct.double(), self.obs_config
    size = oc.max_obstacles * 2 * oc.vertices_per_obstacle
    tokens = torch.cat([_float64(self.obstacle, d[:, :size].reshape(len(d), oc.max_obstacles, -1)),
                        _float64(self.boundary, d[:, size:].reshape(len(d), oc.max_boundary_segments, 4))], 1)
    tokens = tokens + self.slot_position.double()
    return _float64(self.geometry_summary, _float64(self.geometry_attention, tokens).mean(1)).float()[row]


def update_ms(model, batch) -> float:
    optimizer, g, config = make_optimizer(model, PPOConfig()), torch.Generator().manual_seed(0), PPOConfig(repeats=1)
    ppo_update(model, optimizer, batch, config, g, True)
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        ppo_update(model, optimizer, batch, config, g, True)
        times.append(time.perf_counter() - t0)
    return 1000 * statistics.median(times) / 2


def main() -> None:
    torch.set_num_threads(1)
    model, obs = collect_obs()
    batch = chunk_batch(model, obs)
    for variant, token in (("float32", FLOAT32_TOKEN), ("float64", float64_token)) * 2:
        SceneEncoder.geometry_token = token
        print(f"{variant} branch: {update_ms(copy.deepcopy(model), batch):.0f} ms per minibatch update of 8,192 "
              "(shared)")
    chunk = {k: v[:1024] for k, v in batch.items()}
    config, index = PPOConfig(batch_size=1024, update_chunk=1024), torch.arange(1024)
    SceneEncoder.geometry_token = FLOAT32_TOKEN
    wide = copy.deepcopy(model).double()
    accumulate_minibatch_gradient(wide, {k: v.double() for k, v in chunk.items()}, index, config, True)
    for variant, token in (("float32", FLOAT32_TOKEN), ("float64", float64_token)):
        SceneEncoder.geometry_token = token
        narrow = copy.deepcopy(model)
        accumulate_minibatch_gradient(narrow, chunk, index, config, True)
        errors = [((narrow.get_parameter(n).grad.double() - wide.get_parameter(n).grad).norm()
                   / wide.get_parameter(n).grad.norm()).item() for n in NOISY]
        print(f"{variant} branch, relative error against float64 of {', '.join(NOISY)}: "
              + ", ".join(f"{e:.1e}" for e in errors))


if __name__ == "__main__":
    main()
