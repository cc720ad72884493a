"""The five speed ratios of issue 19, measured side by side in one run.

Run ``python -m benchmarks.bench_speed [--runs N] [--quick] [--only 1 2 3 4 5] [--timeout S]``.

1. One SDOF ``identify(frf, "nls")`` on 61 lines against a bare
   ``scipy.optimize.least_squares`` Levenberg–Marquardt fit of the same model
   (one mode ``A / (wn^2 - w^2 + 2 i zeta wn w)`` plus a complex offset) on the same
   data, started from a peak pick.  Goal: ratio <= 2.
2. 1000 channels x 3 modes x 2001 lines (accelerance, 1 % noise): sdypy-EMA's LSCF
   (order 30) + pole selection + LSFD against ``identify(frf, "nls")``.  sdypy-EMA is the
   optional ``bench`` extra (``pip install -e '.[bench]'``); without it the ratio is
   reported as skipped.  The two run interleaved, one call each per round, so that load
   changes of the machine hit both alike.  Goal: sdypy-EMA time / modalbal time >= 30.
3. 200 x 200 ball-balancer stability map (``stability_map(..., margin=False)``, the
   verdict path) against ``numpy.linalg.eigvals`` of the map's 40 000 8x8 first-order
   matrices.  Goal: ratio <= 0.1.  The eigenvalue map (``margin=True``, the default)
   is shown too.
4. The bundled demo scene (``python -m balancer run data/synthetic/demo_scene.toml``) as a
   subprocess against the import floor (a subprocess that only imports numpy, scipy,
   h5py, matplotlib, modal and balancer), runs interleaved.  Goal: ratio <= 2.
5. ``identify`` of two 100 000-line noisy FRFs, each in a subprocess with a time limit: a
   hammer test's H1 estimate (three hits, exponential window, noise above the hammer's
   band: the issue's pathological 8192-line case, larger) and a synthetic accelerance
   with noise rising 100-fold above the band.  Goal: well under a minute (the ratio, the
   worse of the two, is against 60 s).

Every timing is the median of ``--runs`` repetitions with the [min–max] spread; the
machine and the versions are printed first.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
GOALS = {1: ("SDOF identify / bare least_squares LM", "<= 2"),
         2: ("sdypy-EMA / modalbal, 1000 channels", ">= 30"),
         3: ("stability map / numpy eigvals, 40 000 8x8", "<= 0.1"),
         4: ("demo scene / import floor", "<= 2"),
         5: ("100 000-line noisy FRF identify / 60 s", "well under 1")}


def _median(samples: list[float]) -> float:
    return statistics.median(samples) if samples else float("nan")


def _spread(samples: list[float], scale: float = 1.0, unit: str = "s") -> str:
    if not samples:
        return "n/a"
    return (f"{_median(samples) * scale:.4g} [{min(samples) * scale:.4g}–{max(samples) * scale:.4g}] {unit}")


def _time(function, runs: int) -> tuple[list[float], object]:
    samples, value = [], None
    for _ in range(runs):
        start = time.perf_counter()
        value = function()
        samples.append(time.perf_counter() - start)
    return samples, value


# --------------------------------------------------------------------------- goal 1
def sdof_case():
    """The 61-line SDOF receptance of the issue (fn = 100 Hz, zeta = 0.01, 1 % noise, L = 10)."""
    from benchmarks.__main__ import _reference_case

    return _reference_case()


def bare_least_squares(frequency_hz: np.ndarray, response: np.ndarray):
    """The same one-mode model fitted by a bare ``least_squares(method="lm")`` from a peak pick."""
    from scipy.optimize import least_squares

    w = 2 * np.pi * frequency_hz
    peak = int(np.argmax(np.abs(response)))
    wn0 = w[peak]
    above = np.abs(response) >= np.abs(response[peak]) / np.sqrt(2)
    zeta0 = max(above.sum() * (w[1] - w[0]) / (2 * wn0), 1e-4)
    a0 = response[peak] * 2j * zeta0 * wn0 ** 2

    def residual(x):
        model = (x[2] + 1j * x[3]) / (x[0] ** 2 - w ** 2 + 2j * x[1] * x[0] * w) + (x[4] + 1j * x[5])
        r = model - response
        return np.concatenate([r.real, r.imag])

    return least_squares(residual, [wn0, zeta0, a0.real, a0.imag, 0.0, 0.0], method="lm")


def goal1(runs: int) -> dict:
    from modal import identify

    frf, band = sdof_case()
    f, h = frf.frequency_hz, np.asarray(frf.response).reshape(-1)
    batch = 50
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ours, result = _time(lambda: [identify(frf, "nls", bands_hz=[band]) for _ in range(batch)], runs)
    bare, fit = _time(lambda: [bare_least_squares(f, h) for _ in range(batch)], runs)
    ours = [t / batch for t in ours]
    bare = [t / batch for t in bare]
    zeta_ours = result[-1][0].damping_ratio
    zeta_bare = fit[-1].x[1]
    return {"ratio": _median(ours) / _median(bare),
            "text": (f"{f.size} lines: identify(frf, 'nls') {_spread(ours, 1e3, 'ms')}, bare least_squares LM "
                     f"{_spread(bare, 1e3, 'ms')}; zeta {zeta_ours:.5f} vs {zeta_bare:.5f} (truth 0.01)")}


# --------------------------------------------------------------------------- goal 2
def thousand_channels():
    """1000 channels x 3 modes x 2001 lines, accelerance, 1 % noise (the report's case)."""
    from benchmarks.__main__ import _thousand_channels

    return _thousand_channels()


def goal2(runs: int) -> dict:
    import contextlib
    import io

    from modal import identify

    frf, fn, zeta = thousand_channels()

    def mine():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return identify(frf, "nls")

    try:
        import sdypy.EMA as ema
    except Exception:  # noqa: BLE001 - optional peer
        ema = None
    h = np.atleast_2d(frf.response)

    def peer():
        model = ema.Model(h, frf.frequency_hz, lower=10, upper=390, pol_order_high=30, frf_form="accelerance")
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()), \
                warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model.get_poles(show_progress=False)
            model.select_closest_poles(list(fn))
            model.get_constants(whose_poles="own", FRF_ind="all")
        return model

    ours, theirs, result, model = [], [], None, None
    for _ in range(runs):  # interleaved, so that load changes hit both alike
        t, result = _time(mine, 1)
        ours += t
        if ema is not None:
            t, model = _time(peer, 1)
            theirs += t
    fe = max(abs(m.natural_frequency_hz / fn[i] - 1) for i, m in enumerate(result.modes[:3]))
    ze = max(abs(m.damping_ratio / zeta[i] - 1) for i, m in enumerate(result.modes[:3]))
    text = f"modalbal identify(frf, 'nls') {_spread(ours)} (max fn err {fe:.1e}, max zeta err {ze:.1e})"
    if ema is None:
        return {"ratio": None, "text": text + "; sdypy-EMA not installed (optional `bench` extra): skipped"}
    nat, xi = np.asarray(model.nat_freq, float), np.asarray(model.nat_xi, float)
    pfe = max(abs(nat[np.argmin(abs(nat - f0))] / f0 - 1) for f0 in fn)
    pze = max(abs(xi[np.argmin(abs(nat - f0))] / z0 - 1) for f0, z0 in zip(fn, zeta))
    return {"ratio": _median(theirs) / _median(ours),
            "text": text + f"; sdypy-EMA {ema.__version__} LSCF + LSFD {_spread(theirs)} (max fn err {pfe:.1e}, "
                           f"max zeta err {pze:.1e})"}


