"""Fitting one model to one target's values at the metric's direction pairs.

The problem (:func:`problem`): the target's ``eval`` at the pairs, the
metric's weights (the reported ``brdf_error``, :mod:`.metric`) and the
objective's (what the fit minimises: the compressed values,
:func:`.metric.compress`), relative to a black BSDF's.

The fit (:func:`fit_model`) works on each free parameter's unconstrained
coordinate u (:mod:`.models`: the parameter is a logistic of u, so its
gradient never vanishes at a bound), in three stages:

1. **Scan.** ``scan`` candidate settings of the non-colour parameters (the
   plugin's defaults, every one at its low end, every one at its high end —
   so that a model that contains another as a limit starts once from it —
   then a Latin hypercube across the ranges, log-scaled for roughnesses and
   exponents). ``eval`` is linear in the colours for every course model (all
   but ``oren_nayar+ec``, whose multiple scattering is not: there it is a
   start), so each candidate's colours are solved exactly by bounded linear
   least squares on the pairs' values (one ``eval`` per colour parameter),
   and the candidate is scored by the objective. A rung's colours that eval
   is not linear in (``eta``, ``kappa``, ``f82_tint``: :mod:`.models`) are
   scanned with the shapes, as greys.
2. **Descent.** The ``starts`` best candidates are refined by
   Levenberg-Marquardt (:func:`levenberg_marquardt`) on the residuals of the
   objective, their Jacobian in u by Dr.Jit's forward-mode AD, every
   coordinate within ±``U_MAX``; at most ``steps`` residual evaluations. It
   accepts only steps that lower the objective, so a start never ends worse
   than it began. The start with the lowest objective wins.
3. **Off and onto the bounds**, the winner only (:func:`refine`). Where
   its descent ended with a coordinate beyond ±``U_START`` it starts again
   from there with those coordinates pulled in: a coordinate driven to a
   bound has lost its gradient. A coordinate left next to its bound goes
   onto it where the objective cannot tell (:func:`to_bounds`).

Every ``eval`` reads the parameters from opaque Dr.Jit variables: one kernel
for all the values tried.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

import drjit as dr
import mitsuba as mi

from ..._jit import from_numpy
from ...bsdfs import BY_NAME
from . import metric as metric_module, models as M

RESTARTS = 3                # refine(): descents again from the end point, at most
RESTART_GAIN = 0.01         # refine(): a restart is kept if it lowers the objective by 1 % or more
SNAP = 1e-4                 # to_bounds(): a coordinate goes onto its bound if the objective rises this little (relative)
RESIDUAL_CAP = 1e3           # a non-finite residual counts as this
TOLERANCE = 1e-10            # a relative decrease of the objective, or a step in u, this small stops


@dataclass
class Problem:
    """The pairs as Dr.Jit arrays and the target's values there."""
    si: object
    wo: object
    objective: str
    weight: object           # mi.Float: the metric's weights (brdf_error)
    target: object           # mi.Color3f: eval of the target
    norm: float              # Σ w ‖target‖²: E²(0)
    shown: object            # mi.Float: the objective's weights
    target_c: object         # mi.Color3f: the target's compressed values
    norm_c: float            # Σ shown ‖c(target)‖²: E_c²(0)
    arrays: dict = field(default_factory=dict)     # NumPy copies


def problem(target_bsdf, pairs, objective: str = "cbrt") -> Problem:
    """The target's values at ``pairs`` (non-finite values: the pair left out)."""
    si, wo = surface_at(pairs.wi), from_numpy(mi.Vector3f, pairs.wo.T)
    return problem_from_values(values_of(target_bsdf, si, wo), pairs, objective, si, wo)


def problem_from_values(values: np.ndarray, pairs, objective: str = "cbrt", si=None,
                        wo=None) -> Problem:
    """:func:`problem` from the target's values at ``pairs`` (N, 3), taken
    once per target and handed to every fit (:mod:`.work`)."""
    if si is None:
        si, wo = surface_at(pairs.wi), from_numpy(mi.Vector3f, pairs.wo.T)
    finite = np.isfinite(values).all(axis=1)
    values = np.where(finite[:, None], values, 0.0)
    weight = np.where(finite, pairs.weight, 0.0)
    shown = np.where(finite, pairs.shown, 0.0)
    compressed = metric_module.compress(values, objective)
    norm = float(np.sum(weight * np.sum(values ** 2, axis=1)))
    norm_c = float(np.sum(shown * np.sum(compressed ** 2, axis=1)))
    return Problem(si, wo, objective, from_numpy(mi.Float, weight),
                   from_numpy(mi.Color3f, values.T), norm, from_numpy(mi.Float, shown),
                   from_numpy(mi.Color3f, compressed.T), norm_c,
                   {"weight": weight, "target": values, "shown": shown, "target_c": compressed})


