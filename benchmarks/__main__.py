"""Run every benchmark and write ``benchmarks/REPORT.md`` with its plots.

Usage::

    python -m benchmarks [--quick] [--runs N] [--trials N] [--only NAME ...] [--out PATH]

Runs, in order: the five speed ratios of issue 19 (``bench_speed``: SDOF identify
against a bare least-squares fit, 1000 channels against sdypy-EMA, the stability map
against numpy's eigenvalues, the demo scene against the import floor, a 100 000-line
noisy FRF against a minute), identification against the Cramér–Rao bound over damping, noise
and resolution (``bench_identify``), 1 and 1000 channels, the calibration of every
method's standard errors (``bench_calibration``) and of the whole chain from time
records (``bench_chain``), FRF estimation from time records and side by side with pyFRF
(``bench_estimate``, ``bench_pyfrf``), file reading
(``bench_io``), the counterweight optimiser against brute-force grids
(``bench_crank``), the ball-balancer stability map and simulations against plain
``solve_ivp`` (``bench_adb``), batches of files on Dask against one process
looping (``bench_batch``), and the demo scene end to end (``python -m
balancer run`` as a subprocess).  sdypy-EMA, when importable, is run side by side
on the same FRFs (optional; never a dependency).

Timings are medians of ``--runs`` runs with their min–max spread.  The report
states the machine, the versions and the date; plots are written beside it.
A benchmark module that fails is reported as failed, and the others still run.
"""
from __future__ import annotations

import argparse
import contextlib
import datetime as dt
import importlib
import io
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
MODULES = ("bench_identify", "bench_io", "bench_crank", "bench_adb")
METHOD_COLOURS = {"halfpower": "tab:orange", "circle": "tab:green", "nls": "tab:blue", "sdypy-EMA": "tab:red"}


# --------------------------------------------------------------------------- helpers
@dataclass
class Timing:
    """Median and spread of repeated wall-clock timings, s."""

    samples: list[float] = field(default_factory=list)

    @property
    def median(self) -> float:
        return statistics.median(self.samples) if self.samples else float("nan")

    def text(self, unit: str = "s", scale: float = 1.0, digits: int = 3) -> str:
        """``median [min–max] unit`` (n runs)."""
        if not self.samples:
            return "n/a"
        lo, hi = min(self.samples) * scale, max(self.samples) * scale
        return f"{_num(self.median * scale, digits)} [{_num(lo, digits)}–{_num(hi, digits)}] {unit}"


def _num(value: float, digits: int = 3) -> str:
    """Plain notation for timings: 2940 rather than 2.94e+03."""
    return f"{value:.0f}" if abs(value) >= 10 ** (digits - 1) else f"{value:.{digits}g}"


def time_runs(function: Callable[[], object], runs: int) -> tuple[Timing, object]:
    """Call ``function`` ``runs`` times; the timings and the last value."""
    timing, value = Timing(), None
    for _ in range(runs):
        start = time.perf_counter()
        value = function()
        timing.samples.append(time.perf_counter() - start)
    return timing, value


def capture(function: Callable[[], object]) -> tuple[str, float, str | None]:
    """Run a benchmark's ``main`` with stdout captured: (text, seconds, error or None)."""
    buffer = io.StringIO()
    start = time.perf_counter()
    error = None
    with contextlib.redirect_stdout(buffer), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            function()
        except Exception:  # a failing benchmark is reported, the others still run
            error = traceback.format_exc(limit=3)
    return buffer.getvalue(), time.perf_counter() - start, error


def version_of(name: str) -> str:
    try:
        return str(importlib.import_module(name).__version__)
    except Exception:
        return "not installed"


