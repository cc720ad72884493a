"""Operational modal analysis against koma-python and pyOMA-2: time and error on the same ambient records.

Run ``python -m benchmarks.bench_oma [--records N] [--calibration N] [--speed]``.

The records are the anchor case of ``tests/support/ambient.py`` (six modes, eight sensors, a pair 1.9 %
apart, a weakly excited mode, machine tones at 1×/2×/3× of 4.8 Hz, 10 % noise, 1000 s at 100 Hz), seeds
9000+ (not used by any test). Each record goes to the three tools in turn, the order rotating from record
to record (interleaved); the times are medians over the records.

* modalbal: ``modal.oma(signals, 100, band_hz=(1, 30))`` (SSI-cov, automatic selection, tones apart).
* koma-python: ``covssi`` (i = 30 block rows, orders 2-80), ``find_stable_poles`` (s = 2, 5 % frequency,
  20 % damping, 0.3 MAC, band 1-30 Hz, ζ < 0.2), ``PoleClusterer`` (HDBSCAN, min_samples = min_cluster_size
  = 20) and ``group_clusters``, a mode per cluster at its median: the example of its documentation.
* pyOMA-2: ``SSI(method="cov", br=30, ordmax=80)`` on a ``SingleSetup`` and the automatic clustering
  ``Clustering(quick="Kvaale", freqlim=(1, 30))``.

A reported mode within 0.5 % of a true mode is that mode (a second one is a duplicate); one within 0.5 %
of a tone is a tone reported as a mode; any other is spurious. Errors: the largest relative frequency and
damping errors over the modes found.

``--calibration N``: z = error / reported standard error of modalbal's frequency and damping per mode
over N records (seeds 5000+, as the stress test), the table of their means and SDs; ``--channels C`` runs
it on the anchor case with C sensors along the frame (32 or 64: the many-channel layout, 8 references
chosen and fewer output block rows); ``--method plscf`` checks the cross-check estimator's errors instead.
``--tones N``: the tone test over N records of the anchor case (seeds 7000+; 5, 10 and 20 % noise in turn,
1000 s and 200 s, with and without the tones): structural modes called tones (false calls) or flagged
tone_like, tones missed or listed as modes flagged neither harmonic nor tone_like, and the lowest kurtosis any
structural mode's band reached against the limit.
``--light N``: the same on lightly damped structures (every mode at ζ = 0.1, 0.2 or 0.5 %, seeds 7500+), the
hard case for a rule on near-zero damping. ``--lone N``: tones with no structural mode near them (between modes,
at 50 Hz, above the highest mode; steady or wandering; running speed unknown or not theirs, seeds 7800+).
``--method`` chooses the estimator for each (fdd and efdd, which give no error bars, not for ``--calibration``).
``--speed``: modalbal's CPU and wall time on larger records (samples × channels). ``--thread-cpu``: on the same
records, the time an idle machine's cores would take, measured on a loaded one (:func:`thread_cpu`).
"""
from __future__ import annotations

import argparse
import contextlib
import inspect
import io
import os
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))  # the shared ambient cases

import modal  # noqa: E402
from support.ambient import FN, TONES, ZETA, anchor_record  # noqa: E402

BAND = (1.0, 30.0)


