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


def load_workflow(name):
    """A script of workflows/ imported as a module (the workflows are not a package)."""
    import importlib.util

    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "workflows",
                        name + ".py")
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod
