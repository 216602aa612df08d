"""Render cost: what a fitted model costs against its target, measured so that
the answer is a property of the model and the scene, not of one noisy run.

**Timed** (:func:`measure_costs`). The target's scene (the ``environment``
view of :mod:`.scene`) lives in a process of its own, and the models' in
another (spawned, never forked), which loads one model's scene after the
other, the previous one released first (one BSDF instance alive at a time:
Dr.Jit traces every live instance at every render; a process per model cost
~10 s to start under load, loading in place ~1 s). After an untimed render
of each scene (it compiles or loads the kernels), the two render in turn —
each round one timed render of each, the order alternating — and each round
gives the ratio model time / target time. The rounds go on until the 90 %
interval of the geometric mean of the ratios (Student's t on their
logarithms) is within ``cost_tolerance`` (high/low <= 1.10 by default), at
least and at most ``cost_rounds``. 1.10 because the time to the same noise
(:func:`.rank.time_to_noise`) multiplies this ratio by the variance ratio,
whose 90 % intervals read high/low 1.03–1.29 (median about 1.1; gold α 0.1
and the α 0.1 plastic, four models each): at load average 4, gold α 0.1's
models took 14–20 rounds to reach 1.05 (five models) and 3–12, median 6.5, to
reach 1.10 (its 28), for a figure the product could not use. ``cost_ratio`` is that mean,
``cost_low`` and ``cost_high`` the interval, ``cost_timing`` what was timed.
Only one measurement runs at a time, after every fit.

**At 32 spp** (``cost_spp``; the views render at 64, and reports made before
``cost_spp`` was recorded timed at their ``spp``): a round costs half as
much and is about as steady. Gold α 0.1's 28 fits, a default fit's report
timed again on the quiet machine (load average 1.1–2; ``python -m
mi_brdfs.tools.fit.cost REPORT --spp N``): at 32 spp 25 of the 28
intervals overlapped the report's (timed at 64) and 58 of 378 pairwise
comparisons by cost class came out otherwise, in 41 s; at 64 spp, 26 and 69,
in 74 s; at 16 spp, 25 and 75, in 31 s, its ratios drawn towards 1 by what
a render costs whatever its samples (a 1-spp render took 0.010–0.024 s of
CPU, a 64-spp one 0.30–0.41 s).

What a round times (``cost_timing``, :func:`timed_render`): the CPU time of
the rendering process (``cpu``, every thread's, the default), its wall-clock
time (``wall``), or the sum of Dr.Jit's kernel history ``execution_time``
(``kernels``). Measured on this 2-core machine at load average 20–23 (5
models against gold α 0.1, twice each, 12 rounds: ``python -m
mi_brdfs.tools.fit.cost docs/benchmarks/trade --timings --models lambert
phong ashikhmin_shirley cook_torrance/beckmann/smith
cook_torrance/ggx/smith+ec``, :func:`steadiness`): the standard deviation of the log ratios was 0.09–0.28 by wall
clock, 0.10–0.28 by kernel history (on the LLVM backend it is wall-clock
time around each kernel, so the load is in it), 0.021–0.046 by CPU time;
the two CPU-time intervals of a model overlapped for 4 of the 5. At load
average 4 (lambert, twice) the gap was smaller: 0.05–0.07 by CPU time,
0.07–0.11 by wall clock and by kernel history. CPU
time counts the work a render does and not the time it waits for a core.

**Again** (``python -m mi_brdfs.tools.fit.cost REPORT_DIR [--targets N]``):
the costs of a fit report's fits measured once more and printed beside the
report's, with whether the two intervals overlap, and how many pairwise
comparisons by cost class (:mod:`.rank`) came out otherwise — the spread of
the method on this machine. It writes nothing.

**Counted** (``ops_ratio``): the Dr.Jit variables one traced ``eval`` and
one traced ``sample`` create (the bench's count, from Dr.Jit's trace log:
:func:`mi_brdfs.tools.analysis.variables_created`), relative to the target's: the
same on every run.
"""
from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import statistics
import sys
import time

import drjit as dr
import mitsuba as mi

from ..analysis import bsdf_call, bsdf_inputs, variables_created
from ..errors import one_line
from . import models as M, rank, scene as S, targets as T
from .task import FULL

OPS_LANES = 1024           # lanes of the traced calls counted (the count does not depend on it)
REPLY_SECONDS = 600.0      # a worker that does not answer in this long is given up


class CostError(RuntimeError):
    """A cost worker that failed (its message on one line)."""


def _make(spec):
    """A BSDF from a :class:`.targets.Target` or fitted properties (a dict)."""
    if isinstance(spec, dict):
        return M.load_dict(spec)
    return spec.as_dict() if spec.xml is None else spec.load()


