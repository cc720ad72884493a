"""False alarms and detection of the unrelated-channel warning (modal.estimate.unrelated and .rise).

Run ``python -m benchmarks.bench_unrelated [--repeats R] [--hammer-only]``.

A two-mode plant (40 and 95 Hz, ζ 3 and 2 %) at 2048 Hz, two response channels of the structure and a
third of noise alone (a dead sensor, its noise drawn from a generator independent of the force's and the
responses'). Every channel's noise is white, its standard deviation a multiple of that channel's clean
peak |value| (the dead channel's scale: the first response's peak). Random excitation: Hann, 50 % overlap,
1 s segments over 8, 16 or 64 s (15, 31 or 127 records), full band. Hammer: hits 2-2.4 s apart,
windows rect, force and exponential (τ 0.5 s), 1, 2, 3, 5 or 10 hits; and a lightly damped plant (ζ 0.7 and
0.5 %, exponential window only: each hit's record starts in the previous one's ringing), 2, 3 or 5 hits.
Variants: every channel AC-coupled (first-order high-pass, τ 0.3 s) and mains hum (50 Hz, its own phase on
each channel, at 0.5 % of the force's peak and 5 % of each response's, the dead one's too).

For each row (every window, plain and AC-coupled with hum, ``--repeats`` seeds each): the standard errors
above chance of the real channels' mean coherence and of their power's rise at the hits (their least; a
channel is warned when neither reaches :data:`~modal.estimate.unrelated.RELATED_SIGMAS`, resp.
:data:`~modal.estimate.rise.RISE_SIGMAS`) and of the dead channel's (their range; "-" where the test is not
made), and how often each was warned.
"""
from __future__ import annotations

import argparse
import itertools
import warnings

import numpy as np
from scipy import signal

import modal
import modal.estimate.core as core
from modal.estimate.rise import RISE_SIGMAS
from modal.estimate.unrelated import RELATED_SIGMAS
from modal.synthetic_time import DigitalModes, hammer_force

FS = 2048.0
FN, ZETA = np.array([40.0, 95.0]), np.array([0.03, 0.02])
CONSTANTS = np.array([[1.0, 0.6], [0.4, -0.9]])
#: a lightly damped version: each hit's record holds the previous hit's ringing (3-5 % of its start after 2 s, under
#: the 5 % at which a hit is rejected as a double hit)
LIGHT = np.array([0.007, 0.005])


def _high_pass(x: np.ndarray, tau_s: float) -> np.ndarray:
    """A first-order AC coupling of time constant ``tau_s`` (s) on each row."""
    a = np.exp(-1.0 / (tau_s * FS))
    return signal.lfilter([a, -a], [1.0, -a], x, axis=1)  # y[n] = a (y[n-1] + x[n] - x[n-1])


def _channels(kind: str, records: int, noise: float, ac: bool, hum: bool, seed: int, zeta=ZETA):
    """Force (n,), responses (3, n): two of the structure, the third noise alone."""
    plant = DigitalModes(FN, zeta, CONSTANTS, FS)
    rng = np.random.default_rng([seed, 1])  # force, scatter, measurement noise
    dead = np.random.default_rng([seed, 2])  # the dead channel's own generator
    if kind == "random":
        n = int((records + 1) / 2 * FS)
        force = rng.standard_normal(n)
        warm = int(5 / (np.min(zeta) * 2 * np.pi * FN.min()) * FS)
        full = force[np.arange(-warm, n) % n]
        clean = plant.respond(full, "acceleration")[:, warm:]
    else:
        spacing = 2.0
        hits = 0.5 + spacing * np.arange(records) + rng.uniform(0.0, 0.4, records)  # a hand's timing
        n = int((hits[-1] + spacing) * FS)
        peaks = 100.0 * np.exp(0.2 * rng.standard_normal(records))
        widths = 0.002 * np.exp(0.1 * rng.standard_normal(records))
        force = hammer_force(n, FS, hits, widths, peaks)
        clean = plant.respond(force, "acceleration")
    peak = np.max(np.abs(clean), axis=1)
    responses = clean + noise * peak[:, None] * rng.standard_normal(clean.shape)
    responses = np.vstack([responses, noise * peak[0] * dead.standard_normal(n)])
    force = force + 1e-3 * np.max(np.abs(force)) * rng.standard_normal(n)
    if hum:
        t = np.arange(n) / FS
        levels = np.concatenate([[np.max(np.abs(force))], peak, [peak[0]]])
        phases = rng.uniform(0, 2 * np.pi, 4)
        share = np.array([0.005, 0.05, 0.05, 0.05])
        hum_rows = (share * levels)[:, None] * np.sin(2 * np.pi * 50.0 * t[None, :] + phases[:, None])
        force = force + hum_rows[0]
        responses = responses + hum_rows[1:]
    if ac:
        both = _high_pass(np.vstack([force, responses]), 0.3)
        force, responses = both[0], both[1:]
    return force, responses


