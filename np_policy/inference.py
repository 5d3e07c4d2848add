"""Compiled single-observation inference of the actor's mean action (the planner's hot path).

``ActorCritic.mean_action`` in torch costs about 0.4 ms per call at batch 1 on this CPU, almost all of it
per-operator overhead; a plan calls it once per arc. ``CompiledActor`` copies the trained weights into numpy
arrays and evaluates the same network — stream MLPs, the geometry-token attention block, the global–local fusion
block(s), the projection and the actor MLP of ``np_policy.network`` (paper §III-C, App. A Table IV) — in one
numba function, so a call costs tens of microseconds. It is tested against the torch model to float32 rounding.

A batch of ``TORCH_BATCH`` or more observations (the footprint planner's sampled and rescue rollouts) goes to the
torch model instead: its batched forward does the products over all rows at once, about three times the rows per
second of the compiled kernel at batches of 32–128 with one thread, where the compiled kernel pays a small product
per layer and row (``python -m np_policy.bench_actor``). The actions agree to float32 rounding, not bit for bit;
a batch of one (the paper's planner, the mean rollout) always takes the compiled kernel, and a whole mean rollout of
one env runs as one compiled loop of the actor and the env's step (``CompiledActor.mean_rollout``): the per-arc
Python round trip (array checks, two kernel dispatches) cost about as much as the network and the step themselves.
That loop computes the geometry token (the obstacle and boundary slot streams and their attention block, about
half the network's products) once: the slots are the scene's, constant in the target frame
(`np_sim.observation`), so every arc's token is the first arc's, bit for bit; only the ego (and LiDAR) streams,
the fusion and the actor run per arc.

Layout: the weights are flattened into two typed lists, matrices (in × out, so ``x @ W``) and vectors (biases,
LayerNorm gains and offsets), in exactly the order ``_mean_action`` consumes them; ``_export`` is the one place
that order is written on the Python side. The lists are filled inside a cached kernel from one flat buffer: a typed
list's ``append`` called from Python compiles afresh in every process (about 2 s, numba does not cache it).
"""

from __future__ import annotations

import math

import numpy as np
import torch
from numba import njit
from numba.typed import List
from torch import nn

import np_sim.kernels  # noqa: F401  (sets numba's cache directory)
from np_sim.env_core import action_space_error
from np_sim.kernels import step as K
from np_policy.network import ActorCritic, SelfAttentionBlock


TORCH_BATCH = 8
"""Batches of at least this many observations run the torch model's forward (module docstring): from about 8 rows
its batched forward passes the compiled kernel called per row (``python -m np_policy.bench_actor``)."""


@njit(cache=True, error_model="numpy")
def _dense(x, mats, vecs, cursor, relu):
    """y = x W + b (optionally ReLU) with the next matrix and vector; returns y and the advanced cursor."""
    y = np.ascontiguousarray(x) @ mats[cursor[0]] + vecs[cursor[1]]
    cursor[0] += 1
    cursor[1] += 1
    if relu:
        y = np.maximum(y, np.float32(0.0))
    return y


@njit(cache=True, error_model="numpy")
def _layer_norm(x, vecs, cursor, eps):
    """Row-wise LayerNorm (biased variance) with the next gain and offset vectors."""
    gain, offset = vecs[cursor[1]], vecs[cursor[1] + 1]
    cursor[1] += 2
    out = np.empty_like(x)
    for r in range(x.shape[0]):
        mean = x[r].mean()
        var = ((x[r] - mean) ** 2).mean()
        out[r] = (x[r] - mean) / np.sqrt(var + eps) * gain + offset
    return out


@njit(cache=True, error_model="numpy")
def _attention_block(x, heads, mats, vecs, cursor, eps):
    """Post-norm transformer layer of ``SelfAttentionBlock``: x ← LN(x + MHA(x)); x ← LN(x + FF(x))."""
    s, d = x.shape
    dh = d // heads
    qkv = _dense(x, mats, vecs, cursor, False)
    attended = np.empty((s, d), np.float32)
    scale = np.float32(1.0 / math.sqrt(dh))
    for h in range(heads):
        q = np.ascontiguousarray(qkv[:, h * dh:(h + 1) * dh])
        k = np.ascontiguousarray(qkv[:, d + h * dh:d + (h + 1) * dh])
        v = np.ascontiguousarray(qkv[:, 2 * d + h * dh:2 * d + (h + 1) * dh])
        scores = (q @ k.T.copy()) * scale
        for r in range(s):
            row = np.exp(scores[r] - scores[r].max())
            scores[r] = row / row.sum()
        attended[:, h * dh:(h + 1) * dh] = scores @ v
    x = _layer_norm(x + _dense(attended, mats, vecs, cursor, False), vecs, cursor, eps)
    hidden = _dense(x, mats, vecs, cursor, True)
    return _layer_norm(x + _dense(hidden, mats, vecs, cursor, False), vecs, cursor, eps)


