import os


def pytest_configure(config):
    # OpenMM's CPU platform hands forces to a worker thread; for the small systems of the
    # tests, one pinned core is 3-4x faster (workflows/benchmark_engine.py). The suite runs
    # on one pytest-xdist worker per core (pyproject: -n auto --dist loadfile): worker k
    # takes core k; the controller only waits, so it leaves its cores to the workers (they
    # inherit its mask). Without xdist: one core chosen by process id, so that concurrent
    # test runs spread over the cores.
    try:
        cores = sorted(os.sched_getaffinity(0))
        worker = os.environ.get("PYTEST_XDIST_WORKER")
        if worker is not None:
            k = int(worker.lstrip("gw") or 0)
        elif getattr(config.option, "numprocesses", None):
            return  # the xdist controller
        else:
            k = os.getpid()
        os.sched_setaffinity(0, {cores[k % len(cores)]})
    except (AttributeError, OSError, ValueError):
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


# The braid's default until 2026-12-05 (2 x 60 nm at 20 pN, Brownian dynamics alone, a stiff
# trap): the tests written against it pin it, so that the default scene can follow the
# experiments (dnabraid/scenes/braid.py, docs/validation.md 1.6).
from dnabraid.scenes.braid import TOY_BRAID  # noqa: E402


def toy_braid(**over):
    """The pre-2026-12-06 default braid with `over` on top (keys of `make_scene`)."""
    return {**TOY_BRAID, **over}


def without_guard_roundoff(points):
    """Summary points with the move guard's largest disagreement removed, for comparing
    runs that must agree to all digits. That number is the round-off of OpenMM's energy
    (CPU platform: single-precision nonbonded terms summed over threads in an order that a
    new Context need not repeat): the integration braid's resumed point read 6.97e-5 pN nm
    where the uninterrupted one read 2.59e-5 (CI, 2026-12-06), with positions, moves and
    every observable identical. The guard itself still stops a run that exceeds its
    tolerance; here it is checked to stay below 1e-3 pN nm."""
    import copy

    out = copy.deepcopy(points)
    for p in out:
        mv = p.get("rigid_moves") or {}
        d = mv.pop("guard_max_diff_pN_nm", None)
        assert d is None or d < 1e-3, (p.get("label"), d)
    return out
