"""Numerical detection of how the free parameters enter a term's features (App. C.3.4).

Analytic minimization needs every feature to depend on at most one free parameter, and to be affine in it
between breakpoints (kinks from |.|, jumps from angle wrapping or sign flips). We find this from the feature
map alone: a dense sweep of each free parameter, refined around every place where the slope changes until
the breakpoint is located to LOCATE_TOL, then a residual check inside every piece. Anything else (a feature
mixing two free parameters, a curved map such as a distance over a free position) is reported as
NotApplicable, and the caller falls back to the genetic algorithm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SWEEP_POINTS = 513  # samples per free parameter in the first sweep
REFINE_POINTS = 129  # samples across each region refined around a breakpoint
MAX_LEVELS = 8  # refinement levels; each shrinks a region by REFINE_POINTS - 1
LOCATE_TOL = 1e-11  # breakpoints are located to this fraction of max(1, range width)
SLOPE_RTOL = 1e-7  # relative tolerance for two slopes being equal
AFFINE_RTOL = 1e-7  # relative residual allowed inside a piece
MAX_BREAKPOINTS = 64  # per free parameter and term; more means "not piecewise affine"
CHECK_POINTS = 4  # random points for the dependency (perturbation) check
PIECE_FRACTIONS = np.array([0.2, 0.5, 0.8])  # where each piece is probed: two to fit, one to check
_EPS = np.finfo(float).eps


class NotApplicable(Exception):
    """The features are not piecewise affine in single free parameters; the message says why."""


@dataclass(frozen=True, eq=False)
class TermStructure:
    """feature_i(theta) = const_i + sum_j slope[j][i, p_j] * theta_j + offset[j][i, p_j] on piece p_j of j."""

    var_of: np.ndarray  # (n_features,) index of the free parameter a feature depends on, -1 if none
    const: np.ndarray  # (n_features,) value of the features that depend on no free parameter, else 0
    edges: tuple[np.ndarray, ...]  # per free parameter: piece edges low = e_0 < ... < e_P = high
    slope: tuple[np.ndarray, ...]  # per free parameter: (n_features, P); zero rows for other features
    offset: tuple[np.ndarray, ...]  # per free parameter: (n_features, P)


def _features(term, theta: np.ndarray) -> np.ndarray:
    values = np.asarray(term.features(theta), dtype=float)
    if values.ndim != 2 or len(values) != len(theta):
        raise NotApplicable(
            f"features of term {term.label!r} gave shape {values.shape} for {len(theta)} rows"
        )
    return values


def detect(term, low: np.ndarray, high: np.ndarray, names: tuple[str, ...]) -> TermStructure:
    """Breakpoints and affine pieces of every feature of `term` in the free parameters (or NotApplicable)."""
    n_free = len(low)
    base = (low + high) / 2
    rng = np.random.default_rng(0)  # fixed: the check points are part of the method, not a random choice
    points = rng.uniform(low, high, size=(CHECK_POINTS, n_free))
    moved = np.repeat(points[:, None, :], n_free, axis=1)  # (K, n_free, n_free): row j has theta_j redrawn
    redraw = rng.uniform(low, high, size=(CHECK_POINTS, n_free))
    moved[:, np.arange(n_free), np.arange(n_free)] = redraw
    sweeps = [np.linspace(low[j], high[j], SWEEP_POINTS) for j in range(n_free)]
    rows = [points, moved.reshape(-1, n_free)]
    for j, t in enumerate(sweeps):
        block = np.repeat(base[None, :], SWEEP_POINTS, axis=0)
        block[:, j] = t
        rows.append(block)
    values = _features(term, np.concatenate(rows))
    n_features = values.shape[1]
    at_points = values[:CHECK_POINTS]
    at_moved = values[CHECK_POINTS : CHECK_POINTS * (1 + n_free)].reshape(CHECK_POINTS, n_free, n_features)
    swept = values[CHECK_POINTS * (1 + n_free) :].reshape(n_free, SWEEP_POINTS, n_features)
    if not np.all(np.isfinite(values)):
        raise NotApplicable(f"features of term {term.label!r} are not finite everywhere")

    scale = 1.0 + np.abs(values).max(axis=0)
    tol = 1e3 * _EPS * scale
    depends = (np.ptp(swept, axis=1) > tol) | (np.abs(at_moved - at_points[:, None, :]) > tol).any(axis=0)
    var_of = np.full(n_features, -1)
    for i in range(n_features):
        on = np.flatnonzero(depends[:, i])
        if len(on) > 1:
            raise NotApplicable(
                f"feature {i} of term {term.label!r} depends on both {names[on[0]]} and {names[on[1]]}"
            )
        if len(on) == 1:
            var_of[i] = on[0]
    const = np.where(var_of < 0, at_points[0], 0.0)

    widths = np.maximum(1.0, high - low)
    found = _breakpoints(term, var_of, low, high, base, swept, names)
    edges = []
    for j in range(n_free):
        e = np.concatenate([[low[j]], np.sort(found[j]), [high[j]]])
        e = e[np.concatenate([[True], np.diff(e) > 10 * LOCATE_TOL * widths[j]])]
        e[-1] = high[j]
        if len(e) - 2 > MAX_BREAKPOINTS:
            raise NotApplicable(
                f"term {term.label!r} has {len(e) - 2} breakpoints in {names[j]} (budget {MAX_BREAKPOINTS})"
            )
        edges.append(e)
    slopes, offsets = _fit_pieces(term, var_of, edges, base, names)
    return TermStructure(var_of, const, tuple(edges), slopes, offsets)


def _breakpoints(term, var_of, low, high, base, swept, names) -> list[np.ndarray]:
    """Per free parameter: where some feature depending on it changes slope or jumps.

    Every (feature, free parameter) pair starts as one region sampled by the sweep; each level resamples
    the runs of intervals that hold a breakpoint, all regions of the term in one call of its features.
    """
    feature = np.flatnonzero(var_of >= 0)
    var = var_of[feature]
    found: list[list[np.ndarray]] = [[] for _ in low]
    if len(feature) == 0:
        return [np.empty(0) for _ in low]
    grid = np.linspace(low[var], high[var], SWEEP_POINTS, axis=1)
    vals = swept[var, :, feature]  # (regions, SWEEP_POINTS)
    tol = LOCATE_TOL * np.maximum(1.0, high - low)
    for level in range(MAX_LEVELS + 1):
        kinks, kink_rows, (region, a, b), clean_any, n_gap = _scan(grid, vals)
        if level == 0:
            curved = n_gap > SWEEP_POINTS // 8
        else:
            curved = ~clean_any
        if curved.any():
            r = np.flatnonzero(curved)[0]
            raise NotApplicable(
                f"feature {feature[r]} of term {term.label!r} is not piecewise affine in "
                f"{names[var[r]]} (curved)"
            )
        points = [(var[kink_rows], kinks)]
        if level > 0:  # a region with no gap left at this resolution hides a kink below the noise
            quiet = np.setdiff1d(np.arange(len(grid)), np.concatenate([region, kink_rows]))
            points.append((var[quiet], (grid[quiet, 0] + grid[quiet, -1]) / 2))
        small = (b - a) < tol[var[region]]
        points.append((var[region[small]], (a[small] + b[small]) / 2))
        for v, t in points:
            for j in np.unique(v):
                found[j].append(t[v == j])
        region, a, b = region[~small], a[~small], b[~small]
        if len(region) == 0:
            break
        if len(region) > MAX_BREAKPOINTS * len(feature):
            raise NotApplicable(f"term {term.label!r} has too many breakpoints")
        if level == MAX_LEVELS:
            name = names[var[region[0]]]
            raise NotApplicable(f"a breakpoint of term {term.label!r} in {name} could not be located")
        feature, var = feature[region], var[region]
        grid = np.linspace(a, b, REFINE_POINTS, axis=1)
        theta = np.repeat(base[None, :], grid.size, axis=0)
        theta[np.arange(grid.size), np.repeat(var, REFINE_POINTS)] = grid.ravel()
        vals = _features(term, theta)[np.arange(grid.size), np.repeat(feature, REFINE_POINTS)]
        vals = vals.reshape(grid.shape)
    return [np.unique(np.concatenate(f)) if f else np.empty(0) for f in found]
def _scan(grid: np.ndarray, vals: np.ndarray):
    """Per row: breakpoints at sample points, the runs of intervals with a breakpoint inside, gap counts."""
    h = np.diff(grid, axis=1)
    d = np.diff(vals, axis=1) / h
    noise = 64 * _EPS * (1.0 + np.abs(vals).max(axis=1, keepdims=True)) / h
    allowed = SLOPE_RTOL * (1 + np.abs(d[:, 1:]) + np.abs(d[:, :-1])) + noise[:, 1:] + noise[:, :-1]
    same = np.abs(np.diff(d, axis=1)) <= allowed
    pad = np.zeros((len(grid), 1), dtype=bool)
    # an interval is clean when it shares its slope with a neighbour (a run of at least two)
    clean = np.concatenate([pad, same], axis=1) | np.concatenate([same, pad], axis=1)
    # slope changes exactly at a sample point between two clean intervals
    rows, k = np.nonzero(clean[:, :-1] & clean[:, 1:] & ~same)
    kinks = grid[rows, k + 1]
    gap = ~clean
    starts = np.nonzero(gap & ~np.concatenate([pad, gap[:, :-1]], axis=1))
    ends = np.nonzero(gap & ~np.concatenate([gap[:, 1:], pad], axis=1))
    region = starts[0]
    a = grid[starts[0], starts[1]]
    b = grid[ends[0], ends[1] + 1]
    return kinks, rows, (region, a, b), clean.any(axis=1), gap.sum(axis=1)


def _fit_pieces(term, var_of, edges, base, names):
    """Slope and offset of each feature on each piece of its free parameter, checked at a third point."""
    n_features = len(var_of)
    slopes = tuple(np.zeros((n_features, len(e) - 1)) for e in edges)
    offsets = tuple(np.zeros((n_features, len(e) - 1)) for e in edges)
    used = [j for j in range(len(edges)) if np.any(var_of == j)]
    if not used:
        return slopes, offsets
    t = [e[:-1, None] + PIECE_FRACTIONS[None, :] * np.diff(e)[:, None] for e in edges]  # (P_j, 3)
    blocks = []
    for j in used:
        block = np.repeat(base[None, :], t[j].size, axis=0)
        block[:, j] = t[j].ravel()
        blocks.append(block)
    values = _features(term, np.concatenate(blocks))
    start = 0
    for j in used:
        dependent = np.flatnonzero(var_of == j)
        n_pieces = len(t[j])
        f = values[start : start + t[j].size, dependent].reshape(n_pieces, 3, len(dependent))
        start += t[j].size
        tj = t[j]
        s = (f[:, 2] - f[:, 0]) / (tj[:, 2] - tj[:, 0])[:, None]  # (P, nd)
        c = f[:, 0] - s * tj[:, :1]
        residual = np.abs(f[:, 1] - (s * tj[:, 1:2] + c))
        allowed = AFFINE_RTOL * (1 + np.abs(f).max(axis=1)) + 1e3 * _EPS * (1 + np.abs(s) * np.abs(tj).max())
        if np.any(residual > allowed):
            p, q = np.argwhere(residual > allowed)[0]
            raise NotApplicable(
                f"feature {dependent[q]} of term {term.label!r} is not affine in {names[j]} on "
                f"[{edges[j][p]:.6g}, {edges[j][p + 1]:.6g}]"
            )
        slopes[j][dependent] = s.T
        offsets[j][dependent] = c.T
    return slopes, offsets
