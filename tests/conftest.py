import os


def pytest_configure(config):
    # OpenMM's CPU platform hands forces to a worker thread; for the small systems of the
    # tests, one pinned core is 3-4x faster (workflows/benchmark_engine.py).
    try:
        # one core, chosen by process id so that concurrent test runs spread over the cores
        cores = sorted(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cores[os.getpid() % len(cores)]})
    except (AttributeError, OSError):
        pass
