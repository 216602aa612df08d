"""Running the fits of targets × models through a ``concurrent.futures``
executor: local processes (``-j N``, each task in a worker process started
with ``spawn``, never ``fork``: a forked Dr.Jit is unsafe) or a Dask
distributed cluster (``--scheduler ADDRESS``, through the client's
``concurrent.futures`` executor). Targets × models is embarrassingly
parallel: each task fits one model to one target and measures it
(:func:`.task.run`).

Render cost is timed inside each task, the target and the model side by side
in one process; tasks running at the same time on the same machine share its
cores, so the ratios are steadiest with ``-j 1`` on a quiet machine.

On a Dask cluster every worker needs ``mi_brdfs`` installed (with the same
versions), and an XML target's files (a measured BSDF's data) at the same
path as here.
"""
from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing
import os
import sys
import time
from typing import Callable, Iterator

from . import models as M, targets as T
from .task import Settings, run as run_task

SCHEDULER_TIMEOUT = 10.0       # seconds to reach a Dask scheduler


class SweepError(RuntimeError):
    """A sweep that cannot run (reported on one line)."""


def _init_worker(threads: int | None) -> None:
    import mi_brdfs  # noqa: F401
    if threads:
        import drjit as dr
        dr.set_thread_count(threads)


@contextlib.contextmanager
def local_executor(jobs: int) -> Iterator[cf.Executor]:
    """``jobs`` worker processes (spawned), Dr.Jit's threads shared among them."""
    threads = max(1, (os.cpu_count() or 1) // jobs) if jobs > 1 else None
    pool = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                                  initializer=_init_worker, initargs=(threads,))
    try:
        yield pool
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def connect(address: str):
    """A Dask distributed client for ``address``; SweepError if Dask is not
    installed or the scheduler cannot be reached."""
    try:
        import distributed
    except ModuleNotFoundError:
        raise SweepError("--scheduler needs Dask: pip install 'mi_brdfs[dask]'") from None
    try:
        return distributed.Client(address, timeout=SCHEDULER_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as error:
        detail = " ".join(str(error).split()) or type(error).__name__
        raise SweepError(f"--scheduler {address}: cannot reach the Dask scheduler "
                         f"({detail})") from None


@contextlib.contextmanager
def dask_executor(address: str) -> Iterator[cf.Executor]:
    client = connect(address)
    try:
        yield client.get_executor(pure=False)
    finally:
        client.close()


def sweep(targets: list[T.Target], models: list[M.Model], settings: Settings,
          executor: cf.Executor, show: Callable[[int, int, float, dict], None] | None = None
          ) -> list[dict]:
    """Every target × model through ``executor``; records in (target, model)
    order. ``show(done, total, elapsed, record)`` after each task."""
    tasks = [(t, m) for t in targets for m in models]
    start = time.perf_counter()
    futures = {executor.submit(run_task, t, m, settings): i for i, (t, m) in enumerate(tasks)}
    records: list[dict | None] = [None] * len(tasks)
    try:
        for done, future in enumerate(cf.as_completed(futures), 1):
            i = futures[future]
            try:
                record = future.result()
            except Exception as error:             # a worker that died, not a failed fit
                from ..errors import one_line
                t, m = tasks[i]
                record = {"target": t.spec, "model": m.name, "plugin": m.plugin,
                          "error": f"worker failed: {one_line(error)}"}
            record["target_name"] = tasks[i][0].name
            records[i] = record
            if show:
                show(done, len(tasks), time.perf_counter() - start, record)
    except BaseException:
        for f in futures:
            f.cancel()
        raise
    return [r for r in records if r is not None]


def run(targets: list[T.Target], models: list[M.Model], settings: Settings, jobs: int = 1,
        scheduler: str | None = None, show=None) -> list[dict]:
    """The sweep on local processes, or on the Dask scheduler at ``scheduler``."""
    context = dask_executor(scheduler) if scheduler else local_executor(jobs)
    with context as executor:
        return sweep(targets, models, settings, executor, show)


def progress_printer(label: str, stream=None, enabled: bool = True, verbose: bool = False):
    """``show`` for :func:`sweep`: a bar on a terminal, plain lines in a log."""
    from ..progress import Progress
    bar = Progress(label, stream=stream, enabled=enabled, unit="fits")
    out = stream if stream is not None else sys.stderr

    def show(done: int, total: int, elapsed: float, record: dict) -> None:
        if enabled and (verbose or not bar.terminal):
            out.write(f"{label}: {summary(record)}\n")
            out.flush()
        bar(done, total, elapsed)
    show.close = bar.close
    return show


def summary(record: dict) -> str:
    """One line on a finished fit."""
    head = f"{record['target']} × {record['model']}"
    if "error" in record:
        return f"{head}: FAILED: {record['error']}"
    parts = [f"brdf error {record['brdf_error']:.4g}"]
    if record.get("image_relmse") is not None:
        parts += [f"image relMSE {record['image_relmse']:.3g}", f"FLIP {record['image_flip']:.3g}",
                  f"cost {record['cost_ratio']:.2f}x"]
    parts.append(f"{record['seconds']:.1f} s")
    return f"{head}: " + ", ".join(parts)