def operations(bsdf) -> int:
    """Dr.Jit variables one traced eval and one traced sample of ``bsdf`` create."""
    x = bsdf_inputs(OPS_LANES)
    for method in ("eval", "sample"):
        bsdf_call(bsdf, method, x)             # the first call may build what later calls reuse
    return sum(variables_created(lambda m=method: bsdf_call(bsdf, m, x))
               for method in ("eval", "sample"))


def _load(spec, res: int, spp: int):
    """The scene of ``spec``, rendered once untimed, and its operation count."""
    scene = mi.load_dict(S.scene_dict(_make(spec), res, S.COST_VIEW))
    S.render(scene, spp, seed=0)
    return scene, operations(scene.shapes()[0].bsdf())


def timed_render(scene, spp: int, seed: int) -> tuple[float, float, float]:
    """One render's (wall-clock seconds, seconds its kernels executed: the sum
    of Dr.Jit's kernel history ``execution_time``, CPU seconds of this
    process: every thread's)."""
    dr.kernel_history_clear()
    with dr.scoped_set_flag(dr.JitFlag.KernelHistory, True):
        start, cpu = time.perf_counter(), time.process_time()
        S.render(scene, spp, seed=seed)
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        history = dr.kernel_history()
    return wall, sum(k.get("execution_time", 0.0) for k in history) / 1e3, cpu


def _serve(conn, spec, res: int, spp: int) -> None:
    """The worker: load the scene, render once untimed, count operations, then
    answer requests until told to stop (None): a seed, one timed render
    (:func:`timed_render`); ("load", spec), another BSDF's scene in place of
    the first (released first: one BSDF instance alive at a time)."""
    try:
        scene, ops = _load(spec, res, spp)
        conn.send(("ready", ops))
        while (request := conn.recv()) is not None:
            if isinstance(request, tuple):
                del scene
                S.release()
                scene, ops = _load(request[1], res, spp)
                conn.send(("ready", ops))
            else:
                conn.send(("time", timed_render(scene, spp, request)))
    except Exception as error:                 # reported to the parent on one line
        conn.send(("error", one_line(error)))
    finally:
        conn.close()


class Worker:
    """A process holding one scene (:func:`_serve`)."""

    def __init__(self, spec, res: int, spp: int):
        context = multiprocessing.get_context("spawn")
        self.conn, child = context.Pipe()
        self.process = context.Process(target=_serve, args=(child, spec, res, spp), daemon=True)
        self.process.start()
        child.close()
        self.ops = self._reply("ready")

    def _reply(self, kind: str):
        if not self.conn.poll(REPLY_SECONDS):
            raise CostError(f"no answer in {REPLY_SECONDS:.0f} s")
        try:
            what, value = self.conn.recv()
        except EOFError:
            raise CostError(f"the process ended (exit code {self.process.exitcode})") from None
        if what == "error":
            raise CostError(value)
        if what != kind:
            raise CostError(f"answered {what!r} where {kind!r} was due")
        return value

    def time(self, seed: int) -> tuple[float, float, float]:
        """(wall-clock, kernel, CPU) seconds of one render (:func:`timed_render`)."""
        self.conn.send(seed)
        return self._reply("time")

    def load(self, spec) -> None:
        """Another BSDF's scene in this process, in place of the one held."""
        self.conn.send(("load", spec))
        self.ops = self._reply("ready")

    def close(self) -> None:
        try:
            self.conn.send(None)
        except (BrokenPipeError, OSError):
            pass
        self.process.join(timeout=30)
        if self.process.is_alive():
            self.process.kill()
            self.process.join()
        self.conn.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def interval(ratios: list[float], confidence: float = 0.90) -> tuple[float, float, float]:
    """(geometric mean, low, high): Student's t interval on the log ratios."""
    from scipy.stats import t as student     # optional: the reports extra
    logs = [math.log(r) for r in ratios]
    mean = statistics.fmean(logs)
    if len(logs) < 2:
        return math.exp(mean), 0.0, math.inf
    half = student.ppf(0.5 + confidence / 2, len(logs) - 1) * statistics.stdev(logs) / math.sqrt(len(logs))
    return math.exp(mean), math.exp(mean - half), math.exp(mean + half)


TIMINGS = {"wall": 0, "kernels": 1, "cpu": 2}     # which of a worker's times the ratio takes


