"""One thread that runs the explorer's jobs, newest request first-class.

Dr.Jit work runs on one thread (:class:`Worker`), so that requests of many
clients never meet inside Dr.Jit. Each job has a *slot* — (client, column,
operation) for the websocket, a slot of its own for each HTTP request — and
a slot holds one job: a newer job replaces a queued one, and a running one
is abandoned at its next step. A job is a function that returns a result,
or a generator of results (the passes of a progressive render): after each
step the job goes to the back of the queue, and a job of an *urgent*
operation (the plots a slider asks for) is taken before any other that
waits, so that a slider's plots wait for no more than the pass running. Every result is handed to the job's
``deliver(result, error, done)`` on the worker's thread; ``error`` is a
one-line message. An idle worker waits on a condition: no CPU.
"""
from __future__ import annotations

import sys
import threading
from collections import OrderedDict
from typing import Callable

from .backend import MaterialError, message
from .material import RequestError


class Job:
    def __init__(self, slot, work: Callable, deliver: Callable):
        self.slot, self.work, self.deliver = slot, work, deliver
        self.steps = None             # the generator, once the work returned one


class Worker:
    """A thread running jobs by slot, the newest job of each slot only."""

    def __init__(self, name: str, urgent: tuple = ()):
        self.urgent = frozenset(urgent)       # operations (a slot's last item) taken first
        self._lock = threading.Condition()
        self._queue: OrderedDict[object, Job] = OrderedDict()   # runnable, oldest first
        self._newest: dict[object, Job] = {}                    # each slot's job
        self._stopping = False
        self.thread = threading.Thread(target=self._run, name=name, daemon=True)
        self.thread.start()

    def submit(self, slot, work: Callable, deliver: Callable) -> None:
        """Run ``work()`` for ``slot``, replacing the slot's earlier job."""
        job = Job(slot, work, deliver)
        with self._lock:
            self._newest[slot] = job
            self._queue.pop(slot, None)
            self._queue[slot] = job
            self._lock.notify()

    def cancel(self, owner) -> None:
        """Drop every job whose slot starts with ``owner`` (a client that left)."""
        with self._lock:
            for slot in [s for s in self._newest if s[0] == owner]:
                del self._newest[slot]
                self._queue.pop(slot, None)

    def call(self, work: Callable):
        """Run ``work()`` on the worker's thread and wait for its result."""
        done = threading.Event()
        box: dict = {}

        def deliver(result, error, finished):
            box.update(result=result, error=error)
            done.set()
        self.submit(("call", object()), work, deliver)
        done.wait()
        if box["error"] is not None:
            raise RuntimeError(box["error"])
        return box["result"]

    def stop(self, timeout: float = 5.0) -> None:
        with self._lock:
            self._stopping = True
            self._queue.clear()
            self._newest.clear()
            self._lock.notify()
        self.thread.join(timeout)

    # --- the thread ----------------------------------------------------------------
    def _next(self) -> Job | None:
        with self._lock:
            while not self._queue and not self._stopping:
                self._lock.wait()
            if self._stopping:
                return None
            slot = next((s for s in self._queue if s[-1] in self.urgent), None)
            if slot is not None:
                return self._queue.pop(slot)
            return self._queue.popitem(last=False)[1]

    def _run(self) -> None:
        while (job := self._next()) is not None:
            result, error, finished = self._step(job)
            with self._lock:
                current = self._newest.get(job.slot) is job
                if current and not finished:
                    self._queue[job.slot] = job          # its next step, after the others
                elif current:
                    del self._newest[job.slot]
            if current:
                try:
                    job.deliver(result, error, finished)
                except Exception as e:                    # noqa: BLE001  (a client gone)
                    print(f"mi-brdfs explore: a result was not delivered: {message(e)}",
                          file=sys.stderr)

    @staticmethod
    def _step(job: Job):
        """(result, error, finished) of one step of ``job``."""
        try:
            if job.steps is None:
                result = job.work()
                if not hasattr(result, "__next__"):
                    return result, None, True
                job.steps = result
            try:
                return next(job.steps), None, False
            except StopIteration:
                return None, None, True
        except (RequestError, MaterialError) as error:
            return None, str(error), True
        except Exception as error:                        # noqa: BLE001  (reported, one line)
            text = message(error)
            print(f"mi-brdfs explore: {job.slot[-1]} failed: {text}", file=sys.stderr)
            return None, text, True