def run_ours(signals, fs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = modal.oma(signals, fs, band_hz=BAND)
    return [(m.natural_frequency_hz, m.damping_ratio) for m in result]


def run_koma(signals, fs):
    import koma.clustering
    import koma.oma

    orders = np.arange(2, 82, 2)
    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lambd, phi, pole_orders = koma.oma.covssi(signals.T, fs, 30, orders, showinfo=False)
        stab = koma.oma.find_stable_poles(lambd, phi, pole_orders, 2,
                                          stabcrit={"freq": 0.05, "damping": 0.2, "mac": 0.3},
                                          valid_range={"freq": [2 * np.pi * BAND[0], 2 * np.pi * BAND[1]],
                                                       "damping": [0, 0.2]}, indicator="freq")
        lambd_stab, phi_stab, orders_stab = stab[0], stab[1], stab[2]
        clusterer = koma.clustering.PoleClusterer(lambd_stab, phi_stab, orders_stab, min_cluster_size=20,
                                                  min_samples=20)
        args = clusterer.postprocess(prob_threshold=0.99, normalize_and_maxreal=True)
        if len(args[0]) == 0:
            return []
        xi, omega_n, *_ = koma.clustering.group_clusters(*args)
    return [(float(np.median(w)) / (2 * np.pi), float(np.median(z))) for w, z in zip(omega_n, xi)]


def run_pyoma(signals, fs):
    import logging

    from pyoma2.algorithms import SSI
    from pyoma2.algorithms.data.run_params import Clustering
    from pyoma2.setup import SingleSetup

    logging.disable(logging.CRITICAL)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()), \
            warnings.catch_warnings():
        warnings.simplefilter("ignore")
        setup = SingleSetup(signals.T.copy(), fs)
        alg = SSI(name="ssicov", method="cov", br=30, ordmax=80)
        setup.add_algorithms(alg)
        setup.run_by_name("ssicov")
        alg.add_clustering(Clustering(name="auto", quick="Kvaale", freqlim=BAND))
        alg.run_clustering("auto")
        res = alg.result.clustering_results["auto"]
    return [(float(f), float(z)) for f, z in zip(np.atleast_1d(res.Fn), np.atleast_1d(res.Xi))]


TOOLS = {"modalbal": run_ours, "koma-python": run_koma, "pyOMA-2": run_pyoma}


def score(found):
    """(modes found once, duplicates, spurious, tones as modes, max |df/f|, max |dζ/ζ|)."""
    f = np.array([x[0] for x in found]) if found else np.zeros(0)
    z = np.array([x[1] for x in found]) if found else np.zeros(0)
    used = np.zeros(f.size, bool)
    once = dup = 0
    ferr, zerr = [], []
    for fn, zeta in zip(FN, ZETA):
        near = np.flatnonzero(np.abs(f / fn - 1) < 0.005)
        used[near] = True
        if near.size:
            once += 1
            dup += near.size - 1
            best = near[np.argmin(np.abs(f[near] - fn))]
            ferr.append(abs(f[best] / fn - 1))
            zerr.append(abs(z[best] / zeta - 1))
    tone = np.zeros(f.size, bool)
    for t in TONES:
        tone |= np.abs(f / t - 1) < 0.005
    spurious = int(np.sum(~used & ~tone))
    return once, dup, spurious, int(np.sum(tone & ~used)), max(ferr, default=np.nan), max(zerr, default=np.nan)


def compare(n_records: int) -> str:
    names = list(TOOLS)
    times = {n: [] for n in names}
    scores = {n: [] for n in names}
    for r in range(n_records):
        rec = anchor_record(9000 + r, noise=0.1, tones=True)
        order = names[r % len(names):] + names[:r % len(names)]  # interleaved, rotating
        for name in order:
            t0 = time.perf_counter()
            try:
                found = TOOLS[name](rec.signals, rec.sample_rate_hz)
            except Exception as exc:  # noqa: BLE001 - a peer failing is a result of the benchmark
                print(f"{name} record {r}: failed ({type(exc).__name__}: {exc})", file=sys.stderr)
                found = []
            times[name].append(time.perf_counter() - t0)
            scores[name].append(score(found))
    lines = [f"{n_records} records (anchor case, 8 channels × 100 000 samples), interleaved; time = median",
             "", "| tool | time per record [s] | modes found (of 6) | duplicates | spurious | tones as modes | "
             "max freq. error | max damping error |", "|---|---|---|---|---|---|---|---|"]
    for name in names:
        s = np.array(scores[name], float)
        lines.append(f"| {name} | {statistics.median(times[name]):.2f} | {s[:, 0].min():.0f}-{s[:, 0].max():.0f} | "
                     f"{s[:, 1].sum():.0f} | {s[:, 2].sum():.0f} | {s[:, 3].sum():.0f} | "
                     f"{np.nanmax(s[:, 4]) * 100:.2f} % | {np.nanmax(s[:, 5]) * 100:.1f} % |")
    return "\n".join(lines)


