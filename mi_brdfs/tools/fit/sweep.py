"""Running the fits of targets × models: on local processes (``-j N``, each
task in a worker process started with ``spawn``, never ``fork``: a forked
Dr.Jit is unsafe) or on a Dask distributed cluster (``--scheduler ADDRESS``).
Targets × models is embarrassingly parallel: each task fits one model to one
target and renders it (:func:`.task.fit_and_measure`). Render costs are
measured afterwards, on this machine, one at a time (:mod:`.cost`).

On a cluster:

- the address is checked before anything connects (a protocol Dask knows,
  HOST:PORT): a malformed one is refused at once;
- a scheduler that cannot be reached in ``SCHEDULER_TIMEOUT`` seconds, or
  that has no worker for ``worker_timeout`` seconds (60 by default: before
  the sweep, or all along it once every worker has left) ends the sweep with
  one line (:class:`SweepError`);
- a worker lost mid-sweep is Dask's to handle: the scheduler gives its tasks
  to another worker. Each task's transitions (``Client.story``) tell when
  that happened; the record then has ``reruns`` (how many times its worker
  was lost) and ``worker`` (host:pid of the process that finished it), and
  the report says so.

Every worker needs ``mi_brdfs`` installed (with the same versions), and an
XML target's files (a measured BSDF's data) at the same path as here.
"""
from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing
import os
import sys
import time
from typing import Iterator

import drjit as dr

from ..errors import one_line
from ..progress import Progress
from . import models as M, targets as T
from .task import Settings, fit_and_measure

SCHEDULER_TIMEOUT = 10.0       # seconds to reach a Dask scheduler
WORKER_TIMEOUT = 60.0          # seconds with no worker before a cluster sweep gives up
POLL = 0.5                     # seconds between looks at a cluster's tasks
DEFAULT_PORT = 8786            # Dask's scheduler port


class SweepError(RuntimeError):
    """A sweep that cannot run (reported on one line)."""


def _init_worker(threads: int | None) -> None:
    if threads:
        dr.set_thread_count(threads)
        # FLIP's OpenMP threads too (read when flip_evaluator is imported, later)
        os.environ.setdefault("OMP_NUM_THREADS", str(threads))


def default_jobs() -> int:
    """Local fits at once when none is asked for: the cores, at most 2 (more
    processes on this 2-core machine only share the same cores)."""
    return max(1, min(2, os.cpu_count() or 1))


@contextlib.contextmanager
def local_executor(jobs: int) -> Iterator[cf.Executor]:
    """``jobs`` worker processes (spawned), the cores shared among them (Dr.Jit's
    threads and FLIP's)."""
    threads = max(1, (os.cpu_count() or 1) // jobs) if jobs > 1 else None
    pool = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                                  initializer=_init_worker, initargs=(threads,))
    try:
        yield pool
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


# ----------------------------------------------------------------------------
#  A Dask cluster
# ----------------------------------------------------------------------------

def check_address(address: str) -> None:
    """SweepError unless ``address`` is PROTOCOL://HOST:PORT (or HOST:PORT)
    with a protocol Dask has; nothing is connected."""
    # optional: the dask extra (connect says so on one line when it is missing)
    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port
    from distributed.comm.registry import backends
    valid = [b for b in backends if b != "inproc"]
    example = f"e.g. tcp://HOST:{DEFAULT_PORT}"
    try:
        protocol, location = parse_address(address)
    except ValueError as error:
        raise SweepError(f"--scheduler {address}: not an address ({error}; {example})") from None
    if protocol not in valid:
        raise SweepError(f"--scheduler {address}: unknown protocol {protocol!r}; valid: "
                         f"{', '.join(valid)} ({example})")
    if protocol != "ucx":
        try:
            host, port = parse_host_port(location, DEFAULT_PORT)
        except ValueError:
            host, port = "", 0
        if not host or not 0 < port < 65536:
            raise SweepError(f"--scheduler {address}: {location!r} is not HOST:PORT ({example})")