def compare(target_worker: Worker, model_worker: Worker, rounds: tuple[int, int],
            tolerance: float, timing: str = "cpu", both: list | None = None) -> dict:
    """Rounds of one timed render each, alternating which goes first, until
    the interval of the ``timing`` ratios is tight (module docstring);
    ``both``: a list that receives each round's ratios of every timing."""
    if timing not in TIMINGS:
        raise ValueError(f"cost timing {timing!r} is unknown; valid: {', '.join(TIMINGS)}")
    ratios = []
    for r in range(rounds[1]):
        order = (target_worker, model_worker) if r % 2 == 0 else (model_worker, target_worker)
        seconds = {id(w): w.time(seed=1 + r) for w in order}
        pair = tuple(m / t for m, t in zip(seconds[id(model_worker)], seconds[id(target_worker)]))
        if both is not None:
            both.append(pair)
        ratios.append(pair[TIMINGS[timing]])
        mean, low, high = interval(ratios)
        if len(ratios) >= rounds[0] and high / low <= 1.0 + tolerance:
            break
    return {"cost_ratio": mean, "cost_low": low, "cost_high": high, "cost_rounds": len(ratios),
            "cost_closed": high / low <= 1.0 + tolerance, "cost_aim": 1.0 + tolerance,
            "cost_timing": timing}


def measure_costs(target, records: list[dict], settings, show=None) -> None:
    """Add the cost columns to the successful ``records`` of ``target`` (in
    place); a failed measurement leaves them None and adds ``cost_error``."""
    ok = [r for r in records if "error" not in r]
    if not ok:
        return
    try:
        target_worker = Worker(target, settings.res, settings.cost_spp)
    except CostError as error:
        for r in ok:
            r["cost_error"] = f"the target's cost worker failed: {error}"
        return
    timing = settings.cost_timing
    model_worker = None                  # one process for every model, each loaded in turn
    with target_worker:
        try:
            for r in ok:
                load = os.getloadavg()[0]
                try:
                    if model_worker is None:
                        model_worker = Worker(r["parameters"], settings.res, settings.cost_spp)
                    else:
                        model_worker.load(r["parameters"])
                    r.update(compare(target_worker, model_worker, settings.cost_rounds,
                                     settings.cost_tolerance, timing))
                    r["ops_ratio"] = model_worker.ops / target_worker.ops
                    r["ops"] = model_worker.ops
                    r["cost_spp"] = settings.cost_spp
                except CostError as error:
                    r["cost_error"] = str(error)
                    if model_worker is not None:       # a fresh process for the next one
                        model_worker.close()
                        model_worker = None
                r["cost_load"] = max(load, os.getloadavg()[0])
                r["cost_cores"] = os.cpu_count()
                if show:
                    show(r)
        finally:
            if model_worker is not None:
                model_worker.close()


def measure_all(targets: list, records: list[dict], settings, show=None, offset: int = 0,
                total: int | None = None, start: float | None = None) -> None:
    """:func:`measure_costs` for every target, one measurement at a time;
    ``show(done, total, elapsed, record)`` after each (``offset``: the steps
    done before, ``start``: the run's ``time.perf_counter()`` at its start)."""
    start = time.perf_counter() if start is None else start
    done = [offset]

    def step(record: dict) -> None:
        done[0] += 1
        if show:
            show(done[0], total or done[0], time.perf_counter() - start, record)

    for t in targets:
        mine = [r for r in records if r.get("target_name") == t.name]
        measure_costs(t, mine, settings, step)
        done[0] += sum(1 for r in mine if "error" in r)


def remeasure(report_dir: str, max_targets: int | None = None, settings=None, show=None
              ) -> list[dict]:
    """The fits of a report measured again: per fit, the report's interval and
    the new one."""
    settings = settings or FULL
    with open(os.path.join(report_dir, "fits.json")) as f:
        saved = [r for r in json.load(f) if "error" not in r and r.get("cost_ratio") is not None]
    specs = list(dict.fromkeys(r["target"] for r in saved))[:max_targets]
    rows = []
    for spec in specs:
        target = T.parse([spec])[0]
        again = [{"model": r["model"], "parameters": r["parameters"]} for r in saved
                 if r["target"] == spec]
        measure_costs(target, again, settings, show)
        for old, new in zip([r for r in saved if r["target"] == spec], again):
            rows.append({"target": spec, "model": old["model"],
                         "before": (old["cost_ratio"], old["cost_low"], old["cost_high"]),
                         "again": (new.get("cost_ratio"), new.get("cost_low"), new.get("cost_high")),
                         "rounds": new.get("cost_rounds"), "load": new.get("cost_load"),
                         "overlap": (new.get("cost_low") is not None
                                     and new["cost_low"] <= old["cost_high"]
                                     and old["cost_low"] <= new["cost_high"])})
    return rows


def calls_changed(rows: list[dict]) -> tuple[int, int]:
    """Of the pairs of models of one target measured both times (rows of
    :func:`remeasure`), in how many the cost comparison of :mod:`.rank`
    (cheaper, the same or costlier, by cost class) came out otherwise the
    second time; and of how many."""
    changed = pairs = 0
    for target in dict.fromkeys(r["target"] for r in rows):
        mine = [r for r in rows if r["target"] == target and r["again"][0] is not None]
        for i, a in enumerate(mine):
            for b in mine[i + 1:]:
                pairs += 1
                calls = []
                for when in ("before", "again"):
                    ca, cb = ({"cost_ratio": r[when][0]} for r in (a, b))
                    calls.append((rank.cheaper(ca, cb), rank.cheaper(cb, ca)))
                changed += calls[0] != calls[1]
    return changed, pairs