# --------------------------------------------------------------------------- goal 3
def goal3(runs: int) -> dict:
    import inspect

    from balancer.adb import ADBParameters, balanced_state, stability_map
    from balancer.adb.stability import _balanced_companion

    s1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
    speeds = np.linspace(0.3, 4.0, 200) * s1.natural_frequency_rad_s
    drags = np.geomspace(1e-6, 0.1, 200)
    members = [s1.replace(D=float(d)) for d in drags]
    matrices = _balanced_companion(members, speeds, [balanced_state(p)[2:4] for p in members])
    fast_available = "margin" in inspect.signature(stability_map).parameters
    eig_s, verdict_s, full_s = [], [], []
    fast = full = None
    for _ in range(runs):  # interleaved, so that load changes hit all three alike
        eig_s += _time(lambda: np.linalg.eigvals(matrices), 1)[0]
        if fast_available:
            t, fast = _time(lambda: stability_map(s1, speeds, "D", drags, margin=False), 1)
            verdict_s += t
        t, full = _time(lambda: stability_map(s1, speeds, "D", drags), 1)
        full_s += t
    text = (f"numpy eigvals of the map's {matrices.shape[0]} {matrices.shape[1]}x{matrices.shape[2]} matrices "
            f"{_spread(eig_s, 1e3, 'ms')}; eigenvalue map (margin=True) {_spread(full_s, 1e3, 'ms')} "
            f"= {_median(full_s) / _median(eig_s):.3g}x")
    if not fast_available:
        return {"ratio": _median(full_s) / _median(eig_s), "text": text + "; no margin=False option (before): "
                "the ratio is the eigenvalue map's"}
    same = int(np.sum(fast.stability_class == full.stability_class))
    left = int(np.sum(np.isfinite(fast.max_real_part_per_s)))
    return {"ratio": _median(verdict_s) / _median(eig_s),
            "text": text + f"; verdict map (margin=False) {_spread(verdict_s, 1e3, 'ms')}, same class at "
                           f"{same}/{full.stability_class.size} points, {left} points left to the eigenvalue path"}


