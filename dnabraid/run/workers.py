"""Core pinning and the process pool every parallel run goes through.

OpenMM's CPU platform hands the forces of a small system to a worker thread, and the
hand-off costs more than the force: a process pinned to one core with one OpenMM thread
runs the bead systems here 3-4x faster (workflows/benchmark_engine.py). Parallel work is
therefore one process per core, each pinned to its own core:

* :func:`usable_cores` and :func:`pin_to_core` pin a process;
* :func:`run_jobs` runs ``fn(job, report)`` for a list of jobs, serially in this process
  (one worker) or in a pool of spawned processes (several), forwards the steps the jobs
  report to a progress callback, and returns the results in job order.

The pool uses the ``spawn`` start method: forking a process after OpenMM has started its
threads can deadlock the child. Hence ``fn`` must be a module-level function and the jobs
and results picklable.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import os
import pickle
import traceback
from collections.abc import Callable, Iterable
from typing import Any

log = logging.getLogger(__name__)

__all__ = ["usable_cores", "pin_to_core", "run_jobs"]

#: Steps a worker accumulates before it sends a progress message to the parent.
REPORT_BATCH = 20_000
#: Seconds the parent waits for a job to finish before it forwards progress again.
_POLL_S = 0.25

# set in each pool worker by _init_worker
_QUEUE = None


def usable_cores() -> list[int]:
    """The CPU cores this process may run on.

    Returns
    -------
    list of int
        The sorted affinity set (Linux); elsewhere ``range(os.cpu_count())``.
    """
    try:
        return sorted(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return list(range(os.cpu_count() or 1))


def pin_to_core(k: int = 0) -> None:
    """Pin this process to usable core ``k`` modulo the number of usable cores.

    Parameters
    ----------
    k : int
        Index into :func:`usable_cores` (taken modulo its length). A no-op where the
        operating system has no affinity call (not Linux) or refuses it.
    """
    cores = usable_cores()
    try:
        os.sched_setaffinity(0, {cores[k % len(cores)]})
    except (AttributeError, OSError):  # pragma: no cover - not on Linux
        pass


class RemoteTraceback(Exception):
    """The traceback of an exception raised in a pool worker (set as its ``__cause__``)."""

    def __init__(self, tb: str):
        super().__init__(tb)
        self.tb = tb

    def __str__(self) -> str:
        return "\n" + self.tb


def _init_worker(counter, cores: list[int], queue) -> None:
    """Pool initializer: take the next core of ``cores`` and keep the progress queue."""
    global _QUEUE
    _QUEUE = queue
    with counter.get_lock():
        slot = counter.value
        counter.value += 1
    try:
        os.sched_setaffinity(0, {cores[slot % len(cores)]})
    except (AttributeError, OSError):  # pragma: no cover - not on Linux
        pass


def _portable(exc: BaseException) -> BaseException:
    """``exc`` if it survives pickling to the parent, else a RuntimeError with its text."""
    try:
        pickle.loads(pickle.dumps(exc))
        return exc
    except Exception:  # an exception class whose __init__ pickle cannot call again
        return RuntimeError(f"{type(exc).__qualname__}: {exc}")


def _call(fn: Callable, job) -> tuple:
    """Run one job in a pool worker; progress is batched into the queue.

    Returns ``("ok", result)`` or ``("error", exception, traceback text)``: the
    exception travels as a value, so that the parent re-raises it with its own type.
    """
    acc = [0]

    def report(n) -> None:
        acc[0] += n
        if acc[0] >= REPORT_BATCH:
            _QUEUE.put(acc[0])
            acc[0] = 0

    try:
        res = fn(job, report)
    except Exception as exc:  # handed to the parent intact
        out: tuple = ("error", _portable(exc), traceback.format_exc())
    else:
        out = ("ok", res)
    if acc[0]:
        _QUEUE.put(acc[0])  # SimpleQueue: in the pipe before the result is sent
    return out


def run_jobs(fn: Callable[[Any, Callable[[int], None]], Any], jobs: Iterable, workers: int,
             *, progress: Callable[[int], None] | None = None,
             on_done: Callable[[int, Any], None] | None = None,
             errors: str = "raise") -> list:
    """Run ``fn(job, report)`` for every job, serially or in a pool of pinned processes.

    Parameters
    ----------
    fn : callable(job, report)
        A module-level function (it is pickled by name). ``report(n)`` tells the parent
        that ``n`` more steps (or any unit of work) are done.
    jobs : iterable
        Picklable job descriptions.
    workers : int
        ``<= 1``: every job runs in this process, in order, and ``report`` is
        ``progress`` itself. Otherwise ``min(workers, len(jobs))`` spawned processes,
        the i-th started pinned to usable core i (modulo the cores this process may use),
        each job in whichever process is free.
    progress : callable(int), optional
        Called in this process with the reported steps; from a pool the steps come in
        batches of at least :data:`REPORT_BATCH` (the remainder when a job ends).
    on_done : callable(index, result), optional
        Called in this process as each job finishes, with its index in ``jobs`` and its
        result (the exception, with ``errors="return"``, for a failed job).
    errors : {"raise", "return"}
        ``"raise"``: the first exception a job raises is re-raised here with its type and
        message (from a pool: after the jobs already running have finished and the pool
        has shut down; jobs not started are cancelled). ``"return"``: the exception
        object takes the failed job's place in the results and the other jobs go on (a
        worker process that dies gives the pool's ``BrokenProcessPool`` for its jobs).

    Returns
    -------
    list
        The results in the order of ``jobs``.

    Notes
    -----
    An exception raised in a pool worker has a :class:`RemoteTraceback` (the worker's
    traceback) as its ``__cause__``. One that cannot be pickled back becomes a
    ``RuntimeError`` naming its type. An exception raised by ``progress`` or ``on_done``
    stops waiting at once; jobs already running are left to finish in the background.
    """
    if errors not in ("raise", "return"):
        raise ValueError(f"errors must be 'raise' or 'return', got {errors!r}")
    jobs = list(jobs)
    if not jobs:
        return []
    if workers <= 1:
        return _run_serial(fn, jobs, progress, on_done, errors)
    return _run_pool(fn, jobs, min(int(workers), len(jobs)), progress, on_done, errors)


def _run_serial(fn, jobs, progress, on_done, errors) -> list:
    report = progress if progress is not None else (lambda n: None)
    out = []
    for i, job in enumerate(jobs):
        try:
            res = fn(job, report)
        except Exception as exc:
            if errors == "raise":
                raise
            res = exc
        out.append(res)
        if on_done is not None:
            on_done(i, res)
    return out


def _run_pool(fn, jobs, n, progress, on_done, errors) -> list:
    import multiprocessing as mp

    ctx = mp.get_context("spawn")  # no fork after OpenMM has started threads
    queue = ctx.SimpleQueue()
    counter = ctx.Value("i", 0)

    def drain() -> None:
        while not queue.empty():
            steps = queue.get()
            if progress is not None:
                progress(steps)

    ex = cf.ProcessPoolExecutor(max_workers=n, mp_context=ctx, initializer=_init_worker,
                                initargs=(counter, usable_cores(), queue))
    log.debug("run_jobs: %d jobs on %d processes", len(jobs), n)
    results: list = [None] * len(jobs)
    first: BaseException | None = None
    try:
        futs = {ex.submit(_call, fn, job): i for i, job in enumerate(jobs)}
        pending = set(futs)
        while pending:
            done, pending = cf.wait(pending, timeout=_POLL_S,
                                    return_when=cf.FIRST_COMPLETED)
            drain()
            for f in sorted(done, key=futs.__getitem__):
                i = futs[f]
                if f.cancelled():
                    continue
                try:
                    out = f.result()
                except Exception as exc:  # the worker process died (killed, out of memory)
                    res: Any = exc
                else:
                    if out[0] == "ok":
                        res = out[1]
                    else:
                        res = out[1]
                        res.__cause__ = RemoteTraceback(out[2])
                if isinstance(res, BaseException):
                    if errors == "raise":
                        if first is None:
                            first = res
                            for g in pending:
                                g.cancel()
                        continue
                results[i] = res
                if on_done is not None:
                    on_done(i, res)
    except BaseException:
        ex.shutdown(wait=False, cancel_futures=True)
        raise
    ex.shutdown(wait=True)
    drain()
    if first is not None:
        raise first
    return results