def git_commit() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                             timeout=10)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def machine_section() -> str:
    """Machine, versions and date, as a markdown list."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    lines = [
        f"- date: {dt.datetime.now(dt.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}",
        f"- machine: {platform.platform()}, {cpu}, {os.cpu_count()} CPUs",
        f"- versions: Python {platform.python_version()}, numpy {version_of('numpy')}, scipy {version_of('scipy')}, "
        f"h5py {version_of('h5py')}, matplotlib {version_of('matplotlib')}, pyuff {version_of('pyuff')}, "
        f"modalbal {version_of('modal')} (commit {git_commit()})",
    ]
    return "\n".join(lines)


def fenced(text: str) -> str:
    return "```text\n" + text.rstrip() + "\n```"


# --------------------------------------------------------------------------- identification
def identify_section(trials: int, runs: int, quick: bool, plots: list[str]) -> str:
    """SDOF grid against the CRLB, per-method timing spread, 1000 channels, plots."""
    from benchmarks import bench_identify as bi

    zetas = (0.01, 0.2) if quick else (0.001, 0.01, 0.05, 0.2)
    noises = (0.0, 0.01) if quick else (0.0, 0.001, 0.01, 0.05)
    resolutions = (3, 10) if quick else (1, 3, 10, 100)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = bi.sdof_grid(trials, zetas, noises, resolutions)
    out = [f"### SDOF receptance, fn = 100 Hz, {trials} trials per cell\n",
           "Median |relative error| of fn and ζ over the trials, the same over the Cramér–Rao bound "
           "(0.6745·CRLB is the median |error| of an efficient estimator; 1 = efficient; n/a without noise), "
           "and the median time per fit.\n",
           "| ζ | noise | L | method | fn err | fn/CRLB | ζ err | ζ/CRLB | µs/fit |", "|---|---|---|---|---|---|---|---|---|"]
    for z, p, lines, method, fe, fr, ze, zr, us in rows:
        out.append(f"| {z:g} | {p:g} | {lines:g} | {method} | {fe:.2e} | {fr:.2f} | {ze:.2e} | {zr:.2f} | {us:.0f} |")
    out.append("")
    out.append(_method_timing(runs))
    out.append("")
    out.append(_many_channels(runs))
    out.append("")
    out.append(_peer_section(runs))
    plots.extend(_identify_plots(rows))
    return "\n".join(out)


def _reference_case():
    from modal.synthetic import add_noise, modal_frf

    fn, zeta = 100.0, 0.01
    bw = 2 * zeta * fn
    f = np.arange(fn - 3 * bw, fn + 3 * bw + bw / 20, bw / 10)
    return add_noise(modal_frf(f, [fn], [zeta], [1.0]), 0.01, seed=1), (float(f[0]), float(f[-1]))


def _method_timing(runs: int) -> str:
    """Time per fit of each method on one reference case, median over runs of 50 fits."""
    from modal import identify

    frf, band = _reference_case()
    out = ["### Time per fit, reference case (ζ = 0.01, 1 % noise, L = 10, one band)\n",
           f"Each run times 50 fits; median over {runs} runs [min–max].\n",
           "| method | µs per fit | ζ estimate |", "|---|---|---|"]
    for method in ("halfpower", "circle", "nls"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            timing, result = time_runs(lambda m=method: [identify(frf, m, bands_hz=[band]) for _ in range(50)], runs)
        out.append(f"| {method} | {timing.text('µs', 1e6 / 50)} | {result[-1][0].damping_ratio:.5f} (truth 0.01) |")
    return "\n".join(out)


def _thousand_channels():
    from modal.synthetic import add_noise, modal_frf

    rng = np.random.default_rng(1)
    fn = np.array([50.0, 120.0, 300.0])
    zeta = np.array([0.01, 0.02, 0.03])
    const = rng.standard_normal((1000, 3)) + 0.05j * rng.standard_normal((1000, 3))
    f = np.linspace(0, 400, 2001)
    return add_noise(modal_frf(f, fn, zeta, const, kind="accelerance"), 0.01, seed=2), fn, zeta


def _many_channels(runs: int) -> str:
    """1 and 1000 channels (3 modes, 2001 lines, accelerance, 1 % noise)."""
    from modal import identify

    frf, fn, zeta = _thousand_channels()
    one = frf.channel(0)
    out = ["### 1 and 1000 channels (3 modes, 2001 lines, accelerance, 1 % noise)\n",
           f"Median of {runs} runs [min–max]; worst relative error over the three modes.\n",
           "| channels | method | time | max fn err | max ζ err |", "|---|---|---|---|---|"]
    for label, data in (("1", one), ("1000", frf)):
        for method in ("halfpower", "circle", "nls"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    timing, result = time_runs(lambda m=method, d=data: identify(d, m), runs)
                except Exception as exc:  # noqa: BLE001 - reported in the table
                    out.append(f"| {label} | {method} | failed: {type(exc).__name__}: {exc} | | |")
                    continue
            fe = max(abs(m.natural_frequency_hz / fn[i] - 1) for i, m in enumerate(result.modes[:3]))
            ze = max(abs(m.damping_ratio / zeta[i] - 1) for i, m in enumerate(result.modes[:3]))
            out.append(f"| {label} | {method} | {timing.text('s')} | {fe:.1e} | {ze:.1e} |")
    return "\n".join(out)


def _peer_section(runs: int) -> str:
    """sdypy-EMA side by side on the same FRFs, when it is importable."""
    try:
        import sdypy.EMA as ema  # noqa: F401  (sdypy-EMA >= 0.26)
    except Exception:
        try:
            import pyEMA as ema  # noqa: F401  (older name)
        except Exception:
            return ("### sdypy-EMA\n\nsdypy-EMA is not installed in this environment: the side-by-side run was "
                    "skipped (it is optional and not a dependency; `pip install sdypy-EMA` to include it).")
    version = getattr(ema, "__version__", "?")
    where = Path(getattr(ema, "__file__", "?")).resolve()
    inside = str(where).startswith(sys.prefix)
    out = [f"### sdypy-EMA {version} side by side (same FRFs)\n",
           "sdypy-EMA: LSCF poles (model order 30) and the stable poles nearest the true frequencies "
           "(`get_poles`, `select_closest_poles`; no modal constants). modalbal: `identify(frf, 'nls')`, "
           "which also returns modal constants, k, c, m and standard errors. "
           f"sdypy-EMA imported from {'this environment' if inside else 'a directory on PYTHONPATH outside the project environment'} "
           "(optional, never a dependency). "
           f"Median of {runs} runs [min–max]; worst relative error over the three modes.\n",
           "| case | tool | time | max fn err | max ζ err |", "|---|---|---|---|---|"]
    import inspect

    from modal import identify

    # sdypy-EMA renamed frf_type to frf_form (the old name warns)
    kind_keyword = "frf_form" if "frf_form" in inspect.signature(ema.Model).parameters else "frf_type"
    frf, fn, zeta = _thousand_channels()
    for label, data in (("1 channel", frf.channel(0)), ("1000 channels", frf)):
        h = np.atleast_2d(data.response)
        freq = data.frequency_hz

        def run_peer():
            model = ema.Model(h, freq, lower=10, upper=390, pol_order_high=30, **{kind_keyword: "accelerance"})
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
                model.get_poles(show_progress=False)
                model.select_closest_poles(list(fn))
            return model

        try:
            timing, model = time_runs(run_peer, runs)
            nat = np.asarray(model.nat_freq, float)
            xi = np.asarray(model.nat_xi, float)
            fe = max(abs(nat[np.argmin(abs(nat - f0))] / f0 - 1) for f0 in fn)
            ze = max(abs(xi[np.argmin(abs(nat - f0))] / z0 - 1) for f0, z0 in zip(fn, zeta))
            out.append(f"| {label} | sdypy-EMA | {timing.text('s')} | {fe:.1e} | {ze:.1e} |")
        except Exception as exc:  # noqa: BLE001
            out.append(f"| {label} | sdypy-EMA | failed: {type(exc).__name__}: {str(exc)[:80]} | | |")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            timing, result = time_runs(lambda d=data: identify(d, "nls"), runs)
        fe = max(abs(m.natural_frequency_hz / fn[i] - 1) for i, m in enumerate(result.modes[:3]))
        ze = max(abs(m.damping_ratio / zeta[i] - 1) for i, m in enumerate(result.modes[:3]))
        out.append(f"| {label} | modalbal nls | {timing.text('s')} | {fe:.1e} | {ze:.1e} |")
    return "\n".join(out)


def _identify_plots(rows: Sequence[tuple]) -> list[str]:
    """Error against run time per method, and a Pareto view (ζ error/CRLB against time)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files = []
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    for ax, index, label in ((axes[0], 4, "median |fn error| (relative)"),
                             (axes[1], 6, "median |ζ error| (relative)")):
        for method in ("halfpower", "circle", "nls"):
            pts = np.array([(r[8], r[index]) for r in rows if r[3] == method and np.isfinite(r[index])])
            if pts.size:
                ax.scatter(pts[:, 0], np.maximum(pts[:, 1], 1e-17), s=18, alpha=0.75, label=method,
                           color=METHOD_COLOURS[method])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per fit (µs)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.suptitle("SDOF grid: every (ζ, noise, L) cell, error against run time per method")
    path = HERE / "identify_error_vs_time.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    files.append(path.name)

    fig, ax = plt.subplots(figsize=(6.5, 4.5), constrained_layout=True)
    noisy = [r for r in rows if r[1] > 0 and np.isfinite(r[7])]
    pts_all = []
    for method in ("halfpower", "circle", "nls"):
        pts = np.array([(r[8], r[7]) for r in noisy if r[3] == method])
        if pts.size:
            ax.scatter(pts[:, 0], pts[:, 1], s=18, alpha=0.6, label=method, color=METHOD_COLOURS[method])
            med = np.median(pts, axis=0)
            ax.scatter(*med, s=160, marker="*", edgecolor="k", color=METHOD_COLOURS[method], zorder=5)
            pts_all.append((method, *med))
    if pts_all:
        front = pareto_front([(t, e) for _, t, e in pts_all])
        xs, ys = zip(*sorted(front))
        ax.plot(xs, ys, "k--", lw=1, label="Pareto front (method medians)")
    ax.axhline(1.0, color="grey", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("time per fit (µs)")
    ax.set_ylabel("median |ζ error| / (0.6745 CRLB)  (1 = efficient)")
    ax.set_title("Pareto view, noisy cells (stars: method medians)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    path = HERE / "identify_pareto.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    files.append(path.name)
    return files


def pareto_front(points: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    """Points not dominated in (time, error): nothing else is at least as fast and as accurate.

    Parameters
    ----------
    points : sequence of (time, error)

    Returns
    -------
    list of (time, error)
        The non-dominated points, in input order.
    """
    front = []
    for i, (t, e) in enumerate(points):
        dominated = any((t2 <= t and e2 <= e) and (t2 < t or e2 < e) for j, (t2, e2) in enumerate(points) if j != i)
        if not dominated:
            front.append((t, e))
    return front


# --------------------------------------------------------------------------- crank plot
def crank_plot(runs: int, plots: list[str]) -> str:
    """Excess of the true peak force over the exact optimum against run time: exact vs grids."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from benchmarks.bench_crank import MECH, SPEED_RPM
    from balancer.compressor.crank import grid_search_counterweight, max_shaking_force, optimal_counterweight

    t_exact, opt = time_runs(lambda: optimal_counterweight(MECH, SPEED_RPM), runs)
    rows = [("exact", t_exact, 0.0)]
    r = MECH.crank_radius_m
    for n, step in ((11, 5.0), (21, 2.0), (51, 1.0), (101, 1.0), (201, 0.5)):
        ks, radii = np.linspace(0, 1, n), np.linspace(0, r, n)
        theta = np.deg2rad(np.arange(0.0, 360.0, step))
        timing, res = time_runs(lambda: grid_search_counterweight(MECH, SPEED_RPM, ks, radii, theta),
                                max(1, min(runs, 3)))
        m_c = MECH.rotating_mass_kg + res.k * MECH.reciprocating_mass_kg
        excess = max_shaking_force(MECH, SPEED_RPM, m_c, res.counterweight_radius_m) - opt.max_force_n
        rows.append((f"grid {n}x{n}, {step:g} deg", timing, excess))
    fig, ax = plt.subplots(figsize=(6.5, 4.2), constrained_layout=True)
    for label, timing, excess in rows:
        y = max(excess, 1e-12)
        ax.errorbar(timing.median, y, xerr=[[timing.median - min(timing.samples)], [max(timing.samples) - timing.median]],
                    fmt="o", capsize=3, label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time (s), median with min–max")
    ax.set_ylabel("true peak − F* (N)  (exact drawn at 1e-12)")
    ax.set_title(f"Counterweight optimum vs (k, r_c, θ) grids; F* = {opt.max_force_n:.6f} N", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    path = HERE / "crank_error_vs_time.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    plots.append(path.name)
    lines = ["| method | time | true peak − F* (N) |", "|---|---|---|"]
    lines += [f"| {label} | {timing.text('s')} | {excess:.2e} |" for label, timing, excess in rows]
    return "\n".join(lines)


# --------------------------------------------------------------------------- other modules
def module_section(name: str, argv: list[str]) -> tuple[str, str]:
    """Run ``benchmarks.<name>.main(argv)``; (markdown, status line)."""
    try:
        module = importlib.import_module(f"benchmarks.{name}")
    except Exception as exc:  # noqa: BLE001
        return f"`{name}` could not be imported: {type(exc).__name__}: {exc}", f"{name}: import failed"
    text, seconds, error = capture(lambda: module.main(argv))
    head = f"`python -m benchmarks.{name} {' '.join(argv)}`".replace(" `", "`") + f" (whole run {seconds:.1f} s):\n"
    body = fenced(text) if text.strip() else "(no output)"
    if error:
        return head + "\n" + body + "\n\nFailed:\n" + fenced(error), f"{name}: FAILED"
    return head + "\n" + body, f"{name}: ok ({seconds:.0f} s)"


def demo_section(runs: int, plots: list[str]) -> str:
    """The demo scene end to end, as a user runs it (a subprocess per run)."""
    scene = ROOT / "data" / "synthetic" / "demo_scene.toml"
    timing = Timing()
    failures = []
    with tempfile.TemporaryDirectory() as folder:
        for run in range(runs):
            out = Path(folder) / f"demo{run}.h5"
            start = time.perf_counter()
            proc = subprocess.run([sys.executable, "-m", "balancer", "run", str(scene), "--out", str(out)], cwd=ROOT,
                                  capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"})
            elapsed = time.perf_counter() - start
            if proc.returncode != 0:
                failures.append(f"run {run}: exit {proc.returncode}: {proc.stderr.strip()[-300:]}")
            else:
                timing.samples.append(elapsed)
    lines = ["`python -m balancer run data/synthetic/demo_scene.toml --out <tmp>` as a subprocess (interpreter start, "
             "imports, FRF file → identification → ball-balancer stability map and run-up → counterweight and mounts → "
             f"archive and plots), {runs} runs: **{timing.text('s')}**."]
    lines += [f"- failed {f}" for f in failures]
    return "\n".join(lines)


def stress_summary() -> str:
    """The last stress-run result, copied from docs/stress.md."""
    path = ROOT / "docs" / "stress.md"
    if not path.is_file():
        return "docs/stress.md is missing."
    text = path.read_text(encoding="utf-8")
    marker = "## Last result"
    if marker not in text:
        return "See docs/stress.md."
    section = text.split(marker, 1)[1].split("\n## ", 1)[0].strip()
    return f"From docs/stress.md (run with `.venv/bin/python -m pytest -m stress`):\n\n{section}"


# --------------------------------------------------------------------------- speed ratios
def speed_section(runs: int, quick: bool) -> str:
    """The five ratios of issue 19 (``benchmarks.bench_speed``), also printed to stdout."""
    from benchmarks import bench_speed

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = bench_speed.run(sorted(bench_speed.GOALS), 3 if quick else runs, 60.0 if quick else 180.0)
    text = bench_speed.table(results)
    print(machine_section() + "\n\n" + text, flush=True)
    before = HERE / "speed_before.md"
    return ("`python -m benchmarks.bench_speed` (each ratio measured in this run; goal 2's peer is the optional "
            "`bench` extra):\n\n" + text
            + ("\n\n" + before.read_text(encoding="utf-8").strip() if before.is_file() else ""))


# --------------------------------------------------------------------------- main
def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes (a smoke run of a minute or two)")
    parser.add_argument("--runs", type=int, default=5, help="repetitions for every median (default 5)")
    parser.add_argument("--trials", type=int, default=50, help="noise trials per SDOF grid cell (default 50)")
    parser.add_argument("--only", nargs="+", choices=["speed", "identify", "calibration", "global", "estimate", "io",
                                                      "crank", "adb", "influence", "batch", "demo"],
                        help="run only these sections")
    parser.add_argument("--out", type=Path, default=HERE / "REPORT.md", help="report file (default benchmarks/REPORT.md)")
    parser.add_argument("--refresh-stress", action="store_true",
                        help="only rewrite the report's stress-run section from docs/stress.md")
    args = parser.parse_args(argv)
    os.environ.setdefault("MPLBACKEND", "Agg")
    if args.refresh_stress:
        text = args.out.read_text(encoding="utf-8")
        head = text.split("\n## Stress run\n", 1)[0]
        args.out.write_text(head + "\n## Stress run\n\n" + stress_summary() + "\n", encoding="utf-8")
        print(f"[benchmarks] refreshed the stress section of {args.out}", file=sys.stderr)
        return 0
    wanted = set(args.only or ["speed", "identify", "calibration", "global", "estimate", "io", "crank", "adb",
                               "influence", "batch",
                               "demo"])
    runs = max(1, args.runs)
    started = time.perf_counter()
    plots: list[str] = []
    status: list[str] = []
    sections: list[tuple[str, str]] = []

    def section(title: str, make: Callable[[], str], key: str) -> None:
        print(f"[benchmarks] {title} ...", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        try:
            body = make()
            status.append(f"{key}: ok ({time.perf_counter() - t0:.0f} s)")
        except Exception:  # noqa: BLE001 - the report says what failed
            body = "Failed:\n" + fenced(traceback.format_exc(limit=4))
            status.append(f"{key}: FAILED")
        sections.append((title, body))

    if "speed" in wanted:
        section("Speed against the floor: the five ratios of issue 19", lambda: speed_section(runs, args.quick), "bench_speed")
    if "identify" in wanted:
        section("Identification: methods against the Cramér–Rao bound, 1 and 1000 channels",
                lambda: identify_section(5 if args.quick else args.trials, runs, args.quick, plots), "bench_identify")

    def run_module(name: str, argv_: list[str]) -> str:
        body, line = module_section(name, argv_)
        status.append(line)
        return body

    if "calibration" in wanted:
        sections.append(("Calibration of the standard errors (issue 21)",
                         run_module("bench_calibration", ["--seeds", "50" if args.quick else "200"])))
        sections.append(("Calibration of the chain, time records to modes",
                         run_module("bench_chain", ["--records", "20" if args.quick else "80", "--cells", "all"])))
    if "global" in wanted:
        sections.append(("Global identification (pLSCF + joint refinement) against sdypy-EMA",
                         run_module("bench_global", ["--runs", str(runs), "--seeds", "2" if args.quick else "5"])))
    if "estimate" in wanted and (HERE / "bench_estimate.py").is_file():
        sections.append(("FRFs from time data: estimate time and identification on estimates",
                         run_module("bench_estimate", ["--quick"] if args.quick else [])))
    if "estimate" in wanted:
        sections.append(("FRF estimation side by side with pyFRF: run time, error, lab mistakes",
                         run_module("bench_pyfrf", ["--rounds", str(runs)])))
    if "influence" in wanted and (HERE / "bench_influence.py").is_file():
        sections.append(("Field balancing: influence-coefficient corrections", run_module("bench_influence", [])))
    if "io" in wanted:
        io_args = ["--runs", str(runs)] + (["--channels", "100"] if args.quick else [])
        sections.append(("File reading and writing (1000 channels × 2001 lines per format)",
                         run_module("bench_io", io_args)))
    if "crank" in wanted:
        body = run_module("bench_crank", [])
        try:
            body += "\n\nError against time (plotted in crank_error_vs_time.png):\n\n" + crank_plot(runs, plots)
        except Exception:  # noqa: BLE001
            body += "\n\nThe crank plot failed:\n" + fenced(traceback.format_exc(limit=3))
        sections.append(("Counterweight optimiser against brute-force grids", body))
    if "adb" in wanted:
        if (HERE / "bench_adb.py").is_file():
            sections.append(("Ball balancer: stability map, batched simulation and stiff drag against plain solve_ivp",
                             run_module("bench_adb", ["--quick"] if args.quick else [])))
        else:
            sections.append(("Ball balancer", "benchmarks/bench_adb.py is not present; skipped."))
    if "batch" in wanted:
        batch_args = ["--runs", str(min(runs, 3))] + (["--files", "60"] if args.quick else [])
        sections.append(("Batches of files on Dask (modal batch): files per second and workers",
                         run_module("bench_batch", batch_args)))
    if "demo" in wanted:
        section("Demo scene end to end", lambda: demo_section(min(runs, 3) if args.quick else runs, plots), "demo")

    total = time.perf_counter() - started
    doc = ["# Benchmark report", "",
           f"Written by `python -m benchmarks{' --quick' if args.quick else ''}"
           f"{' --runs ' + str(args.runs) if args.runs != 5 else ''}` in {total / 60:.1f} min. "
           "Timings are medians of several runs with the [min–max] spread; errors are against the known truth "
           "of synthetic data.", "", "## Machine, versions, date", "", machine_section(), "",
           "## Sections run", "", *[f"- {s}" for s in status], ""]
    if plots:
        doc += ["## Plots", ""] + [f"![{p}]({p})" for p in plots] + [""]
    for title, body in sections:
        doc += [f"## {title}", "", body, ""]
    doc += ["## Stress run", "", stress_summary(), ""]
    args.out.write_text("\n".join(doc), encoding="utf-8")
    print(f"[benchmarks] wrote {args.out} ({total:.0f} s)", file=sys.stderr)
    return 0 if all("FAILED" not in s for s in status) else 1


if __name__ == "__main__":
    sys.exit(main())
