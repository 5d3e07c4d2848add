"""Compiled Reeds–Shepp shortest paths (Reeds & Shepp 1990, Pacific J. Math. 145(2), §8 formulas 8.1–8.11).

Work is done in the normalised frame of the start pose: goal (x, y, φ) relative to the start, lengths in units of
the minimum turning radius r = 1/κ_max. A *word* is a sequence of up to five pieces, each a letter (``LEFT`` = +1,
``STRAIGHT`` = 0, ``RIGHT`` = −1: the physical steering direction) and a signed normalised length (sign = gear).
Eight base formulas, each closed in (x, y, φ), generate all 48 words through the paper's symmetries:

* timeflip (x, y, φ) → (−x, y, −φ): every piece length negated (gears swapped);
* reflect  (x, y, φ) → (x, −y, −φ): left and right swapped;
* backwards (x, y, φ) → (x cos φ + y sin φ, x sin φ − y cos φ, φ): the word read in reverse order.

Family counts: CSC 8, CCC 12 (C|C|C, C|CC, CC|C), CCCC 8 (CC|CC, C|CC|C), CCSC 16 (C|C_{π/2}SC and CSC_{π/2}|C in both
turning orders), CCSCC 4 (C|C_{π/2}SC_{π/2}|C) — 48 in all.

The pieces map onto the action arcs of paper eq:arc (spec §2): a piece of letter c ∈ {+1, 0, −1} and normalised
signed length t is the arc (κ, l) with l = t / κ_max and κ = −sgn(l)·c·κ_max (physical steering c·κ_max).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.kinematics import wrap_angle

LEFT, STRAIGHT, RIGHT = 1, 0, -1
_ZERO = 1e-14  # accept a piece whose sign test fails by rounding only
_HALF_PI = 0.5 * math.pi

# Letters of the eight base words (rows padded with STRAIGHT; _N_PIECES gives the used count) and whether the
# "backwards" symmetry generates new words from them (it does for the asymmetric CCC and CCSC bases).
_BASE_LETTERS = np.array(
    [
        [LEFT, STRAIGHT, LEFT, 0, 0],  # 8.1  L+ S+ L+
        [LEFT, STRAIGHT, RIGHT, 0, 0],  # 8.2  L+ S+ R+
        [LEFT, RIGHT, LEFT, 0, 0],  # 8.3/8.4  L+ R− L
        [LEFT, RIGHT, LEFT, RIGHT, 0],  # 8.7  L+ R+u L−u R−
        [LEFT, RIGHT, LEFT, RIGHT, 0],  # 8.8  L+ R−u L−u R+
        [LEFT, RIGHT, STRAIGHT, LEFT, 0],  # 8.9  L+ R−π/2 S− L−
        [LEFT, RIGHT, STRAIGHT, RIGHT, 0],  # 8.10 L+ R−π/2 S− R−
        [LEFT, RIGHT, STRAIGHT, LEFT, RIGHT],  # 8.11 L+ R−π/2 S− L−π/2 R+
    ],
    dtype=np.int64,
)
_N_PIECES = np.array([3, 3, 3, 4, 4, 4, 4, 5], dtype=np.int64)
_HAS_BACKWARDS = np.array([False, False, True, False, False, True, True, False])
N_BASES = 8
MAX_PIECES = 5


@njit(cache=True, error_model="numpy")
def _tau_omega(u: float, v: float, xi: float, eta: float, phi: float):
    """(τ, ω) of the CCCC formulas 8.7/8.8: the first and last turn angles given the middle ones."""
    delta = wrap_angle(u - v)
    a = math.sin(u) - math.sin(delta)
    b = math.cos(u) - math.cos(delta) - 1.0
    t1 = math.atan2(eta * a - xi * b, xi * a + eta * b)
    t2 = 2.0 * (math.cos(delta) - math.cos(v) - math.cos(u)) + 3.0
    tau = wrap_angle(t1 + math.pi) if t2 < 0.0 else wrap_angle(t1)
    return tau, wrap_angle(tau - u + v - phi)


# The base formulas: each takes the normalised goal (x, y, φ) with sp = sin φ, cp = cos φ, writes the signed
# normalised piece lengths into out (5,) and returns whether the word exists with the gear pattern of its name.


@njit(cache=True, error_model="numpy")
def _lsl(x: float, y: float, phi: float, sp: float, cp: float, out: np.ndarray) -> bool:
    """Formula 8.1, L+ S+ L+."""
    xi, eta = x - sp, y - 1.0 + cp
    u = math.hypot(xi, eta)
    t = math.atan2(eta, xi)
    v = wrap_angle(phi - t)
    out[0], out[1], out[2] = t, u, v
    return t >= -_ZERO and v >= -_ZERO


@njit(cache=True, error_model="numpy")
def _lsr(x: float, y: float, phi: float, sp: float, cp: float, out: np.ndarray) -> bool:
    """Formula 8.2, L+ S+ R+."""
    xi, eta = x + sp, y - 1.0 - cp
    rho2 = xi * xi + eta * eta
    if rho2 < 4.0:
        return False
    u = math.sqrt(rho2 - 4.0)
    t = wrap_angle(math.atan2(eta, xi) + math.atan2(2.0, u))
    v = wrap_angle(t - phi)
    out[0], out[1], out[2] = t, u, v
    return t >= -_ZERO and v >= -_ZERO


@njit(cache=True, error_model="numpy")
def _lrl(x: float, y: float, phi: float, sp: float, cp: float, out: np.ndarray) -> bool:
    """Formulas 8.3/8.4, L+ R− L (the last turn's gear is free: C|C|C and C|CC)."""
    xi, eta = x - sp, y - 1.0 + cp
    rho = math.hypot(xi, eta)
    if rho > 4.0:
        return False
    u = -2.0 * math.asin(0.25 * rho)
    t = wrap_angle(math.atan2(eta, xi) + 0.5 * u + math.pi)
    v = wrap_angle(phi - t + u)
    out[0], out[1], out[2] = t, u, v
    return t >= -_ZERO and u <= _ZERO


@njit(cache=True, error_model="numpy")
def _lrlr_forward(x: float, y: float, phi: float, sp: float, cp: float, out: np.ndarray) -> bool:
    """Formula 8.7, L+ R+u L−u R−."""
    xi, eta = x + sp, y - 1.0 - cp
    rho = 0.25 * (2.0 + math.hypot(xi, eta))
    if rho > 1.0:
        return False
    u = math.acos(rho)
    t, v = _tau_omega(u, -u, xi, eta, phi)
    out[0], out[1], out[2], out[3] = t, u, -u, v
    return t >= -_ZERO and v <= _ZERO


@njit(cache=True, error_model="numpy")
def _lrlr_reverse(x: float, y: float, phi: float, sp: float, cp: float, out: np.ndarray) -> bool:
    """Formula 8.8, L+ R−u L−u R+."""
    xi, eta = x + sp, y - 1.0 - cp
    rho = (20.0 - xi * xi - eta * eta) / 16.0
    if rho < 0.0 or rho > 1.0:
        return False
    u = -math.acos(rho)
    if u < -_HALF_PI:
        return False
    t, v = _tau_omega(u, u, xi, eta, phi)
    out[0], out[1], out[2], out[3] = t, u, u, v
    return t >= -_ZERO and v >= -_ZERO


@njit(cache=True, error_model="numpy")
def _lrsl(x: float, y: float, phi: float, sp: float, cp: float, out: np.ndarray) -> bool:
    """Formula 8.9, L+ R−π/2 S− L−."""
    xi, eta = x - sp, y - 1.0 + cp
    rho = math.hypot(xi, eta)
    if rho < 2.0:
        return False
    r = math.sqrt(rho * rho - 4.0)
    u = 2.0 - r
    t = wrap_angle(math.atan2(eta, xi) + math.atan2(r, -2.0))
    v = wrap_angle(phi - _HALF_PI - t)
    out[0], out[1], out[2], out[3] = t, -_HALF_PI, u, v
    return t >= -_ZERO and u <= _ZERO and v <= _ZERO


@njit(cache=True, error_model="numpy")
def _lrsr(x: float, y: float, phi: float, sp: float, cp: float, out: np.ndarray) -> bool:
    """Formula 8.10, L+ R−π/2 S− R−."""
    xi, eta = x + sp, y - 1.0 - cp
    rho = math.hypot(xi, eta)
    if rho < 2.0:
        return False
    t = math.atan2(xi, -eta)
    u = 2.0 - rho
    v = wrap_angle(t + _HALF_PI - phi)
    out[0], out[1], out[2], out[3] = t, -_HALF_PI, u, v
    return t >= -_ZERO and u <= _ZERO and v <= _ZERO


@njit(cache=True, error_model="numpy")
def _lrslr(x: float, y: float, phi: float, sp: float, cp: float, out: np.ndarray) -> bool:
    """Formula 8.11, L+ R−π/2 S− L−π/2 R+."""
    xi, eta = x + sp, y - 1.0 - cp
    rho = math.hypot(xi, eta)
    if rho < 2.0:
        return False
    u = 4.0 - math.sqrt(rho * rho - 4.0)
    if u > _ZERO:
        return False
    t = wrap_angle(math.atan2((4.0 - u) * xi - 2.0 * eta, -2.0 * xi + (u - 4.0) * eta))
    v = wrap_angle(t - phi)
    out[0], out[1], out[2], out[3], out[4] = t, -_HALF_PI, u, -_HALF_PI, v
    return t >= -_ZERO and v >= -_ZERO


@njit(cache=True, error_model="numpy")
def _base_word(k: int, x: float, y: float, phi: float, sp: float, cp: float, out: np.ndarray) -> bool:
    """Solve base word k (Reeds–Shepp formula 8.1–8.11, the rows of ``_BASE_LETTERS``) for the normalised goal
    (x, y, φ), with (sp, cp) = (sin φ, cos φ).

    Writes the signed normalised piece lengths into ``out`` (5,) and returns whether the word exists with the
    gear pattern of its name.
    """
    if k == 0:
        return _lsl(x, y, phi, sp, cp, out)
    if k == 1:
        return _lsr(x, y, phi, sp, cp, out)
    if k == 2:
        return _lrl(x, y, phi, sp, cp, out)
    if k == 3:
        return _lrlr_forward(x, y, phi, sp, cp, out)
    if k == 4:
        return _lrlr_reverse(x, y, phi, sp, cp, out)
    if k == 5:
        return _lrsl(x, y, phi, sp, cp, out)
    if k == 6:
        return _lrsr(x, y, phi, sp, cp, out)
    return _lrslr(x, y, phi, sp, cp, out)


@njit(cache=True, error_model="numpy")
def _goal_images(x: float, y: float, phi: float) -> np.ndarray:
    """What every symmetric image of the normalised goal (x, y, φ) needs, computed once: (x, y, the backwards image
    xb, yb, φ, sin φ, cos φ, sin −φ, cos −φ) (the trigonometry of −φ is evaluated, not derived, so each base
    formula sees exactly the values it would compute itself)."""
    cphi, sphi = math.cos(phi), math.sin(phi)
    return np.array([x, y, x * cphi + y * sphi, x * sphi - y * cphi, phi, sphi, cphi, math.sin(-phi),
                     math.cos(-phi)])


@njit(cache=True, error_model="numpy")
def _solve_symmetric(k: int, backwards: int, sym: int, goal: np.ndarray, buf: np.ndarray) -> bool:
    """Solve base word k for the normalised goal (`_goal_images`) under one symmetry (``backwards``; timeflip =
    ``sym & 1``, reflect = ``sym >> 1``): base lengths into ``buf``."""
    bx, by = (goal[2], goal[3]) if backwards else (goal[0], goal[1])
    timeflip, reflect = sym & 1, sym >> 1
    qx = -bx if timeflip else bx
    qy = -by if reflect else by
    if timeflip != reflect:
        return _base_word(k, qx, qy, -goal[4], goal[7], goal[8], buf)
    return _base_word(k, qx, qy, goal[4], goal[5], goal[6], buf)


@njit(cache=True, error_model="numpy")
def _write_word(k: int, backwards: int, sym: int, buf: np.ndarray, letters: np.ndarray, lengths: np.ndarray) -> int:
    """The word `_solve_symmetric` solved into ``buf``, as letters and signed lengths (5,); returns its piece count."""
    n = _N_PIECES[k]
    timeflip, reflect = sym & 1, sym >> 1
    for i in range(n):
        j = n - 1 - i if backwards else i
        letter = _BASE_LETTERS[k, j]
        letters[i] = -letter if reflect else letter
        lengths[i] = -buf[j] if timeflip else buf[j]
    return n


@njit(cache=True, error_model="numpy")
def all_words(x: float, y: float, phi: float, letters: np.ndarray, lengths: np.ndarray, counts: np.ndarray) -> int:
    """Every Reeds–Shepp word that reaches the normalised goal (x, y, φ) (formulas 8.1–8.11 under timeflip, reflect
    and backwards): letters (48, 5), signed normalised lengths (48, 5) and piece counts (48,) filled in generation
    order; returns the number of words."""
    buf = np.empty(MAX_PIECES)
    goal = _goal_images(x, y, phi)
    w = 0
    for k in range(N_BASES):
        for backwards in range(2 if _HAS_BACKWARDS[k] else 1):
            for sym in range(4):
                if _solve_symmetric(k, backwards, sym, goal, buf):
                    counts[w] = _write_word(k, backwards, sym, buf, letters[w], lengths[w])
                    w += 1
    return w


@njit(cache=True, error_model="numpy")
def _shortest(x: float, y: float, phi: float, buf: np.ndarray):
    """(base word, backwards, symmetry) of the shortest Reeds–Shepp word to the normalised goal (x, y, φ) over all
    48 words (the first of equal length in `all_words`' order), its base lengths left in ``buf``; base −1 when
    none exists."""
    best = np.inf
    best_k, best_backwards, best_sym = -1, 0, 0
    goal = _goal_images(x, y, phi)
    for k in range(N_BASES):
        for backwards in range(2 if _HAS_BACKWARDS[k] else 1):
            for sym in range(4):
                if not _solve_symmetric(k, backwards, sym, goal, buf):
                    continue
                total = 0.0
                for i in range(_N_PIECES[k]):
                    total += abs(buf[i])
                if total < best:
                    best = total
                    best_k, best_backwards, best_sym = k, backwards, sym
    if best_k >= 0:
        _solve_symmetric(best_k, best_backwards, best_sym, goal, buf)
    return best_k, best_backwards, best_sym


@njit(cache=True, error_model="numpy")
def shortest_word(x: float, y: float, phi: float, letters: np.ndarray, lengths: np.ndarray) -> int:
    """Shortest Reeds–Shepp word to the normalised goal (x, y, φ) over all 48 words (the first of equal length in
    `all_words`' order).

    Fills ``letters`` (5,) int64 and ``lengths`` (5,) float (signed, normalised) and returns the piece count.
    """
    buf = np.empty(MAX_PIECES)
    k, backwards, sym = _shortest(x, y, phi, buf)
    return 0 if k < 0 else _write_word(k, backwards, sym, buf, letters, lengths)


@njit(cache=True, error_model="numpy")
def relative_goal(x0: float, y0: float, th0: float, x1: float, y1: float, th1: float, kappa_max: float):
    """Goal (x1, y1, θ1) in the start's frame, scaled by κ_max: the normalised (x, y, φ) of the formulas."""
    dx, dy = x1 - x0, y1 - y0
    c, s = math.cos(th0), math.sin(th0)
    return (c * dx + s * dy) * kappa_max, (-s * dx + c * dy) * kappa_max, wrap_angle(th1 - th0)


@njit(cache=True, error_model="numpy")
def rs_length(x0: float, y0: float, th0: float, x1: float, y1: float, th1: float, kappa_max: float) -> float:
    """Length (m) of the shortest Reeds–Shepp path between two poses at curvature bound κ_max (summed in the
    word's piece order, as its arcs are)."""
    x, y, phi = relative_goal(x0, y0, th0, x1, y1, th1, kappa_max)
    buf = np.empty(MAX_PIECES)
    k, backwards, _ = _shortest(x, y, phi, buf)
    n = 0 if k < 0 else _N_PIECES[k]
    total = 0.0
    for i in range(n):
        total += abs(buf[n - 1 - i] if backwards else buf[i])
    return total / kappa_max


@njit(cache=True, error_model="numpy")
def rs_arcs_into(x0: float, y0: float, th0: float, x1: float, y1: float, th1: float, kappa_max: float,
                 min_length: float, out: np.ndarray) -> int:
    """Shortest Reeds–Shepp path as eq:arc arcs (κ, l) written into ``out`` (5, 2); returns the arc count.

    A piece of letter c and normalised length t becomes l = t/κ_max, κ = −sgn(l)·c·κ_max; pieces shorter than
    ``min_length`` (m) are dropped (they only arise from rounding at word boundaries).
    """
    x, y, phi = relative_goal(x0, y0, th0, x1, y1, th1, kappa_max)
    letters = np.empty(MAX_PIECES, np.int64)
    lengths = np.empty(MAX_PIECES)
    n = shortest_word(x, y, phi, letters, lengths)
    m = 0
    for i in range(n):
        length = lengths[i] / kappa_max
        if abs(length) < min_length:
            continue
        gear = 1.0 if length > 0.0 else -1.0
        out[m, 0] = -gear * letters[i] * kappa_max
        out[m, 1] = length
        m += 1
    return m