def calibration(n_records: int, n_sensors: int = 8, method: str = "ssi", sample_rate_hz: float = 100.0) -> str:
    zf, zz, wrong = [], [], 0
    layout = None
    for seed in range(n_records):
        rec = anchor_record(5000 + seed, noise=0.1, tones=True, n_sensors=n_sensors, sample_rate_hz=sample_rate_hz)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = modal.oma(rec.signals, rec.sample_rate_hz, band_hz=BAND, method=method)
        layout = (len(result.settings["reference_channels"]), result.settings.get("block_rows"),
                  result.settings.get("block_cols"), result.settings.get("lags"), result.settings["decimation"])
        wrong += len(result) != FN.size or len(result.harmonics_hz) != TONES.size
        row_f, row_z = [], []
        for k, fn in enumerate(FN):
            near = [m for m in result if abs(m.natural_frequency_hz / fn - 1) < 0.005]
            m = near[0] if len(near) == 1 else None
            row_f.append(np.nan if m is None else (m.natural_frequency_hz - fn) / m.std.natural_frequency_hz)
            row_z.append(np.nan if m is None else (m.damping_ratio - ZETA[k]) / m.std.damping_ratio)
        zf.append(row_f), zz.append(row_z)
    zf, zz = np.array(zf), np.array(zz)
    shape = (f"{layout[1]} + 1 output block rows, {layout[2]} reference block columns; SSI" if method == "ssi"
             else f"half-spectra over {layout[3]} lags; pLSCF")
    lines = [f"z = error / reported standard error over {n_records} records (anchor case, {n_sensors} sensors, "
             f"{layout[0]} references, {shape}; sampled at {sample_rate_hz:g} Hz, decimated by {layout[4]}); "
             f"records with a mode missing, twice or a tone missing: {wrong}", "",
             "| mode [Hz] | ζ | z(f) mean | z(f) SD | z(ζ) mean | z(ζ) SD |", "|---|---|---|---|---|---|"]
    for k in range(FN.size):
        lines.append(f"| {FN[k]:g} | {ZETA[k]:g} | {np.nanmean(zf[:, k]):+.2f} | {np.nanstd(zf[:, k]):.2f} | "
                     f"{np.nanmean(zz[:, k]):+.2f} | {np.nanstd(zz[:, k]):.2f} |")
    return "\n".join(lines)


def _structural_kurtosis(result, rec, band):
    """(kurtosis, frequency Hz) of every structural mode of ``result`` (within 0.5 % of one of ``FN`` or ``fn``) on
    the band the tone test judges it on: 64 lines around the strongest line within its half-power band."""
    from modal.operational.inputs import prepare
    from modal.operational.tones import MIN_BANDWIDTH_TIME, band_kurtosis, strongest_line_hz

    prepared = prepare(rec.signals, rec.sample_rate_hz, band)
    out = []
    for m in result:
        channel = int(np.argmax(np.abs(m.mode_shape) / prepared.scale))  # as the test chooses it
        spectrum = np.fft.rfft(prepared.channel(channel))
        f, zeta = m.natural_frequency_hz, np.nan_to_num(m.damping_ratio)
        search = max(zeta * f, 3 * np.nan_to_num(m.std.natural_frequency_hz), 2 / prepared.duration_s)
        centre = strongest_line_hz(spectrum, prepared.n_samples, prepared.sample_rate_hz, f - search, f + search)
        out.append((band_kurtosis(spectrum, prepared.n_samples, prepared.sample_rate_hz, centre,
                                  MIN_BANDWIDTH_TIME / prepared.duration_s), f))
    return out