def steadiness(report_dir: str, max_targets: int | None = 1, models: list[str] | None = None,
               rounds: int = 12, repeats: int = 2, settings=None, show=print) -> list[dict]:
    """Every timing of :data:`TIMINGS` on the same rounds: per fit of a
    report (the first ``max_targets`` targets, ``models`` or all), ``repeats``
    times ``rounds`` rounds; the geometric mean, interval and standard
    deviation of the log ratios of each timing, the load average."""
    settings = settings or FULL
    with open(os.path.join(report_dir, "fits.json")) as f:
        saved = [r for r in json.load(f) if "error" not in r
                 and (models is None or r["model"] in models)]
    specs = list(dict.fromkeys(r["target"] for r in saved))[:max_targets]
    rows = []
    for spec in specs:
        mine = [r for r in saved if r["target"] == spec]
        with Worker(T.parse([spec])[0], settings.res, settings.cost_spp) as target_worker, \
                Worker(mine[0]["parameters"], settings.res, settings.cost_spp) as model_worker:
            for repeat in range(repeats):
                for r in mine:
                    model_worker.load(r["parameters"])
                    both, load = [], os.getloadavg()[0]
                    compare(target_worker, model_worker, (rounds, rounds), 0.0, both=both)
                    row = {"target": spec, "model": r["model"], "repeat": repeat,
                           "load": max(load, os.getloadavg()[0])}
                    for timing, i in TIMINGS.items():
                        ratios = [b[i] for b in both]
                        row[timing] = interval(ratios) + (
                            statistics.stdev(math.log(x) for x in ratios),)
                    rows.append(row)
                    show(" | ".join([f"{spec} {r['model']} #{repeat} load {row['load']:.1f}"] + [
                        f"{t} {m:.3f} ({lo:.3f}-{hi:.3f}) sd(log) {sd:.3f}"
                        for t, (m, lo, hi, sd) in ((t, row[t]) for t in TIMINGS)]))
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m mi_brdfs.tools.fit.cost",
                                description="Measure a fit report's render costs again and "
                                            "compare the intervals (writes nothing).")
    p.add_argument("report", help="a mi-brdfs fit report folder (its fits.json)")
    p.add_argument("--targets", type=int, default=None, help="only the first N targets")
    p.add_argument("--timings", action="store_true",
                   help="instead: time each fit by every timing (wall, kernels, cpu) on the "
                        "same 12 rounds, twice, and print each one's spread")
    p.add_argument("--models", nargs="+", default=None, metavar="NAME",
                   help="with --timings: only these models")
    p.add_argument("--spp", type=int, default=FULL.cost_spp,
                   help=f"samples per pixel of a timed render (default {FULL.cost_spp})")
    args = p.parse_args(argv)
    if args.spp < 1:
        print(f"{p.prog}: error: --spp {args.spp}: give at least 1", file=sys.stderr)
        return 1
    if args.timings:
        try:
            steadiness(args.report, args.targets or 1, args.models,
                       settings=FULL.replace(cost_spp=args.spp))
        except Exception as error:
            print(f"{p.prog}: error: {one_line(error)}", file=sys.stderr)
            return 1
        return 0
    start = time.perf_counter()
    try:
        rows = remeasure(args.report, args.targets, FULL.replace(cost_spp=args.spp))
    except Exception as error:
        print(f"{p.prog}: error: {one_line(error)}", file=sys.stderr)
        return 1
    print("| target | model | report | again | rounds | load | overlap |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        b, a = r["before"], r["again"]
        again = "failed" if a[0] is None else f"{a[0]:.2f} ({a[1]:.2f}–{a[2]:.2f})"
        print(f"| {r['target']} | {r['model']} | {b[0]:.2f} ({b[1]:.2f}–{b[2]:.2f}) | {again} | "
              f"{r['rounds']} | {r['load']:.1f} | {'yes' if r['overlap'] else 'NO'} |")
    both = [r for r in rows if r["again"][0] is not None]
    widths = [r["again"][2] / r["again"][1] for r in both]
    changed, pairs = calls_changed(rows)
    print(f"\n{sum(r['overlap'] for r in both)} of {len(both)} intervals overlap; "
          f"high/low median {statistics.median(widths):.3f}, largest {max(widths):.3f}; "
          f"{changed} of {pairs} pairwise cost comparisons (by cost class) came out otherwise; "
          f"{args.spp} spp, {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
