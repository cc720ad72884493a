"""Shared fixtures. Guards against the unrelated PyPI ``modal`` shadowing ours."""
from __future__ import annotations

import functools
import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
# hypothesis writes a cache (``constants``, and the example database where a test keeps one)
# under .hypothesis/ in the working directory even with database=None; the runs here are
# derandomised or seeded, so nothing of it is needed: keep it out of the source tree
if "HYPOTHESIS_STORAGE_DIRECTORY" not in os.environ:
    import tempfile

    from hypothesis.configuration import set_hypothesis_home_dir

    set_hypothesis_home_dir(os.path.join(tempfile.gettempdir(), f"modalbal-hypothesis-{os.getuid()}"))

# with PYTHONDONTWRITEBYTECODE set, bytecode is cached outside the checkout (support.bytecode); set here,
# before the xdist workers and the tests' subprocesses start, which inherit it; this process's import
# system reads both settings at every import
def _cache_bytecode() -> None:
    import sys
    import tempfile

    from support.bytecode import cache_outside_the_checkout

    prefix = cache_outside_the_checkout(os.environ, tempfile.gettempdir())
    if prefix is not None:
        sys.pycache_prefix = prefix
        sys.dont_write_bytecode = False


_cache_bytecode()


def pytest_configure(config):
    """The default run's derandomised hypothesis tests draw the same cases whatever else runs.

    Hypothesis mixes constants harvested from every loaded local module into its draws, so a
    derandomised test drew other cases after another test file had been imported (checked:
    st.floats(0, 2) gave 1e-05 in place of 0.001 once test_crank.py ran first). The default
    run (``-m "not stress"``) switches that harvest off; ``-m stress`` keeps it, for exploration.

    Every run is also watched for files its tests leave in the checkout (every test writes under a
    temporary folder): support.checkout compares ``git status`` (and the files inside untracked and
    ignored folders) at the start and the end, and fails the run naming what it left.
    """
    from support.checkout import CheckoutGuard

    config.pluginmanager.register(CheckoutGuard(ROOT), "modalbal-checkout-guard")
    if "not stress" not in (config.option.markexpr or ""):
        return
    try:
        from hypothesis.internal.conjecture import providers
    except ImportError:  # pragma: no cover - hypothesis reorganised; draws then depend on the session
        return
    if hasattr(providers, "_get_local_constants") and hasattr(providers, "Constants"):
        providers._get_local_constants = providers.Constants

import modal  # noqa: E402

if getattr(modal, "__toolkit_id__", None) != "modalbal":  # pragma: no cover
    raise pytest.UsageError(
        "the imported `modal` is not this toolkit's (another distribution, probably the "
        "Modal Labs cloud client, shadows it); use a virtual environment of its own"
    )

from support.paths import REAL, ROOT, SYNTHETIC  # noqa: E402,F401

#: folders of the special suites and the marker each of their tests carries (the long runs of
#: tests/stress/ carry ``stress`` themselves: its quick checks stay in the default run)
SUITE_MARKERS = {"fuzz": "fuzz", "calibration": "calibration"}


@pytest.hookimpl(tryfirst=True)
def pytest_cmdline_main(config):
    """``pytest -n N`` of the default run (``-m "not stress"``) hands its workers whole files
    (:mod:`support.workergroups`); an explicit ``--dist`` is kept, and the stress run keeps ``load``."""
    if (getattr(config.option, "numprocesses", None) and config.option.dist == "no"
            and "not stress" in (config.option.markexpr or "")):
        config.option.dist = "loadfile"


@pytest.hookimpl(tryfirst=True, optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadfile``: whole files to a worker, and the files sharing a session fixture together."""
    if config.getvalue("dist") != "loadfile":
        return None
    from support.workergroups import FileGroupScheduling

    return FileGroupScheduling(config, log)


def pytest_collection_modifyitems(config, items):
    """Mark every test of a special suite's folder with that suite's marker (``-m fuzz`` etc.)."""
    tests = Path(__file__).resolve().parent
    for item in items:
        try:
            top = Path(item.path).resolve().relative_to(tests).parts[0]
        except ValueError:
            continue
        if top in SUITE_MARKERS:
            item.add_marker(getattr(pytest.mark, SUITE_MARKERS[top]))


@pytest.fixture
def synthetic_dir() -> Path:
    return SYNTHETIC


@pytest.fixture
def real_dir() -> Path:
    return REAL


_CLUSTER = pytest.StashKey()
_CLUSTER_LAST_USER = pytest.StashKey()


@pytest.fixture(scope="session")
def _session_cluster(request, tmp_path_factory):
    from support.daskcluster import SessionCluster

    holder = request.session.stash[_CLUSTER] = SessionCluster(tmp_path_factory)
    yield holder
    holder.stop()


@pytest.fixture(scope="module")
def dask_cluster(_session_cluster):
    """A real ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1: (address, folder, processes).

    One cluster serves every file that asks for it; it stops after the last of them on this process
    (:func:`pytest_runtest_teardown`), not at the end of the session."""
    return _session_cluster.get()


def pytest_collection_finish(session):
    """The last test, in the run's order, that asks for the Dask cluster (a run in one process stops it there)."""
    from support.daskcluster import last_user

    fixtures = {item.nodeid: item.fixturenames for item in session.items}
    session.stash[_CLUSTER_LAST_USER] = last_user(fixtures, lambda nodeid: "dask_cluster" in fixtures[nodeid])


@pytest.hookimpl(trylast=True)
def pytest_runtest_teardown(item, nextitem):
    """Stop the Dask cluster once no test left on this process needs it (support.daskcluster.done_with_cluster);
    after the test's own teardown, so the module fixtures built on the cluster are gone first."""
    holder = item.session.stash.get(_CLUSTER, None)
    if holder is None or not holder.running:
        return
    from support.daskcluster import done_with_cluster

    if done_with_cluster(item.nodeid, None if nextitem is None else nextitem.nodeid,
                         item.session.stash.get(_CLUSTER_LAST_USER, None),
                         item.config.getvalue("dist") == "loadfile", _in_cluster_group):
        holder.stop()


@functools.lru_cache(maxsize=None)
def _in_cluster_group(path: str) -> bool:
    from support.workergroups import file_group

    return file_group(path, ROOT) == "dask_cluster"