@njit(cache=True, error_model="numpy")
def _stream_tokens(obs, mats, vecs, sections, cursor):
    """The ego token and, when present, the LiDAR token of one flat observation (the per-pose streams)."""
    tokens = List()
    hidden = _dense(obs[sections[0, 0]:sections[0, 1]].reshape(1, -1), mats, vecs, cursor, True)
    tokens.append(_dense(hidden, mats, vecs, cursor, False))
    if sections[1, 1] > sections[1, 0]:
        hidden = _dense(obs[sections[1, 0]:sections[1, 1]].reshape(1, -1), mats, vecs, cursor, True)
        tokens.append(_dense(hidden, mats, vecs, cursor, False))
    return tokens


@njit(cache=True, error_model="numpy")
def _geometry_token(obs, mats, vecs, sections, shape, eps, cursor):
    """The (1, d) geometry token of one flat observation (paper §III-C: obstacle and boundary slot streams, learned
    slot positions, the geometry-token attention block and its mean summary); (0, 0) without geometry slots. It
    reads only the scene-constant slots (`np_sim.observation`), so one rollout's arcs share it."""
    slots = List()
    if sections[2, 1] > sections[2, 0]:
        width = shape[0]
        rows = np.ascontiguousarray(obs[sections[2, 0]:sections[2, 1]]).reshape(-1, width)
        slots.append(_dense(_dense(rows, mats, vecs, cursor, True), mats, vecs, cursor, False))
    if sections[3, 1] > sections[3, 0]:
        rows = np.ascontiguousarray(obs[sections[3, 0]:sections[3, 1]]).reshape(-1, 4)
        slots.append(_dense(_dense(rows, mats, vecs, cursor, True), mats, vecs, cursor, False))
    if len(slots) == 0:
        return np.empty((0, 0), np.float32)
    n = 0
    for part in slots:
        n += part.shape[0]
    geometry = np.empty((n, slots[0].shape[1]), np.float32)
    row = 0
    for part in slots:
        geometry[row:row + part.shape[0]] = part
        row += part.shape[0]
    geometry += mats[cursor[0]]  # learned slot positions
    cursor[0] += 1
    geometry = _attention_block(geometry, shape[1], mats, vecs, cursor, eps)
    summary = np.empty((1, geometry.shape[1]), np.float32)
    for c in range(geometry.shape[1]):
        summary[0, c] = geometry[:, c].mean()
    return _dense(summary, mats, vecs, cursor, False)


@njit(cache=True, error_model="numpy")
def _fused_action(tokens, mats, vecs, shape, eps, cursor):
    """The fusion block(s), projection and actor MLP on the stream tokens, clipped to [−1, 1]."""
    d = tokens[0].shape[1]
    fused = np.empty((len(tokens), d), np.float32)
    for i in range(len(tokens)):
        fused[i] = tokens[i][0]
    for _ in range(shape[3]):
        fused = _attention_block(fused, shape[2], mats, vecs, cursor, eps)
    feature = _dense(fused.reshape(1, -1), mats, vecs, cursor, True)
    for layer in range(shape[4]):
        feature = _dense(feature, mats, vecs, cursor, layer < shape[4] - 1)
    return np.minimum(np.maximum(feature[0], np.float32(-1.0)), np.float32(1.0))


@njit(cache=True, error_model="numpy")
def _mean_action(obs, mats, vecs, sections, shape, eps):
    """Deterministic action of one flat observation, clipped to [−1, 1] (``ActorCritic.mean_action``).

    ``sections`` (4, 2): (start, stop) of ego, lidar, obstacles, boundary, stop = start when absent;
    ``shape``: obstacle vertex-pair width, geometry heads, fusion heads, fusion depth, actor layers.
    """
    cursor = np.zeros(2, np.int64)
    tokens = _stream_tokens(obs, mats, vecs, sections, cursor)
    geometry = _geometry_token(obs, mats, vecs, sections, shape, eps, cursor)
    if geometry.shape[0] > 0:
        tokens.append(geometry)
    return _fused_action(tokens, mats, vecs, shape, eps, cursor)


