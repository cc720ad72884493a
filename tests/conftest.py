"""Shared fixtures. Guards against the unrelated PyPI ``modal`` shadowing ours."""
from __future__ import annotations

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


def pytest_configure(config):
    """The default run's derandomised hypothesis tests draw the same cases whatever else runs.

    Hypothesis mixes constants harvested from every loaded local module into its draws, so a
    derandomised test drew other cases after another test file had been imported (checked:
    st.floats(0, 2) gave 1e-05 in place of 0.001 once test_crank.py ran first). The default
    run (``-m "not stress"``) switches that harvest off; ``-m stress`` keeps it, for exploration.
    """
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

ROOT = Path(__file__).resolve().parent.parent
SYNTHETIC = ROOT / "data" / "synthetic"
#: real measured files shipped with the project (MIT, from ladisk/pyuff; see data/real/README.md)
REAL = ROOT / "data" / "real"


@pytest.fixture
def synthetic_dir() -> Path:
    return SYNTHETIC


@pytest.fixture
def real_dir() -> Path:
    return REAL


@pytest.fixture(scope="session")
def dask_cluster(tmp_path_factory):
    """A real ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1: (address, folder, processes)."""
    from daskcluster import cluster

    yield from cluster(tmp_path_factory)