def surface_at(wi: np.ndarray):
    """A surface interaction per viewer direction (N, 3), local frame, uv at
    the centre (where a texture of the target is read)."""
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = from_numpy(mi.Vector3f, wi.T)
    si.uv = mi.Point2f(0.5, 0.5)
    return si


def eval_pairs(bsdf, wi: np.ndarray, wo: np.ndarray) -> np.ndarray:
    """eval at the direction pairs (wi, wo), both (N, 3), as (N, 3) float64."""
    return values_of(bsdf, surface_at(wi), from_numpy(mi.Vector3f, wo.T))


def values_of(bsdf, si, wo) -> np.ndarray:
    """eval at the pairs as (N, 3) float64."""
    value = np.array(bsdf.eval(mi.BSDFContext(), si, wo), dtype=np.float64)
    return value.T if value.ndim == 2 else np.repeat(value[:, None], 3, axis=1)


def relative(values: np.ndarray, prob: Problem) -> float:
    """brdf_error: E(f)/E(0) of eval values (N, 3) in the metric."""
    w, t = prob.arrays["weight"], prob.arrays["target"]
    values = np.where(np.isfinite(values), values, np.inf)
    num = float(np.sum(w * np.sum((values - t) ** 2, axis=1)))
    return math.sqrt(num / prob.norm) if prob.norm > 0 else math.nan


def relative_objective(values: np.ndarray, prob: Problem) -> float:
    """The objective E_c(f)/E_c(0) of eval values (N, 3)."""
    w, t = prob.arrays["shown"], prob.arrays["target_c"]
    c = metric_module.compress(np.where(np.isfinite(values), values, np.inf), prob.objective)
    num = float(np.sum(w * np.sum((c - t) ** 2, axis=1)))
    return math.sqrt(num / prob.norm_c) if prob.norm_c > 0 else math.nan


# ----------------------------------------------------------------------------
#  The fit
# ----------------------------------------------------------------------------