def _sigmas(kind: str, records: int, noise: float, window: str, ac: bool, hum: bool, seed: int, light: bool):
    """Standard errors above chance of the three responses' coherence and of their rise at the hits (none for
    random excitation or where a test is not made), and which were warned."""
    force, responses = _channels(kind, records, noise, ac, hum, seed, LIGHT if light else ZETA)
    seen, rises = [], []
    originals = core.chance_tests, core.rise_tests

    def record(*args, **kwargs):
        tests = originals[0](*args, **kwargs)
        seen.extend(tests)
        return tests

    def rise(*args, **kwargs):
        tests = originals[1](*args, **kwargs)
        rises.extend(tests)
        return tests

    core.chance_tests, core.rise_tests = record, rise
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if kind == "random":
                est = modal.estimate_frf(force, responses, FS, segment_length=int(FS), window=window)
            else:
                est = modal.estimate_frf(force, responses, FS, impact=True, window=window,
                                         segment_length=int(FS),
                                         exponential_decay_s=0.5 if window == "exponential" else None)
    finally:
        core.chance_tests, core.rise_tests = originals
    warned = {item["channel"] for item in est.unrelated}
    return ([t.sigmas for t in seen] or [np.nan] * 3, [t.sigmas for t in rises] or [np.nan] * 3,
            [f"response {o + 1}" in warned for o in range(3)], est.averages)


def _span(values) -> str:
    values = np.asarray(values, float)
    if np.all(np.isnan(values)):
        return "-"
    return f"{np.nanmin(values):+.1f} to {np.nanmax(values):+.1f}"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--hammer-only", action="store_true", help="skip the random-excitation rows")
    args = parser.parse_args(argv)
    variants = ((False, False), (True, True))
    rows = [] if args.hammer_only else [("random", r, z, ("hann",), False)
                                        for r, z in itertools.product((15, 31, 127), (0.1, 1.0, 3.0))]
    rows += [("hammer", r, z, ("rect", "force", "exponential"), False)
             for r, z in itertools.product((1, 2, 3, 5, 10), (0.01, 0.1, 0.3, 1.0))]
    rows += [("hammer", r, z, ("exponential",), True) for r, z in itertools.product((2, 3, 5), (0.01, 0.1, 0.3))]
    print(f"related above {RELATED_SIGMAS} (coherence) or {RISE_SIGMAS} (rise) standard errors; {args.repeats} "
          "repeats of each window, plain and AC-coupled with hum")
    print("| excitation | records | noise / peak | real: least coherence SE | real: least rise SE | real warned "
          "| dead: coherence SE | dead: rise SE | dead warned |")
    print("|---|---|---|---|---|---|---|---|---|")
    for kind, records, noise, windows, light in rows:
        real, real_up, dead, dead_up, real_warned, dead_warned, averages = [], [], [], [], 0, 0, set()
        for window, (ac, hum), seed in itertools.product(windows, variants, range(args.repeats)):
            sigmas, ups, warned, n = _sigmas(kind, records, noise, window, ac, hum, seed, light)
            averages.add(n)
            real.extend(sigmas[:2])
            real_up.extend(ups[:2])
            dead.append(sigmas[2])
            dead_up.append(ups[2])
            real_warned += sum(warned[:2])
            dead_warned += warned[2]
        least = "-" if np.all(np.isnan(real)) else f"{np.nanmin(real):.1f}"
        least_up = "-" if np.all(np.isnan(real_up)) else f"{np.nanmin(real_up):.1f}"
        name = kind + (", ζ 0.7/0.5 %" if light else "")
        print(f"| {name} | {'/'.join(map(str, sorted(averages)))} | {noise} | {least} | {least_up} | "
              f"{real_warned}/{len(real)} | {_span(dead)} | {_span(dead_up)} | {dead_warned}/{len(dead)} |",
              flush=True)


if __name__ == "__main__":
    main()