def _tone_scores(result, fn, tones):
    """(structural modes called tones, modes missing, tones missed, tones listed as modes flagged neither harmonic
    nor tone_like, structural modes flagged tone_like)."""
    found = np.array(result.harmonics_hz)
    called = sum(bool(np.any(np.abs(found / f - 1) < 0.005)) for f in fn)
    missing = sum(not any(abs(m.natural_frequency_hz / f - 1) < 0.005 for m in result) for f in fn)
    missed = sum(not np.any(np.abs(found / t - 1) < 0.005) for t in tones)
    unflagged = sum(any(abs(m.natural_frequency_hz / t - 1) < 0.005 and not {"harmonic", "tone_like"} & set(m.flags)
                        for m in result) for t in tones)
    flagged = sum(any(abs(m.natural_frequency_hz / f - 1) < 0.005 and "tone_like" in m.flags for m in result)
                  for f in fn)
    return called, missing, missed, unflagged, flagged


def tone_calls(n_records: int, method: str = "ssi") -> str:
    from modal.operational.tones import KURTOSIS_LIMIT

    false_calls = missed = listed_as_mode = records_with_tones = flagged = 0
    lowest = (np.inf, None)
    for r in range(n_records):
        noise = (0.05, 0.1, 0.2)[r % 3]
        duration = (1000.0, 200.0)[(r // 3) % 2]
        tones = r % 2 == 0
        rec = anchor_record(7000 + r, noise=noise, tones=tones, duration_s=duration)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = modal.oma(rec.signals, rec.sample_rate_hz, band_hz=BAND, method=method)
        called, _, miss, unflagged, like = _tone_scores(result, FN, TONES if tones else [])
        false_calls += called
        flagged += like
        if tones:
            records_with_tones += 1
            missed += miss
            listed_as_mode += unflagged
        for k, f in _structural_kurtosis(result, rec, BAND):
            if np.any(np.abs(f / FN - 1) < 0.005) and k < lowest[0]:
                lowest = (k, f"{f:.2f} Hz, seed {7000 + r}, {noise:.0%} noise, {duration:g} s")
    return "\n".join([f"tone test over {n_records} records ({method}; anchor case, seeds 7000+, 5/10/20 % noise, "
                      f"1000/200 s, tones in every other record)", "",
                      f"structural modes called tones: {false_calls} of {n_records * FN.size}; flagged tone_like: "
                      f"{flagged}",
                      f"tones missed: {missed} of {records_with_tones * TONES.size}; tones listed as unflagged modes: "
                      f"{listed_as_mode}",
                      f"lowest kurtosis of a structural mode's band: {lowest[0]:.2f} ({lowest[1]}); limit "
                      f"{KURTOSIS_LIMIT:g}"])


#: lightly damped cases: the anchor case's frames with every mode at one damping ratio
LIGHT_DAMPING = (0.001, 0.002, 0.005)


def light_calls(n_records: int, method: str = "ssi") -> str:
    """The tone test on lightly damped structures (the hard case for a rule on near-zero damping): the anchor
    case's shapes with every mode at ζ = 0.1, 0.2 or 0.5 % in turn, 1000 s and 200 s, with and without the
    tones (seeds 7500+). Per damping ratio: structural modes called tones or flagged tone_like, modes found
    neither as modes nor as tones, tones missed and listed as modes flagged neither harmonic nor tone_like, the
    lowest kurtosis of a structural mode's band and the fewest decay times ζ·2πf·T a mode holds in its record."""
    from modal.operational.tones import KURTOSIS_LIMIT
    from modal.synthetic import ambient_modal_response
    from support.ambient import FORCE, anchor_shapes

    table = {z: np.zeros(6) for z in LIGHT_DAMPING}
    lowest = {z: (np.inf, "") for z in LIGHT_DAMPING}
    for r in range(n_records):
        zeta = LIGHT_DAMPING[r % 3]
        duration = (1000.0, 200.0)[(r // 3) % 2]
        tones = (r // 6) % 2 == 0
        rec = ambient_modal_response(FN, np.full(FN.size, zeta), anchor_shapes(), 100.0, int(duration * 100),
                                     modal_force_std=FORCE, noise=0.1, tones_hz=TONES if tones else None,
                                     tone_rms=0.5, seed=7500 + r)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = modal.oma(rec.signals, rec.sample_rate_hz, band_hz=BAND, method=method)
        table[zeta][:5] += _tone_scores(result, FN, TONES if tones else [])
        table[zeta][5] += 1
        for k, f in _structural_kurtosis(result, rec, BAND):
            if np.any(np.abs(f / FN - 1) < 0.005) and k < lowest[zeta][0]:
                lowest[zeta] = (k, f"{f:.2f} Hz, seed {7500 + r}, {duration:g} s")
    lines = [f"lightly damped structures over {n_records} records ({method}; anchor shapes, every mode at one ζ, "
             "1000/200 s, tones in every other six; seeds 7500+)", "",
             "| ζ | records | fewest decays ζ·2πf·T | modes called tones | modes flagged tone_like | modes missing | "
             "tones missed | tones as unflagged modes | lowest kurtosis of a mode |", "|---|---|---|---|---|---|---|---|---|"]
    for z in LIGHT_DAMPING:
        called, missing, missed, unflagged, like, n = table[z]
        lines.append(f"| {100 * z:g} % | {n:.0f} | {z * 2 * np.pi * FN.min() * 200:.1f} (200 s) | {called:.0f} | "
                     f"{like:.0f} | {missing:.0f} | {missed:.0f} | {unflagged:.0f} | {lowest[z][0]:.2f} ({lowest[z][1]}) |")
    lines.append(f"\nkurtosis limit {KURTOSIS_LIMIT:g}")
    return "\n".join(lines)


def lone_calls(n_records: int, method: str = "ssi") -> str:
    """Tones with no structural mode near them (``tests/support/ambient.py``'s lone-tone case, 100 s, seeds
    7800+): a tone between modes far from any (55 Hz), at the mains frequency (50 Hz) or above the highest mode
    (160 Hz) in turn, steady or wandering by up to ±0.2 % or ±1 %, the running speed unknown or given as one the
    tone is no harmonic of (7.7 Hz). Per tone position: tones listed as tones, as modes flagged harmonic or
    tone_like, as modes flagged neither, or not found; structural modes called tones or missing."""
    from support.ambient import LONE_FN, lone_tone_record

    positions = (55.0, 50.0, 160.0)
    table = {p: np.zeros(7) for p in positions}
    for r in range(n_records):
        tone = positions[r % 3]
        wander = (0.0, 0.002, 0.01)[(r // 3) % 3]
        rotor = (None, 7.7)[(r // 9) % 2]
        signals, fs = lone_tone_record(tone, wander, 7800 + r)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = modal.oma(signals, fs, band_hz=(5.0, 180.0), method=method, rotor_speed_hz=rotor)
        tolerance = 0.02 if method == "fdd" else 0.01  # FDD's peaks lie on its lines
        near = [m for m in result if abs(m.natural_frequency_hz / tone - 1) < tolerance]
        listed = any(abs(h / tone - 1) < 0.005 for h in result.harmonics_hz)
        flagged = bool(near) and all({"harmonic", "tone_like"} & set(m.flags) for m in near)
        table[tone] += [listed, not listed and flagged, not listed and bool(near) and not flagged,
                        not listed and not near,
                        sum(any(abs(h / f - 1) < tolerance for h in result.harmonics_hz) for f in LONE_FN),
                        sum(not any(abs(m.natural_frequency_hz / f - 1) < tolerance for m in result) for f in LONE_FN),
                        1]
    lines = [f"tones with no mode near them over {n_records} records ({method}; lone-tone case, 100 s, steady or "
             "wandering ±0.2 %/±1 %, running speed unknown or 7.7 Hz; seeds 7800+)", "",
             "| tone [Hz] | records | listed as tones | flagged modes | unflagged modes | not found | "
             "structural modes called tones | structural modes missing |", "|---|---|---|---|---|---|---|---|"]
    for p in positions:
        listed, flagged, unflagged, lost, called, missing, n = table[p]
        lines.append(f"| {p:g} | {n:.0f} | {listed:.0f} | {flagged:.0f} | {unflagged:.0f} | {lost:.0f} | {called:.0f} | "
                     f"{missing:.0f} |")
    return "\n".join(lines)


SPEED_RECORDS = ((100_000, 8, 100.0), (100_000, 64, 100.0), (1_000_000, 8, 100.0), (1_000_000, 64, 100.0),
                 (1_000_000, 64, 600.0))  # (samples, channels, rate [Hz]): the last decimated by 5 to the band first


def speed(runs: int = 3) -> str:
    """CPU and wall time of ``modal.oma`` per record size (median of ``runs`` after one warm-up call), SSI,
    band 1-30 Hz at 100 Hz (and one record at 600 Hz, decimated first), with one thread and with the default (every usable core, :mod:`modal.parallel`),
    interleaved. The header names the ``modal`` package measured: run this file with another tree's interpreter
    (``OTHER/.venv/bin/python OTHER/benchmarks/bench_oma.py --records 0 --speed`` from outside either tree) to
    time that tree's code on the same records."""
    from modal.parallel import usable_cores
    from modal.synthetic import ambient_modal_response

    threaded = "workers" in inspect.signature(modal.oma).parameters
    cores = usable_cores() if threaded else 1
    lines = [f"modal from {Path(modal.__file__).resolve().parent.parent}, OPENBLAS_NUM_THREADS="
             f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, {cores} usable core(s), median of {runs}, "
             f"load {os.getloadavg()[0]:.1f}", "",
             f"| samples × channels | rate [Hz] | band [Hz] | CPU, 1 thread [s] | wall, 1 thread [s] | CPU, {cores} threads [s] | "
             f"wall, {cores} threads [s] |", "|---|---|---|---|---|---|---|"]
    settings = [{"workers": 1}, {}] if threaded else [{}, {}]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        warm = ambient_modal_response(FN, ZETA, np.random.default_rng(1).standard_normal((8, 6)), 100.0, 20_000)
        modal.oma(warm.signals, 100.0, band_hz=BAND)
        for n, ch, rate in SPEED_RECORDS:
            rng = np.random.default_rng(1)
            shapes = rng.standard_normal((ch, 6))
            rec = ambient_modal_response(FN, ZETA, shapes, rate, n, noise=0.1, seed=2)
            times = [([], []) for _ in settings]
            for _ in range(runs):
                for (cpu, wall), kwargs in zip(times, settings):
                    c0, w0 = time.process_time(), time.perf_counter()
                    modal.oma(rec.signals, rate, band_hz=BAND, **kwargs)
                    cpu.append(time.process_time() - c0)
                    wall.append(time.perf_counter() - w0)
            cells = " | ".join(f"{statistics.median(cpu):.2f} | {statistics.median(wall):.2f}" for cpu, wall in times)
            lines.append(f"| {n} × {ch} | {rate:g} | {BAND[0]:g}-{BAND[1]:g} | {cells} |")
            del rec
    return "\n".join(lines)


def thread_cpu(runs: int = 3) -> str:
    """The CPU time on the critical path of ``modal.oma`` with every usable core, per record of :func:`speed`:
    the calling thread's CPU plus, for each pool of threads it starts (:mod:`modal.parallel`), the busiest
    thread's CPU (median of ``runs`` after one warm-up call).

    Each share and item is timed with ``time.thread_time()``, which counts only the CPU a thread was given: when
    other processes hold the cores the wall time measures them, this sum the code (an idle machine's wall time,
    memory bandwidth shared between the threads aside). Run it with another tree's interpreter, as :func:`speed`,
    to time that tree's code. (``run_beside``'s side thread counts in full, as if it ran after the caller's
    step beside it: an upper bound.)"""
    import importlib
    import threading

    import modal.parallel as parallel
    from modal.synthetic import ambient_modal_response

    pools: list[dict] = []

    def timed(function):
        def inner(*args):
            start = time.thread_time()
            try:
                return function(*args)
            finally:
                me = threading.get_ident()
                pools[-1][me] = pools[-1].get(me, 0.0) + time.thread_time() - start
        return inner

    def pooled(original, at):  # the pool's function (argument ``at``) timed on each thread, one record per call
        def inner(*args):
            pools.append({})
            args = list(args)
            args[at] = timed(args[at])
            return original(*args)
        return inner

    patched = {"split_over_threads": pooled(parallel.split_over_threads, 0),
               "map_over_threads": pooled(parallel.map_over_threads, 0), "run_beside": pooled(parallel.run_beside, 1)}
    modules = [importlib.import_module(f"modal.operational.{name}") for name in
               ("correlations", "identify", "inputs", "modes", "ssi", "tones")]
    saved = [(module, name, getattr(module, name)) for module in modules for name in patched if hasattr(module, name)]
    lines = [f"modal from {Path(modal.__file__).resolve().parent.parent}, "
             f"{parallel.usable_cores()} usable core(s), median of {runs}, load {os.getloadavg()[0]:.1f}", "",
             "| samples × channels | rate [Hz] | critical path [s] | calling thread [s] | pools' busiest threads [s] |",
             "|---|---|---|---|---|"]
    try:
        for module, name, _ in saved:
            setattr(module, name, patched[name])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for n, ch, rate in SPEED_RECORDS:
                rng = np.random.default_rng(1)
                rec = ambient_modal_response(FN, ZETA, rng.standard_normal((ch, 6)), rate, n, noise=0.1, seed=2)
                modal.oma(rec.signals, rate, band_hz=BAND)
                sums = []
                for _ in range(runs):
                    pools.clear()
                    start = time.thread_time()
                    modal.oma(rec.signals, rate, band_hz=BAND)
                    caller = time.thread_time() - start
                    me = threading.get_ident()
                    busiest = sum(max([t for thread, t in pool.items() if thread != me] or [0.0]) for pool in pools)
                    sums.append((caller + busiest, caller, busiest))
                total, caller, busiest = (statistics.median(column) for column in zip(*sums))
                lines.append(f"| {n} × {ch} | {rate:g} | {total:.3f} | {caller:.3f} | {busiest:.3f} |")
                del rec
    finally:
        for module, name, original in saved:
            setattr(module, name, original)
    return "\n".join(lines)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=10)
    parser.add_argument("--calibration", type=int, default=0)
    parser.add_argument("--channels", type=int, default=8)
    parser.add_argument("--method", choices=("ssi", "plscf", "fdd", "efdd"), default="ssi",
                        help="the estimator --calibration, --tones and --light check")
    parser.add_argument("--sample-rate", dest="sample_rate_hz", type=float, default=100.0,
                        help="the --calibration records' rate, Hz (above 120 Hz they are decimated to the band first)")
    parser.add_argument("--tones", type=int, default=0)
    parser.add_argument("--light", type=int, default=0)
    parser.add_argument("--lone", type=int, default=0)
    parser.add_argument("--speed", action="store_true")
    parser.add_argument("--thread-cpu", dest="thread_cpu", action="store_true")
    args = parser.parse_args(argv)
    if args.records:
        print(compare(args.records))
    if args.calibration:
        print()
        print(calibration(args.calibration, args.channels, args.method, args.sample_rate_hz))
    if args.tones:
        print()
        print(tone_calls(args.tones, args.method))
    if args.light:
        print()
        print(light_calls(args.light, args.method))
    if args.lone:
        print()
        print(lone_calls(args.lone, args.method))
    if args.speed:
        print()
        print(speed())
    if args.thread_cpu:
        print()
        print(thread_cpu())


if __name__ == "__main__":
    main()
