"""What a run does not use is not imported."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: the modules the checks look for
WATCHED = ("balancer.influence", "matplotlib.figure", "scipy.optimize", "scipy.integrate", "scipy.linalg",
           "scipy.special", "scipy.stats", "h5py", "modal.synthetic", "modal.operational", "modal.operational.identify",
           "modal.batch.run")


@pytest.fixture(scope="module")
def fresh():
    """A fresh interpreter that forks a copy of itself for each check (support.forkserver), with numpy
    imported once: every check's code imports it (through modal or balancer), and it loads none of
    :data:`WATCHED` (asserted), so each check's modules are those of ``python -c CODE``."""
    from support.forkserver import ForkServer

    server = ForkServer(f"import numpy, sys\nassert not any(m in sys.modules for m in {WATCHED!r})")
    yield server
    server.close()


def _modules_after(fresh, code: str) -> dict:
    script = (f"import sys, json\nsys.path.insert(0, {str(ROOT)!r})\n{code}\n"
              f"print(json.dumps({{m: m in sys.modules for m in {WATCHED!r}}}))")
    proc = fresh.run(script, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_numerical_modules_do_not_import_matplotlib(fresh):
    loaded = _modules_after(fresh, "import balancer.scene.stages\nfrom balancer.adb import ADBParameters, stability_map"
                                   "\np = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=5e-4, k=1e4, c=20.0, D=1e-3)\n"
                                   "stability_map(p, [100.0, 200.0], 'D', [1e-3], margin=False)")
    assert loaded["matplotlib.figure"] is False and loaded["balancer.influence"] is False


def test_the_scene_command_line_leaves_the_influence_command_out(fresh):
    # `run` with a missing scene file: parsed, then a one-line error; the influence command's
    # modules (parser included) were never needed
    code = "import balancer.cli\nassert balancer.cli.main(['run', 'no_such_scene.toml']) == 1"
    assert _modules_after(fresh, code)["balancer.influence"] is False
    assert _modules_after(fresh, "import balancer.cli\nbalancer.cli.build_parser()")["balancer.influence"] is True


def test_the_scene_runner_imports_the_solvers_only_when_a_stage_needs_them(fresh):
    # `python -m balancer run` forks its plotting process before the first stage: what the parent has
    # imported by then is paid before both processes can work, so the solvers (scipy.optimize ~0.1 s,
    # scipy.integrate, scipy.linalg) wait until a stage calls them
    loaded = _modules_after(fresh, "import balancer.cli, balancer.scene.runner, balancer.scene.plots")
    assert not any(loaded[m] for m in ("scipy.optimize", "scipy.integrate", "scipy.linalg"))
    assert not loaded["h5py"]  # only the parent writes the archive, after the fork


def test_identification_and_its_checks_leave_scipy_special_and_stats_out(fresh):
    # scipy.special was half of the CPU time of ``import modal`` (0.65 s -> 0.33 s without it), and the checks'
    # quantiles imported it (0.38 CPU-s more per fitting process): they are modal.quantiles' own now
    loaded = _modules_after(fresh, "import modal, modal.cli, balancer.cli")
    assert loaded["scipy.special"] is False and loaded["scipy.stats"] is False
    for method in ("nls", "global"):
        # two close modes and noise: the hidden-mode, missing-peak and residual-whiteness checks all run
        loaded = _modules_after(
            fresh, "import warnings\nimport numpy as np\nimport modal\nwarnings.simplefilter('ignore')\n"
            "frf = modal.add_noise(modal.modal_frf(np.linspace(50, 150, 401), [90.0, 100.0, 104.0],"
            f" [0.01, 0.01, 0.02], [1.0, 0.5, 0.05]), 1e-3, seed=1)\nmodal.identify(frf, {method!r})")
        assert loaded["scipy.special"] is False and loaded["scipy.stats"] is False, method


def test_fits_of_frf_and_time_files_leave_scipy_linalg_optimize_and_special_out(fresh):
    # a fit imported scipy.linalg only for one_blas_thread to find its BLAS (0.2 CPU-s), and a time record's
    # H1 noise split scipy.optimize for a two-coefficient nnls (0.4 CPU-s more, special and linalg with it):
    # `modal fit hammer.csv --impact` went 1.45 -> 0.53 CPU-s, demo_frf.csv 0.55 -> 0.35 (medians of 10)
    for args in (["demo_frf.csv", "--json"], ["hammer.csv", "--impact", "--json"]):
        path = str(ROOT / "data" / "synthetic" / args[0])
        code = f"import modal.cli\nassert modal.cli.main([{'fit'!r}, {path!r}, *{args[1:]!r}]) == 0"
        loaded = _modules_after(fresh, code)
        assert not any(loaded[m] for m in ("scipy.linalg", "scipy.optimize", "scipy.special", "scipy.stats")), args


def test_a_least_squares_balancing_job_leaves_scipy_optimize_out(fresh):
    # scipy.optimize (the min-max correction's linear programs) was most of the import time of every
    # `balancer influence` run (0.86 -> 0.48 CPU-s per run): the default least-squares job does without it
    readings = ROOT / "data" / "synthetic" / "balance_readings.toml"
    run = f"import balancer.cli\nassert balancer.cli.main(['influence', {str(readings)!r}, '--json']) == 0"
    assert _modules_after(fresh, run)["scipy.optimize"] is False
    minmax = run.replace("'--json'", "'--json', '--method', 'minmax'")
    assert _modules_after(fresh, minmax)["scipy.optimize"] is True  # imported where the min-max correction runs


def test_the_modal_command_line_leaves_the_batch_runner_and_h5py_until_a_batch_or_archive_needs_them(fresh):
    # every `modal` command builds the batch command's parser; importing the batch package for it loaded
    # the runner, its archive store and h5py (0.70 -> 0.56 CPU-s per `modal fit ... --json`, medians of 7)
    script = (f"import sys, json\nsys.path.insert(0, {str(ROOT)!r})\nimport modal.cli\n"
              f"assert modal.cli.main(['fit', {str(ROOT / 'data' / 'synthetic' / 'demo_frf.csv')!r}, '--json']) == 0\n"
              "print(json.dumps(['h5py' in sys.modules, 'modal.batch.run' in sys.modules]))\n"
              "from modal.batch import fit_files, TABLE_COLUMNS\nimport modal.batch\n"
              "print(json.dumps(['h5py' in sys.modules, callable(fit_files), 'iter_fit' in dir(modal.batch)]))")
    proc = fresh.run(script, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    fitted, batch = (json.loads(line) for line in proc.stdout.strip().splitlines()[-2:])
    assert fitted == [False, False]
    assert batch == [True, True, True]  # the package's names still there, imported when used


def test_importing_the_toolkit_leaves_the_synthesisers_and_operational_analysis_until_a_name_is_used(fresh):
    # every scene run, plotting process, batch fitting process and Dask worker imports modal; none of them
    # synthesises records or runs operational analysis, whose modules it loaded with it
    loaded = _modules_after(fresh, "import modal, balancer.cli, balancer.scene.runner, modal.batch.fitproc")
    assert loaded["modal.synthetic"] is False and loaded["modal.operational"] is False
    used = ("import modal\nassert all(hasattr(modal, name) for name in modal.__all__)\n"
            "from modal import oma, add_noise\nassert modal.oma is oma and 'DigitalModes' in dir(modal)")
    loaded = _modules_after(fresh, used)
    assert loaded["modal.synthetic"] is True and loaded["modal.operational"] is True  # there when used


def test_the_command_line_parser_lists_the_operational_methods_without_loading_them(fresh):
    # `modal oma --method` lists the methods: every `modal` command builds that parser, and loading operational
    # analysis for it cost ~0.05 CPU-s a command
    loaded = _modules_after(fresh, "import modal.cli\nmodal.cli.build_parser()")
    assert loaded["modal.operational.identify"] is False
    loaded = _modules_after(fresh, "import modal.operational\nmodal.operational.oma")
    assert loaded["modal.operational.identify"] is True
