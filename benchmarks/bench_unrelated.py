"""False alarms and detection of the unrelated-channel warning (:mod:`modal.estimate.unrelated`).

Run ``python -m benchmarks.bench_unrelated [--repeats R]``.

A two-mode plant (40 and 95 Hz, ζ 3 and 2 %) at 2048 Hz, two response channels of the structure and a
third of noise alone (a dead sensor, its noise drawn from a generator independent of the force's and the
responses'). Every channel's noise is white, its standard deviation a multiple of that channel's clean
peak |value| (the dead channel's scale: the first response's peak). Random excitation: Hann, 50 % overlap,
1 s segments over 8, 16 or 64 s (15, 31 or 127 records), full band. Hammer: hits 2-2.4 s apart,
windows rect, force and exponential (τ 0.5 s), 3, 5 or 10 hits. Variants: every channel AC-coupled
(first-order high-pass, τ 0.3 s) and mains hum (50 Hz, its own phase on each channel, at 0.5 % of the
force's peak and 5 % of each response's, the dead one's too).

For each row (every window, plain and AC-coupled with hum, ``--repeats`` seeds each): the standard errors
above chance of the real channels (their least; the warning fires below
:data:`~modal.estimate.unrelated.RELATED_SIGMAS`) and of the dead channel (their range), and how often each
was warned.
"""
from __future__ import annotations

import argparse
import itertools
import warnings

import numpy as np
from scipy import signal

import modal
import modal.estimate.core as core
from modal.estimate.unrelated import RELATED_SIGMAS, chance_tests
from modal.synthetic_time import DigitalModes, hammer_force

FS = 2048.0
FN, ZETA = np.array([40.0, 95.0]), np.array([0.03, 0.02])
CONSTANTS = np.array([[1.0, 0.6], [0.4, -0.9]])


def _high_pass(x: np.ndarray, tau_s: float) -> np.ndarray:
    """A first-order AC coupling of time constant ``tau_s`` (s) on each row."""
    a = np.exp(-1.0 / (tau_s * FS))
    return signal.lfilter([a, -a], [1.0, -a], x, axis=1)  # y[n] = a (y[n-1] + x[n] - x[n-1])


def _channels(kind: str, records: int, noise: float, ac: bool, hum: bool, seed: int):
    """Force (n,), responses (3, n): two of the structure, the third noise alone."""
    plant = DigitalModes(FN, ZETA, CONSTANTS, FS)
    rng = np.random.default_rng([seed, 1])  # force, scatter, measurement noise
    dead = np.random.default_rng([seed, 2])  # the dead channel's own generator
    if kind == "random":
        n = int((records + 1) / 2 * FS)
        force = rng.standard_normal(n)
        warm = int(5 / (ZETA.min() * 2 * np.pi * FN.min()) * FS)
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


def _sigmas(kind: str, records: int, noise: float, window: str, ac: bool, hum: bool, seed: int):
    """Standard errors above chance of the three responses, and which were warned."""
    force, responses = _channels(kind, records, noise, ac, hum, seed)
    seen = []
    original = core.chance_tests

    def record(*args, **kwargs):
        tests = chance_tests(*args, **kwargs)
        seen.extend(tests)
        return tests

    core.chance_tests = record
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
        core.chance_tests = original
    warned = {item["channel"] for item in est.unrelated}
    return [t.sigmas for t in seen], [f"response {o + 1}" in warned for o in range(3)], est.averages


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    variants = ((False, False), (True, True))
    rows = [("random", r, z, ("hann",)) for r, z in itertools.product((15, 31, 127), (0.1, 1.0, 3.0))]
    rows += [("hammer", r, z, ("rect", "force", "exponential"))
             for r, z in itertools.product((3, 5, 10), (0.01, 0.1, 0.3, 1.0))]
    print(f"related above {RELATED_SIGMAS} standard errors; {args.repeats} repeats of each window, plain and "
          "AC-coupled with hum")
    print("| excitation | records | noise / peak | real channels: least SE above chance | real warned "
          "| dead channel: SE above chance | dead warned |")
    print("|---|---|---|---|---|---|---|")
    for kind, records, noise, windows in rows:
        real, dead, real_warned, dead_warned, averages = [], [], 0, 0, set()
        for window, (ac, hum), seed in itertools.product(windows, variants, range(args.repeats)):
            sigmas, warned, n = _sigmas(kind, records, noise, window, ac, hum, seed)
            averages.add(n)
            real.extend(sigmas[:2])
            dead.append(sigmas[2])
            real_warned += sum(warned[:2])
            dead_warned += warned[2]
        print(f"| {kind} | {'/'.join(map(str, sorted(averages)))} | {noise} | {min(real):.1f} | "
              f"{real_warned}/{len(real)} | {min(dead):+.1f} to {max(dead):+.1f} | {dead_warned}/{len(dead)} |",
              flush=True)


if __name__ == "__main__":
    main()