# --------------------------------------------------------------------------- goal 4
#: what the demo imports (scipy.integrate and scipy.optimize: its run-up and its roots and minimum)
FLOOR = "import numpy, scipy, scipy.integrate, scipy.optimize, h5py, matplotlib, modal, balancer"


def goal4(runs: int) -> dict:
    scene = ROOT / "data" / "synthetic" / "demo_scene.toml"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    floor, demo = [], []
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        for run in range(runs):
            start = time.perf_counter()
            subprocess.run([sys.executable, "-c", FLOOR], cwd=ROOT, env=env, check=True, capture_output=True)
            floor.append(time.perf_counter() - start)
            start = time.perf_counter()
            proc = subprocess.run([sys.executable, "-m", "balancer", "run", str(scene), "--out",
                                   str(Path(folder) / f"demo{run}.h5")], cwd=ROOT, env=env, capture_output=True,
                                  text=True)
            demo.append(time.perf_counter() - start)
            if proc.returncode != 0:
                raise RuntimeError(f"demo failed: {proc.stderr[-500:]}")
    return {"ratio": _median(demo) / _median(floor),
            "text": f"demo {_spread(demo)}, import floor (`python -c \"{FLOOR}\"`) {_spread(floor)}"}


# --------------------------------------------------------------------------- goal 5
def noisy_long_frf(lines: int = 100_000, seed: int = 5):
    """A long hammer-test-like accelerance: four modes, noise 1 % in band rising 100x above it."""
    from modal.frf import FRF
    from modal.synthetic import modal_frf

    f = np.linspace(0.0, 5000.0, lines)
    clean = modal_frf(f, [180.0, 730.0, 1450.0, 2600.0], [0.02, 0.01, 0.015, 0.01],
                      [1.0, 0.6, 0.8 + 0.1j, 0.5], kind="accelerance")
    h = np.asarray(clean.response).reshape(-1)
    band_edge = 3000.0  # the hammer's band: the force spectrum falls away above it
    level = 0.01 * np.median(np.abs(h)) * np.where(f < band_edge, 1.0, 100.0 ** np.clip((f - band_edge) / 1000.0, 0, 1))
    rng = np.random.default_rng(seed)
    noisy = h + level * (rng.standard_normal(lines) + 1j * rng.standard_normal(lines)) / np.sqrt(2)
    return FRF(frequency_hz=f, response=noisy, kind="accelerance")


def hammer_h1(lines: int = 100_000, seed: int = 5):
    """A hammer test's H1 estimate with ``lines`` lines, as in the issue's pathological case.

    Three hits (1 ms half-sine pulses: the force spectrum is gone above ~1.5 kHz), four
    modes (180, 730, 1450, 2600 Hz; the last beyond the hammer's band), white noise on the
    measured acceleration, exponential window, ``fs`` = 10 kHz: above the band the estimate
    is noise.
    """
    import modal

    fs = 10_000.0
    segment = 2 * (lines - 1)
    n = 3 * segment + int(0.3 * fs)
    t = np.arange(n) / fs
    force = np.zeros(n)
    for start in (0.1, 0.1 + segment / fs, 0.1 + 2 * segment / fs):
        inside = (t >= start) & (t < start + 1e-3)
        force[inside] = 100.0 * np.sin(np.pi * (t[inside] - start) / 1e-3)
    fn = np.array([180.0, 730.0, 1450.0, 2600.0])
    zeta = np.array([0.02, 0.01, 0.015, 0.01])
    const = np.array([1.0, 0.6, 0.8, 0.5])
    wn = 2 * np.pi * fn
    wd = wn * np.sqrt(1 - zeta**2)
    tau = np.arange(int(2.0 * fs)) / fs  # 2 s of impulse response: every mode decayed to < 1e-10
    impulse = np.sum(const[:, None] / wd[:, None] * np.exp(-zeta[:, None] * wn[:, None] * tau)
                     * np.sin(wd[:, None] * tau), axis=0) / fs
    size = 1 << int(np.ceil(np.log2(n + impulse.size)))
    displacement = np.fft.irfft(np.fft.rfft(force, size) * np.fft.rfft(impulse, size), size)[:n]
    acceleration = np.gradient(np.gradient(displacement, 1 / fs), 1 / fs)
    rng = np.random.default_rng(seed)
    noisy = acceleration + 0.05 * np.std(acceleration) * rng.standard_normal(n)
    return modal.estimate_frf(force, noisy, fs, kind="accelerance", response_quantity="acceleration", impact=True,
                              segment_length=segment, window="exponential", exponential_decay_s=0.5,
                              pretrigger_s=0.05)