class Evaluator:
    """One instance of the model, its parameters set from coordinates u."""

    def __init__(self, model, prob: Problem):
        self.model, self.prob = model, prob
        self.cls = BY_NAME[model.plugin]
        probe = mi.load_dict(model.properties())
        self.free = M.free_parameters(self.cls, list(mi.traverse(probe).keys()), model)
        del probe
        # Colours given as RGB, so that traverse exposes them as colours.
        grey = {f.name: [0.5, 0.5, 0.5] for f in self.free if f.colour}
        self.bsdf = mi.load_dict(M.load_dict({**model.properties(), **grey}))
        self.params = mi.traverse(self.bsdf)
        self.size = sum(3 if f.colour else 1 for f in self.free)
        # base="plastic": the interface's tables are computed in NumPy when a
        # parameter changes, so AD misses their part of the derivatives
        self.numeric = dict(model.options).get("base") == "plastic"

    def set(self, values: dict) -> None:
        """Set parameter values ({name: float or 3 floats}) as opaque variables."""
        for f in self.free:
            v = values[f.name]
            self.params[f.key] = (mi.Color3f(*(dr.opaque(mi.Float, float(c)) for c in v))
                                  if f.colour else dr.opaque(mi.Float, float(v)))
        self.params.update()

    def values(self, u: np.ndarray) -> np.ndarray:
        """eval (N, 3) at the pairs for coordinates u."""
        self.set(M.values(self.free, u))
        return values_of(self.bsdf, self.prob.si, self.prob.wo)

    def _scale(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-pair residual scale and target: residual = scale·(c(eval) - target)."""
        p = self.prob
        if p.objective == "linear":
            return np.sqrt(p.arrays["weight"] / p.norm), p.arrays["target"]
        return np.sqrt(p.arrays["shown"] / p.norm_c), p.arrays["target_c"]

    def residuals(self, u: np.ndarray) -> np.ndarray:
        """The objective's residuals: their squared sum is E_c²/E_c²(0)."""
        scale, target = self._scale()
        r = scale[:, None] * (metric_module.compress(self.values(u), self.prob.objective) - target)
        return np.where(np.isfinite(r), r, RESIDUAL_CAP).ravel()

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """d residuals / d u by Dr.Jit's forward-mode AD: one traced eval, then
        one forward pass per coordinate through the recorded graph (by forward
        differences where the model is not differentiable throughout:
        :attr:`numeric`)."""
        if self.numeric:
            return self.differences(u)
        coords = [dr.opaque(mi.Float, float(x)) for x in u]
        for c in coords:
            dr.enable_grad(c)
        i = 0
        for f in self.free:
            if f.colour:
                self.params[f.key] = mi.Color3f(*(f.value(coords[i + k]) for k in range(3)))
            else:
                self.params[f.key] = f.value(coords[i])
            i += 3 if f.colour else 1
        self.params.update()
        value = self.bsdf.eval(mi.BSDFContext(), self.prob.si, self.prob.wo)
        c = metric_module.compress(value, self.prob.objective)
        scale, _ = self._scale()
        columns = []
        for x in coords:                      # the graph is kept; its interior cleared per pass
            dr.set_grad(x, 1.0)
            dr.forward_to(c, flags=dr.ADFlag.ClearInterior | dr.ADFlag.ClearInput)
            g = np.array(dr.grad(c), dtype=np.float64)
            g = g.T if g.ndim == 2 else np.repeat(g[:, None], 3, axis=1)
            dr.clear_grad(c)
            columns.append((scale[:, None] * g).ravel())
        del value, c, coords
        j = np.stack(columns, axis=1)
        return np.where(np.isfinite(j), j, 0.0)

    def differences(self, u: np.ndarray, step: float = 1e-3) -> np.ndarray:
        """d residuals / d u by forward differences of ``step`` in u."""
        r = self.residuals(u)
        columns = []
        for i in range(len(u)):
            moved = np.array(u, dtype=np.float64)
            moved[i] += step if moved[i] + step <= M.U_MAX else -step
            columns.append((self.residuals(moved) - r) / (moved[i] - u[i]))
        j = np.stack(columns, axis=1)
        return np.where(np.isfinite(j), j, 0.0)

    def colours_by_least_squares(self, shape: dict) -> dict:
        """The colours that fit best (bounded linear least squares, per channel,
        on the eval values weighted as shown) with the other parameters at
        ``shape`` (the colours eval is linear in; the others are in ``shape``)."""
        colours = [f for f in self.free if f.colour and f.linear]
        if not colours:
            return dict(shape)
        basis = []
        for c in colours:
            values = {**shape, **{f.name: [1.0 if f is c else 0.0] * 3 for f in colours}}
            self.set(values)
            basis.append(values_of(self.bsdf, self.prob.si, self.prob.wo))
        w = self.prob.arrays["shown"]
        out = dict(shape)
        solved = np.zeros((len(colours), 3))
        bounds = ([f.lo for f in colours], [f.hi for f in colours])
        for ch in range(3):
            a = np.nan_to_num(np.stack([b[:, ch] for b in basis], axis=1), posinf=0.0, neginf=0.0)
            solved[:, ch] = bounded_least_squares(a, self.prob.arrays["target"][:, ch], w, bounds)
        for i, c in enumerate(colours):
            out[c.name] = [float(v) for v in solved[i]]
        return out

    def coordinates(self, values: dict, edge: float) -> np.ndarray:
        out = []
        for f in self.free:
            v = values[f.name]
            out += [f.coordinate(c, edge) for c in v] if f.colour else [f.coordinate(v, edge)]
        return np.array(out)


def candidates(ev: Evaluator, count: int) -> list[dict]:
    """Values of the scanned parameters (module docstring, stage 1): the
    shapes, and the colours eval is not linear in (a rung's ``eta``, as a grey)."""
    shape = [f for f in ev.free if f.scanned]
    grey = lambda f, v: [float(v)] * 3 if f.colour else float(v)
    defaults = {p.name: p.default for p in ev.cls.PARAMS}
    out = [{f.name: grey(f, min(max(defaults[f.name], f.lo), f.hi)) for f in shape}]
    edge = lambda f, end: f.value(-M.U_START if end == "lo" else M.U_START)
    if shape:
        out += [{f.name: grey(f, edge(f, end)) for f in shape} for end in ("lo", "hi")]
    n = count - len(out)
    if n > 0 and shape:
        rng = np.random.default_rng(len(shape))
        grid = np.stack([(rng.permutation(n) + rng.random(n)) / n for _ in shape], axis=1)
        out += [{f.name: grey(f, f.spread(s)) for f, s in zip(shape, row)} for row in grid]
    return out


def bounded_least_squares(a: np.ndarray, b: np.ndarray, w: np.ndarray, bounds) -> np.ndarray:
    """argmin Σ w (a x - b)² with lo <= x <= hi, exactly. The objective is a
    convex quadratic ½xᵀHx - gᵀx + const (H = aᵀWa, g = aᵀWb; a small ridge
    where a column is 0), and a model has a few colours (n <= 4: toon's), so the
    minimum is found by trying every active set: each unknown free (its
    gradient component 0) or on one of its bounds, 3ⁿ small solves; the
    minimum is the lowest of those within the bounds. (scipy's iterative
    lsq_linear took half the scan's time.)"""
    h = np.einsum("ni,n,nj->ij", a, w, a)       # einsum, not BLAS: see gram()
    g = np.einsum("ni,n->i", a, w * b)
    h = h + np.eye(len(h)) * (1e-12 * max(float(np.trace(h)), 1e-300))
    lo, hi = (np.asarray(x, dtype=np.float64) for x in bounds)
    best, best_q = None, math.inf     # every unknown on a bound is always within them
    for state in itertools.product((0, 1, 2), repeat=len(g)):     # free, at lo, at hi
        state = np.array(state)
        x = np.where(state == 1, lo, hi)
        free = state == 0
        if free.any():
            rhs = g[free] - h[np.ix_(free, ~free)] @ x[~free]
            x[free] = np.linalg.solve(h[np.ix_(free, free)], rhs)
            if np.any(x < lo) or np.any(x > hi):
                continue
        q = 0.5 * x @ h @ x - g @ x
        if q < best_q:
            best, best_q = x, q
    return best


def gram(j: np.ndarray) -> np.ndarray:
    """jᵀj by einsum, on one core: OpenBLAS's threads for a tall product spin
    on cores shared with Dr.Jit's and other processes' (on a loaded 2-core
    machine a fit then takes 13 s instead of 2 s)."""
    return np.einsum("mi,mj->ij", j, j)


def levenberg_marquardt(ev: Evaluator, u0: np.ndarray, evaluations: int):
    """Minimise ‖r(u)‖² from u0 with every u within ±U_MAX: Gauss-Newton steps
    (JᵀJ + λ diag(JᵀJ)) δ = -Jᵀr, λ lowered after a step that lowers the
    objective and raised (the step retried) after one that does not
    (Levenberg 1944, Marquardt 1963). Returns (u, residual evaluations)."""
    u = np.array(u0, dtype=np.float64)
    r = ev.residuals(u)
    cost, used, lam = float(np.sum(r * r)), 1, 1e-3
    while used < evaluations and cost > 0:
        j = ev.jacobian(u)
        h, g = gram(j), np.einsum("mi,m->i", j, r)
        improved = False
        while used < evaluations:
            step = np.linalg.solve(h + lam * (np.diag(np.diag(h)) + 1e-12 * np.eye(len(h))), -g)
            trial = np.clip(u + step, -M.U_MAX, M.U_MAX)
            r_trial = ev.residuals(trial)
            used += 1
            c_trial = float(np.sum(r_trial * r_trial))
            if c_trial < cost:
                done = cost - c_trial <= TOLERANCE * cost or np.max(np.abs(trial - u)) < TOLERANCE
                u, r, cost, lam, improved = trial, r_trial, c_trial, max(lam / 3.0, 1e-9), True
                break
            lam *= 4.0
            if lam > 1e9:
                break
        if not improved or done:
            break
    return u, used


def refine(ev: Evaluator, u: np.ndarray, evaluations: int):
    """:func:`levenberg_marquardt` again from where a descent ended (u) with
    every coordinate pulled within ±``U_START``, kept where that lowers the
    objective by ``RESTART_GAIN`` or more (at most ``RESTARTS`` times); then
    :func:`to_bounds`. A coordinate the descent drove to a bound has lost its
    gradient (σ'(u) ≈ e^-|u|; in float32 σ(u) is 1 from u = 17), so it stays
    there even where the optimum leaves the bound once another parameter
    moves. Measured: compensated Beckmann fitted to Cu α 0.3 ended with m_S's
    green at 1 and F0 0.75 from all three starts (relative objective 0.066,
    the uncompensated fit 0.0089); pulled in, the descent goes on to m_S's
    green 0.66 and F0 0.92 (0.014). Only the best start's end is refined: a
    start that stopped at a bound most often went back to it (k or a diffuse
    channel at 0), and refining all three took a third of the optimiser's
    time (gold α 0.1's 24 models: 91 restarts, 163 descents). Returns (u, residual
    evaluations)."""
    cost, used = float(np.sum(ev.residuals(u) ** 2)), 1
    for _ in range(RESTARTS):
        pulled = np.clip(u, -M.U_START, M.U_START)
        if np.array_equal(pulled, u) or not math.isfinite(cost):
            break
        trial, more = levenberg_marquardt(ev, pulled, evaluations)
        c_trial = float(np.sum(ev.residuals(trial) ** 2))
        used += more + 1
        if not c_trial <= (1.0 - RESTART_GAIN) * cost:
            break
        u, cost = trial, c_trial
    u, more = to_bounds(ev, u, cost)
    return u, used + more


def to_bounds(ev: Evaluator, u: np.ndarray, cost: float):
    """Each coordinate beyond ±``U_START`` (within 0.25 % of the range of a
    bound) moved onto its bound (±``U_MAX``) where the objective cannot tell
    (it rises by ``SNAP`` relative or less), one at a time. A lobe left at a
    weight of 10⁻⁶ is next to nothing to the objective but not to HDR-FLIP,
    which exposes for the darkest pixels of a view. Measured with the
    restarts alone: Beckmann × Smith fitted to Cu α 0.3 ended with k 4·10⁻⁶
    under a white m_D's red (objective 3·10⁻⁵ lower than with k on its bound)
    and rendered at FLIP 0.185 against 0.028; to Al α 0.1, with m_D 3·10⁻⁶
    at k 0.04: FLIP 0.45 against 0.012. Returns (u, residual evaluations)."""
    used = 0
    for i in np.flatnonzero(np.abs(u) > M.U_START):
        if abs(u[i]) == M.U_MAX:
            continue
        trial = u.copy()
        trial[i] = math.copysign(M.U_MAX, u[i])
        c_trial = float(np.sum(ev.residuals(trial) ** 2))
        used += 1
        if c_trial <= cost * (1.0 + SNAP):
            u, cost = trial, min(cost, c_trial)
    return u, used


def scan(ev: Evaluator, count: int) -> list[tuple[float, np.ndarray]]:
    """Stage 1 (module docstring): ``count`` candidates, their colours solved,
    as (objective², u), the best first."""
    scanned = []
    for shape in candidates(ev, count):
        u = ev.coordinates(ev.colours_by_least_squares(shape), M.U_START)
        scanned.append((float(np.sum(ev.residuals(u) ** 2)), u))
    scanned.sort(key=lambda s: s[0] if math.isfinite(s[0]) else math.inf)
    if ev.model.metals and scanned:       # the measured metals at the best scan's roughness
        alpha = M.values(ev.free, scanned[0][1]).get("alpha")
        for start in M.metal_starts(alpha):
            u = ev.coordinates(start, M.U_START)
            scanned.append((float(np.sum(ev.residuals(u) ** 2)), u))
        scanned.sort(key=lambda s: s[0] if math.isfinite(s[0]) else math.inf)
    return scanned


def fit_model(model, prob: Problem, settings, log=None) -> dict:
    """Fit ``model`` (a :class:`.models.Model`) to ``prob``; returns the fitted
    properties, the BRDF error, the objective, what each start's descent
    reached and what the winner's refinement did."""
    ev = Evaluator(model, prob)
    scanned = scan(ev, settings.scan)

    def measured(u, evaluations):
        values = ev.values(u)
        return {"u": u, "objective": relative_objective(values, prob),
                "error": relative(values, prob), "evaluations": evaluations}

    results = []
    for _, u0 in scanned[:settings.starts]:
        results.append(measured(*levenberg_marquardt(ev, u0, settings.steps)))
        if log:
            log(f"{model.name}: start {len(results)}: objective {results[-1]['objective']:.4g}")
    best = min(results, key=lambda r: r["objective"] if math.isfinite(r["objective"]) else math.inf)
    refined = measured(*refine(ev, best["u"], settings.steps))
    parameters = {**model.properties(), **M.values(ev.free, refined["u"])}
    del ev
    keys = ("error", "objective", "evaluations")
    return {"parameters": parameters, "brdf_error": refined["error"],
            "objective": refined["objective"],
            "scan": [math.sqrt(s[0]) for s in scanned],
            "starts": [{k: r[k] for k in keys} for r in results],
            "refined": {k: refined[k] for k in keys}}
