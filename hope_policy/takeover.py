"""HOPE's shortest-first Reeds–Shepp takeover near the target (``jiamiya/HOPE`` ``car_parking_base.py``
``find_rs_path``, ``parking_agent.py`` ``RsPlanner``), checked under the benchmark convention (paper App. B).

When the episode continues and the reference point is within ``rs_max_dist_m`` (HOPE's RS_MAX_DIST = 10 m) of
the target, every Reeds–Shepp word (``np_sim.kernels.reeds_shepp``) to the target at HOPE's curvature bound
tan(δ_max)/wheelbase is a candidate. Candidates are tried shortest first; the search stops at the first valid one,
or at a candidate longer than ``rs_length_ratio`` (1.6) × the shortest once two have been tried. A candidate is
valid when the points along it at spacing ≤ ``rs_spacing_m`` (0.1 m) pass the benchmark checks (reference point
strictly inside the boundary and outside every obstacle, or the footprint under the footprint convention).

The accepted path is cut into chunks of at most one full-speed action (v_max · T = 1.25 m), each piece's full
chunks first and its remainder last (HOPE ``RsPlanner.set_rs_path``). Chunks then replace the policy's actions one
per step and go through the environment's step: 30-sample hard checks, success and the Hermite terminator.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.collision import arc_valid
from np_sim.kernels.kinematics import arc_point
from np_sim.kernels.reeds_shepp import MAX_PIECES, all_words, relative_goal
from np_sim.reeds_shepp import MIN_PIECE_M

MAX_WORDS = 48
MAX_CHUNKS = 128
"""Capacity of the takeover queue; a candidate needing more chunks (longer than 128 full-speed actions) is
rejected like an invalid one."""


@njit(cache=True, error_model="numpy")
def candidate_arcs(x0: float, y0: float, th0: float, target: np.ndarray, kappa_max: float, arcs: np.ndarray,
                   counts: np.ndarray, totals: np.ndarray) -> int:
    """All RS candidates from (x0, y0, θ0) to ``target`` as eq:arc arcs (κ, l) into ``arcs`` (48, 5, 2): a piece of
    letter c and normalised length u is l = u/κ_max, κ = −sgn(l)·c·κ_max (spec §2); ``totals`` their lengths (m)."""
    x, y, phi = relative_goal(x0, y0, th0, target[0], target[1], target[2], kappa_max)
    letters = np.empty((MAX_WORDS, MAX_PIECES), np.int64)
    lengths = np.empty((MAX_WORDS, MAX_PIECES))
    n_words = all_words(x, y, phi, letters, lengths, counts)
    for w in range(n_words):
        total = 0.0
        for i in range(counts[w]):
            length = lengths[w, i] / kappa_max
            gear = 1.0 if length > 0.0 else -1.0
            arcs[w, i, 0] = -gear * letters[w, i] * kappa_max
            arcs[w, i, 1] = length
            total += abs(length)
        totals[w] = total
    return n_words


@njit(cache=True, error_model="numpy")
def chunk_arcs(arcs: np.ndarray, n: int, max_length: float, out: np.ndarray) -> int:
    """Cut the arcs ``arcs[:n]`` into chunks of length ≤ ``max_length`` (full chunks first, remainder last) into
    ``out``; returns the chunk count, or −1 when ``out`` is too small. Pieces shorter than ``MIN_PIECE_M`` are
    rounding residue at word boundaries and are skipped, as in ``np_sim.reeds_shepp``."""
    m = 0
    for i in range(n):
        kappa, length = arcs[i, 0], arcs[i, 1]
        if abs(length) < MIN_PIECE_M:
            continue
        sign = 1.0 if length > 0.0 else -1.0
        rest = abs(length)
        while rest > 0.0:
            piece = min(rest, max_length)
            if m >= out.shape[0]:
                return -1
            out[m, 0] = kappa
            out[m, 1] = sign * piece
            m += 1
            rest -= piece
            if rest < MIN_PIECE_M:
                rest = 0.0
    return m


@njit(cache=True, error_model="numpy")
def path_valid(geo, k: int, x: float, y: float, th: float, arcs: np.ndarray, n: int, spacing: float,
               footprint: bool, local: np.ndarray) -> bool:
    """The arcs ``arcs[:n]`` from (x, y, θ) pass the benchmark checks at points spaced ≤ ``spacing`` (m)."""
    corners = np.empty((4, 2))
    for i in range(n):
        kappa, length = arcs[i, 0], arcs[i, 1]
        samples = max(1, int(math.ceil(abs(length) / spacing)))
        if not arc_valid(geo, k, x, y, th, kappa, length, samples, footprint, local, corners):
            return False
        x, y, th = arc_point(x, y, th, kappa, length)
    return True


@njit(cache=True, error_model="numpy")
def find_takeover(geo, k: int, x: float, y: float, th: float, target: np.ndarray, kappa_max: float,
                  spacing: float, ratio: float, footprint: bool, local: np.ndarray, max_chunk: float,
                  queue: np.ndarray) -> int:
    """Shortest-first search (module docstring); the accepted path's chunks into ``queue`` (MAX_CHUNKS, 2).
    Returns the chunk count, 0 when no candidate is accepted."""
    arcs = np.empty((MAX_WORDS, MAX_PIECES, 2))
    counts = np.zeros(MAX_WORDS, np.int64)
    totals = np.empty(MAX_WORDS)
    n_words = candidate_arcs(x, y, th, target, kappa_max, arcs, counts, totals)
    order = np.argsort(totals[:n_words], kind="mergesort")
    for r in range(n_words):
        w = order[r]
        if r >= 2 and totals[w] > ratio * totals[order[0]]:
            break
        if not path_valid(geo, k, x, y, th, arcs[w], counts[w], spacing, footprint, local):
            continue
        m = chunk_arcs(arcs[w], counts[w], max_chunk, queue)
        if m > 0:
            return m
    return 0