_GOAL5_CHILD = """
import sys, time, warnings
sys.path.insert(0, {root!r})
from benchmarks.bench_speed import {case}
import modal
frf = {case}()
warnings.simplefilter("ignore")
start = time.perf_counter()
result = modal.identify(frf)
print(time.perf_counter() - start, len(result.modes), " ".join(f"{{m.natural_frequency_hz:.1f}}" for m in result.modes))
"""


def _goal5_case(case: str, runs: int, timeout: float) -> tuple[float | None, str]:
    samples, found = [], ""
    for _ in range(max(1, min(runs, 2))):
        try:
            proc = subprocess.run([sys.executable, "-c", _GOAL5_CHILD.format(root=str(ROOT), case=case)], cwd=ROOT,
                                  capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return None, f"did not finish within the {timeout:.0f} s limit (ratio > {timeout / 60:.2g})"
        if proc.returncode != 0:
            return None, f"failed: {proc.stderr.strip()[-300:]}"
        seconds, count, *freqs = proc.stdout.split()
        samples.append(float(seconds))
        found = f"{count} modes at {', '.join(freqs[:8])} Hz (truth 180, 730, 1450, 2600)"
    return _median(samples) / 60.0, f"identify {_spread(samples)}; {found}"


def goal5(runs: int, timeout: float) -> dict:
    """Worst of two 100 000-line cases: a hammer test's H1 estimate and a synthetic noisy FRF."""
    hammer, hammer_text = _goal5_case("hammer_h1", runs, timeout)
    plain, plain_text = _goal5_case("noisy_long_frf", runs, timeout)
    ratios = [r for r in (hammer, plain) if r is not None]
    ratio = None if len(ratios) < 2 else max(ratios)
    return {"ratio": ratio, "text": f"hammer H1 estimate: {hammer_text}. Synthetic noisy accelerance: {plain_text}"}


# --------------------------------------------------------------------------- main
def run(goals, runs: int, timeout: float) -> dict[int, dict]:
    makers = {1: lambda: goal1(runs), 2: lambda: goal2(runs), 3: lambda: goal3(runs), 4: lambda: goal4(runs),
              5: lambda: goal5(runs, timeout)}
    out = {}
    for goal in goals:
        print(f"[bench_speed] goal {goal} ...", file=sys.stderr, flush=True)
        try:
            out[goal] = makers[goal]()
        except Exception as exc:  # noqa: BLE001 - reported in the table
            out[goal] = {"ratio": None, "text": f"failed: {type(exc).__name__}: {exc}"}
    return out


def table(results: dict[int, dict]) -> str:
    lines = ["| goal | ratio | target | measured |", "|---|---|---|---|"]
    for goal, res in results.items():
        name, target = GOALS[goal]
        ratio = "skipped" if res["ratio"] is None else f"{res['ratio']:.3g}"
        lines.append(f"| {goal}. {name} | {ratio} | {target} | {res['text']} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="repetitions per median (default 5)")
    parser.add_argument("--quick", action="store_true", help="3 runs")
    parser.add_argument("--only", type=int, nargs="+", choices=sorted(GOALS), help="only these goals")
    parser.add_argument("--timeout", type=float, default=180.0, help="time limit of goal 5, s (default 180)")
    args = parser.parse_args(argv)
    from benchmarks.__main__ import machine_section

    runs = 3 if args.quick else max(1, args.runs)
    print(machine_section())
    print()
    print(table(run(args.only or sorted(GOALS), runs, args.timeout)))


if __name__ == "__main__":
    main()