@njit(cache=True, error_model="numpy")
def _mean_actions(obs, mats, vecs, sections, shape, eps):
    """``_mean_action`` of every row of ``obs`` (B, obs_size) -> (B, 2), in one call (one dispatch)."""
    out = np.empty((obs.shape[0], 2), np.float32)
    for r in range(obs.shape[0]):
        out[r] = _mean_action(obs[r], mats, vecs, sections, shape, eps)
    return out


@njit(cache=True, error_model="numpy")
def _mean_rollout(geo, targets, static_obs, S, P, local, b_ranges, off_c, off_s, offsets, headings, scales0, scales1,
                  basis, dbasis, pts, kbar_max, dk, lengths, costs, obs, R, mats, vecs, sections, shape, eps, actions):
    """Env 0 of a batched env core stepped by its mean action (``_mean_action``'s network, its geometry token
    computed once: module docstring; then the env's ``step_one``) until it terminates or reaches its arc budget; each
    normalised action into a row of ``actions``. Returns the number of arcs, or −(that number) when the last action
    was not finite (its step not taken)."""
    cursor = np.zeros(2, np.int64)
    _stream_tokens(obs[0], mats, vecs, sections, cursor)  # only to move the cursor past the streams' weights
    geometry = _geometry_token(obs[0], mats, vecs, sections, shape, eps, cursor)
    after_geometry = cursor.copy()
    n = 0
    while True:
        cursor[:] = 0
        tokens = _stream_tokens(obs[0], mats, vecs, sections, cursor)
        if geometry.shape[0] > 0:
            tokens.append(geometry)
        cursor[:] = after_geometry
        action = _fused_action(tokens, mats, vecs, shape, eps, cursor)
        a0 = np.float64(action[0])
        a1 = np.float64(action[1])
        actions[n, 0] = a0
        actions[n, 1] = a1
        n += 1
        if not (np.isfinite(a0) and np.isfinite(a1)):
            return -n
        K.step_one(geo, targets, static_obs, S, P, 0, a0 * P[K.P_KAPPA_MAX], a1 * P[K.P_LENGTH_MAX], local, b_ranges,
                   off_c, off_s, offsets, headings, scales0, scales1, basis, dbasis, pts[0], kbar_max[0], dk[0],
                   lengths[0], costs[0], obs[0], R[0])
        if R[0, K.R_TERMINATED] > 0.0 or R[0, K.R_TRUNCATED] > 0.0:
            return n


def _export(model: ActorCritic) -> tuple[List, List]:
    """The weights in ``_mean_action``'s consumption order (matrices transposed to in × out), as the two typed
    lists the kernels take, built by ``_typed_lists`` from one flat buffer (module docstring)."""
    mats, vecs = [], []

    def dense(layer: nn.Linear) -> None:
        mats.append(layer.weight.detach().numpy().T)
        vecs.append(layer.bias.detach().numpy())

    def norm(layer: nn.LayerNorm) -> None:
        vecs.append(layer.weight.detach().numpy())
        vecs.append(layer.bias.detach().numpy())

    def block(b: SelfAttentionBlock) -> None:
        dense(b.qkv), dense(b.out), norm(b.norm1), dense(b.ff[0]), dense(b.ff[2]), norm(b.norm2)

    def mlp(seq: nn.Sequential) -> None:
        for layer in seq:
            if isinstance(layer, nn.Linear):
                dense(layer)

    enc = model.encoder
    for stream in (enc.ego, enc.lidar, enc.obstacle, enc.boundary):
        if stream is not None:
            mlp(stream)
    if enc.n_slots:
        mats.append(enc.slot_position.detach().numpy())
        block(enc.geometry_attention)
        dense(enc.geometry_summary)
    for b in enc.fusion:
        block(b)
    dense(enc.project)
    mlp(model.actor)
    flat = np.concatenate([a.astype(np.float32).ravel() for a in mats + vecs])
    shapes = np.array([a.shape for a in mats] + [(1, a.shape[0]) for a in vecs], np.int64)
    return _typed_lists(flat, shapes, len(mats))


