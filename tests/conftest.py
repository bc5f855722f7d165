import os


def pytest_configure(config):
    # OpenMM's CPU platform hands forces to a worker thread; for the small systems of the
    # tests, one pinned core is 3-4x faster (workflows/benchmark_engine.py).
    try:
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    except (AttributeError, OSError):
        pass
