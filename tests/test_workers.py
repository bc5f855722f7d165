"""dnabraid.run.workers: pinning, serial and pooled jobs, progress batching, errors."""

from __future__ import annotations

import os
import time

import pytest

from dnabraid.run import workers
from dnabraid.run.workers import pin_to_core, run_jobs, usable_cores


# module-level jobs: the pool pickles them by name ------------------------------------
def _square(job, report):
    """job = (x, steps, sleep_s): reports ``steps`` one at a time, returns x^2."""
    x, steps, sleep_s = job
    for _ in range(steps):
        report(1)
    time.sleep(sleep_s)
    return x * x


def _fail_on_odd(job, report):
    report(5)
    if job % 2:
        raise ValueError(f"job {job} is odd")
    return job


def _affinity(job, report):
    time.sleep(0.3)  # keep every worker busy so that each takes a job
    return sorted(os.sched_getaffinity(0))


class _Unpicklable(Exception):
    def __init__(self, message, *, code):
        super().__init__(message)
        self.code = code


def _raise_unpicklable(job, report):
    raise _Unpicklable("keyword-only arguments", code=job)


# -------------------------------------------------------------------------------------
def test_usable_cores_and_pin():
    cores = usable_cores()
    assert cores == sorted(cores) and len(cores) >= 1
    before = os.sched_getaffinity(0)
    try:
        pin_to_core(len(cores) + 1)  # taken modulo the usable cores
        assert os.sched_getaffinity(0) == {cores[(len(cores) + 1) % len(cores)]}
    finally:
        os.sched_setaffinity(0, before)


def test_serial_in_order_with_direct_progress():
    seen, done = [], []
    res = run_jobs(_square, [(3, 2, 0), (1, 0, 0), (2, 3, 0)], 1, progress=seen.append,
                   on_done=lambda i, r: done.append((i, r)))
    assert res == [9, 1, 4]
    assert seen == [1] * 5  # no batching in-process
    assert done == [(0, 9), (1, 1), (2, 4)]
    assert run_jobs(_square, [], 4) == []


def test_serial_errors():
    with pytest.raises(ValueError, match="job 1 is odd"):
        run_jobs(_fail_on_odd, [0, 1, 2], 0)
    res = run_jobs(_fail_on_odd, [0, 1, 2], 1, errors="return")
    assert res[0] == 0 and res[2] == 2
    assert isinstance(res[1], ValueError) and str(res[1]) == "job 1 is odd"
    with pytest.raises(ValueError, match="errors must be"):
        run_jobs(_fail_on_odd, [0], 1, errors="ignore")


def test_pool_order_progress_and_pinning():
    """Jobs finishing in reverse order come back in job order; the steps arrive in batches
    of at least REPORT_BATCH plus one remainder per job; each worker has one core."""
    n = workers.REPORT_BATCH
    jobs = [(1, 2 * n + 7, 0.6), (2, n // 2, 0.3), (3, 3, 0.0)]
    seen, done = [], []
    res = run_jobs(_square, jobs, 2, progress=seen.append,
                   on_done=lambda i, r: done.append(i))
    assert res == [1, 4, 9]
    assert sum(seen) == sum(j[1] for j in jobs)
    assert len(seen) <= 2 + 3  # two full batches, at most one remainder per job
    assert sorted(done) == [0, 1, 2] and done[-1] == 0  # the slow job finishes last
    cores = set(usable_cores())
    aff = run_jobs(_affinity, range(2), 2)
    assert all(len(a) == 1 and set(a) <= cores for a in aff)
    if len(cores) >= 2:
        assert aff[0] != aff[1], "the two workers share a core"


def test_pool_errors_keep_type_and_message():
    with pytest.raises(ValueError, match="job 1 is odd") as info:
        run_jobs(_fail_on_odd, [0, 1, 2, 4], 2)
    assert isinstance(info.value.__cause__, workers.RemoteTraceback)
    assert "_fail_on_odd" in str(info.value.__cause__)
    done = []
    res = run_jobs(_fail_on_odd, [0, 1, 2, 3], 2, errors="return",
                   on_done=lambda i, r: done.append(i))
    assert res[0] == 0 and res[2] == 2
    assert [type(r) for r in (res[1], res[3])] == [ValueError, ValueError]
    assert str(res[3]) == "job 3 is odd" and sorted(done) == [0, 1, 2, 3]
    # an exception that cannot be rebuilt from its args still reaches the parent
    with pytest.raises(RuntimeError, match="_Unpicklable: keyword-only arguments"):
        run_jobs(_raise_unpicklable, [1, 2], 2)