@njit(cache=True, error_model="numpy")
def _typed_lists(flat, shapes, n_mats):
    """Split ``flat`` (float32) into the matrices ``shapes[:n_mats]`` (rows, cols) and the vectors
    ``shapes[n_mats:]`` (1, length), in order, each its own C-contiguous copy: (matrices, vectors)."""
    mats, vecs = List(), List()
    start = 0
    for i in range(shapes.shape[0]):
        rows, cols = shapes[i, 0], shapes[i, 1]
        block = flat[start:start + rows * cols].copy()
        start += rows * cols
        if i < n_mats:
            mats.append(block.reshape(rows, cols))
        else:
            vecs.append(block)
    return mats, vecs


class CompiledActor:
    """The mean action of a trained ``ActorCritic`` for one observation, compiled (see module docstring)."""

    def __init__(self, model: ActorCritic):
        enc = model.encoder
        norms = [m for m in model.modules() if isinstance(m, nn.LayerNorm)]
        eps = {m.eps for m in norms}
        if len(eps) > 1:
            raise ValueError(f"CompiledActor: LayerNorms with different eps {sorted(eps)} are not supported")
        self.eps = np.float32(eps.pop() if eps else 1e-5)
        self.sections = np.zeros((4, 2), np.int64)
        for i, name in enumerate(("ego", "lidar", "obstacles", "boundary")):
            if name in enc.sections:
                self.sections[i] = enc.sections[name]
        net = enc.net_config
        n_actor = sum(isinstance(m, nn.Linear) for m in model.actor)
        self.shape = np.array([2 * enc.obs_config.vertices_per_obstacle, net.token_heads, net.fusion_heads,
                               len(enc.fusion), n_actor], np.int64)
        self.obs_size = enc.obs_size
        self.model = model
        self.torch_only = enc.bev is not None
        """The compiled kernel has no BEV stream: a BEV-input network (Table III's control) acts through torch."""
        with torch.no_grad():
            self.mats, self.vecs = ([], []) if self.torch_only else _export(model)

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        """(2,) float32 action in [−1, 1] for one flat observation of length ``obs_size``."""
        obs = np.ascontiguousarray(obs, dtype=np.float32)
        if obs.shape != (self.obs_size,):
            raise ValueError(f"CompiledActor: expected one observation of shape ({self.obs_size},), "
                             f"got {obs.shape}")
        if self.torch_only:
            return self.model.mean_action(torch.from_numpy(obs[None])).numpy()[0]
        return _mean_action(obs, self.mats, self.vecs, self.sections, self.shape, self.eps)

    def batch(self, obs: np.ndarray) -> np.ndarray:
        """(B, 2) float32 actions for B flat observations (B, ``obs_size``): one compiled call for all rows below
        ``TORCH_BATCH`` rows, the torch model's batched forward from there (module docstring)."""
        obs = np.ascontiguousarray(obs, dtype=np.float32)
        if obs.ndim != 2 or obs.shape[1] != self.obs_size:
            raise ValueError(f"CompiledActor.batch: expected observations of shape (B, {self.obs_size}), "
                             f"got {obs.shape}")
        if len(obs) >= TORCH_BATCH or self.torch_only:
            return self.model.mean_action(torch.from_numpy(obs)).numpy()
        return _mean_actions(obs, self.mats, self.vecs, self.sections, self.shape, self.eps)

    def plays_rollout(self, core) -> bool:
        """Whether ``mean_rollout`` can play in ``core`` (an `np_sim.env_core.BatchCore`): one env, the compiled
        kernel, and an observation the step kernel writes whole (no nearest-object slots, no BEV latent)."""
        return core.num_envs == 1 and not self.torch_only and not core.selectors and core.bev is None

    def mean_rollout(self, core) -> np.ndarray:
        """(arcs, 2) normalised actions of env 0's mean rollout in ``core`` from its current state (reset first, its
        observation row as the reset wrote it; ``plays_rollout`` must hold), ``core`` left at its end: the batched
        loop of `np_policy.sampling` with a batch of one and zero noise, arc for arc, in one compiled call (module
        docstring). ValueError on a non-finite action, as the env's step raises."""
        actions = np.empty((int(core.P[K.P_MAX_ARCS]), 2))
        n = _mean_rollout(core.geo, core.arrays.targets, core.static_obs, core.S, core.P, core.local, core.b_ranges,
                          core.off_c, core.off_s, core.offsets, core.headings, core.scales0, core.scales1, core.basis,
                          core.dbasis, core.h_pts, core.h_kbar_max, core.h_dk, core.h_len, core.h_cost, core.obs,
                          core.R, self.mats, self.vecs, self.sections, self.shape, self.eps, actions)
        if n < 0:
            raise action_space_error(0, actions[-n - 1])
        return actions[:n]