def connect(address: str, worker_timeout: float = WORKER_TIMEOUT):
    """A Dask client for ``address`` with at least one worker; SweepError (one
    line) if Dask is missing, the address malformed, the scheduler out of
    reach or without a worker for ``worker_timeout`` seconds."""
    try:
        import distributed          # optional: the dask extra
    except ModuleNotFoundError:
        raise SweepError("--scheduler needs Dask: pip install 'mi_brdfs[dask]'") from None
    check_address(address)
    try:
        client = distributed.Client(address, timeout=SCHEDULER_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as error:
        detail = " ".join(str(error).split()) or type(error).__name__
        raise SweepError(f"--scheduler {address}: cannot reach the Dask scheduler "
                         f"({detail})") from None
    try:
        client.wait_for_workers(1, timeout=worker_timeout)
    except (TimeoutError, OSError):
        client.close()
        raise SweepError(f"--scheduler {address}: no worker joined the scheduler in "
                         f"{worker_timeout:g} s (start one: dask worker {address})") from None
    return client


def lost_workers(client, key) -> int:
    """How many times the task ``key`` was taken back from a worker that left
    (the scheduler's transitions processing -> released on worker clean-up)."""
    try:
        story = client.story(key)
    except Exception:                   # an old scheduler without stories: unknown, not lost
        return 0
    return sum(1 for s in story if len(s) > 4 and s[0] == "scheduler" and s[2] == "processing"
               and s[3] == "released" and "worker-cleanup" in str(s[5] if len(s) > 5 else s[4]))


def dask_sweep(client, address: str, tasks: list, settings: Settings, collect,
               worker_timeout: float = WORKER_TIMEOUT, works: dict | None = None) -> None:
    """Every task on the cluster; ``collect(i, record)`` as each finishes."""
    works = works or {}
    futures = [client.submit(fit_and_measure, t, m, settings, works.get(t.name), pure=False)
               for t, m in tasks]
    pending = dict(enumerate(futures))
    alone_since = None
    try:
        while pending:
            finished = [i for i, f in pending.items() if f.done()]
            for i in finished:
                f = pending.pop(i)
                try:
                    record = f.result()
                except Exception as error:          # the task itself could not run
                    record = failed(tasks[i], f"worker failed: {_line(error)}")
                record["reruns"] = lost_workers(client, f.key)
                collect(i, record)
            if finished or not pending:
                continue
            if client.nthreads():
                alone_since = None
            elif alone_since is None:
                alone_since = time.monotonic()
            elif time.monotonic() - alone_since > worker_timeout:
                raise SweepError(f"--scheduler {address}: no worker for {worker_timeout:g} s "
                                 f"({len(tasks) - len(pending)} of {len(tasks)} fits done)")
            time.sleep(POLL)
    finally:
        for f in pending.values():
            f.cancel()


# ----------------------------------------------------------------------------
#  The sweep
# ----------------------------------------------------------------------------

def _line(error: BaseException) -> str:
    return one_line(error)


def failed(task, message: str) -> dict:
    t, m = task
    return {"target": t.spec, "model": m.name, "plugin": m.plugin, "error": message}


def local_sweep(executor: cf.Executor, tasks: list, settings: Settings, collect,
                works: dict | None = None) -> None:
    works = works or {}
    futures = {executor.submit(fit_and_measure, t, m, settings, works.get(t.name)): i
               for i, (t, m) in enumerate(tasks)}
    try:
        for future in cf.as_completed(futures):
            i = futures[future]
            try:
                record = future.result()
            except Exception as error:             # a worker that died, not a failed fit
                record = failed(tasks[i], f"worker failed: {_line(error)}")
            collect(i, record)
    except BaseException:
        for f in futures:
            f.cancel()
        raise


def run_fits(tasks: list[tuple[T.Target, M.Model]], settings: Settings, jobs: int | None = None,
             scheduler: str | None = None, show=None, client=None,
             worker_timeout: float = WORKER_TIMEOUT, total: int | None = None,
             start: float | None = None, works: dict | None = None) -> list[dict]:
    """Every (target, model) task, on local processes or on the Dask scheduler
    at ``scheduler`` (``client``: one already connected); records in task
    order (``jobs``: local processes, None :func:`default_jobs`).
    ``show(done, total, elapsed, record)`` after each task (``total``: the
    steps of the whole run, if more than the fits; ``start``: its
    ``time.perf_counter()`` at the start of the run; ``works``: target name:
    its :class:`.work.TargetWork`, handed to each of its tasks)."""
    records: list[dict | None] = [None] * len(tasks)
    start = time.perf_counter() if start is None else start

    def collect(i: int, record: dict) -> None:
        record["target_name"] = tasks[i][0].name
        records[i] = record
        if show:
            show(sum(r is not None for r in records), total or len(tasks),
                 time.perf_counter() - start, record)

    if scheduler:
        own = client is None
        client = client or connect(scheduler, worker_timeout)
        try:
            dask_sweep(client, scheduler, tasks, settings, collect, worker_timeout, works)
        finally:
            if own:
                client.close()
    else:
        with local_executor(jobs or default_jobs()) as executor:
            local_sweep(executor, tasks, settings, collect, works)
    return [r for r in records if r is not None]


PHASES = {"fit": "fitted", "cost": "cost timed"}


def phase(record: dict) -> str:
    """Which step of a fit a finished record closes: ``fit`` or ``cost``."""
    return "cost" if "cost_rounds" in record or "cost_error" in record else "fit"


def progress_printer(label: str, stream=None, enabled: bool = True, verbose: bool = False):
    """``show(done, total, elapsed, record)`` for :func:`run_fits` and the
    cost measurements (``done`` of ``total`` models in the record's phase,
    :func:`phase`): a bar per phase on a terminal ("LABEL (fitted): 3/24
    models", the time left from the models after the first, which also
    starts the worker), plain lines in a log; each finished model's
    :func:`summary` with ``verbose`` or in a log."""
    out = stream if stream is not None else sys.stderr
    state = {"phase": None, "bar": None, "start": 0.0}

    def show(done: int, total: int, elapsed: float, record: dict) -> None:
        now = phase(record)
        if now != state["phase"]:
            if state["bar"] is not None:
                state["bar"].close()
            state.update(phase=now, start=state.get("last", 0.0),       # the phase's start
                         bar=Progress(f"{label} ({PHASES[now]})", stream=stream,
                                      enabled=enabled, unit="models"))
        state["last"] = elapsed
        bar = state["bar"]
        if enabled and (verbose or not bar.terminal):
            out.write(f"{label}: {summary(record)}\n")
            out.flush()
        bar(done, total, max(elapsed - state["start"], 0.0))

    def close() -> None:
        if state["bar"] is not None:
            state["bar"].close()
    show.close = close
    return show


def summary(record: dict) -> str:
    """One line on a finished fit."""
    head = f"{record['target']} × {record['model']}"
    if "error" in record:
        return f"{head}: FAILED: {record['error']}"
    if "cost_rounds" in record or "cost_error" in record:
        if "cost_error" in record:
            return f"{head}: cost not measured: {record['cost_error']}"
        return (f"{head}: cost {record['cost_ratio']:.2f}x ({record['cost_low']:.2f}-"
                f"{record['cost_high']:.2f}, {record['cost_rounds']} rounds), "
                f"{record['ops_ratio']:.2f}x the operations")
    parts = [f"brdf error {record['brdf_error']:.4g}"]
    if record.get("image_flip") is not None:
        parts += [f"FLIP {record['image_flip']:.3g}", f"image relMSE {record['image_relmse']:.3g}"]
    if record.get("reruns"):
        parts.append(f"re-run after its worker was lost ({record['reruns']}x)")
    parts.append(f"{record['seconds']:.1f} s")
    return f"{head}: " + ", ".join(parts)
