"""One hammer record whose FRF changes part way through: false alarms and detection of the estimate's warning.

Run ``python -m benchmarks.bench_hit_change [--records N] [--takes]``.

Three modes (40, 95 and 170 Hz; ζ 3, 2 and 1.5 %) seen by two accelerometers, hits 3-3.5 s apart (jittered, as
a hand's are: hits in step with the mains would make its hum look like a change with the force) at 2048 Hz,
forces scattered by 25 % (log-normal) and pulse widths by 10 %, each hit's modal constants by ``scatter`` (a
hand-held hammer never hits the same spot twice), white noise on the force and the responses (fractions of
their peaks), optionally 0.5 % mains hum at 50 Hz on the responses and AC coupling (τ = 0.3 s) on every channel.
Every record goes through ``modal.estimate_frf(..., impact=True, window="force")``; a record counts when the
warning "the hits' FRF changes between hit ..." (:func:`modal.estimate.levels.change_dependence`) is raised.

False alarms: one point throughout. Detection: from hit n/2 + 1 on, sensor 2's first modal constant is
multiplied by ``change`` (a sensor sliding towards a node or knocked loose), or every constant of both sensors
changes (the hammer moved to another point).

``--takes``: each record two takes of ``hits`` hits joined (``take_lengths``, as files of one point), the
change (if any) within the second take from its hit n/2 + 1 on; counted are the change warning (each take of
4 hits or more tested for a change part way through) and the takes' warning ("the takes' FRFs differ").
"""
from __future__ import annotations

import argparse
import warnings

import numpy as np

import modal
from modal.synthetic_time import DigitalModes, impact_record

SAMPLE_RATE_HZ = 2048.0
NATURAL_FREQUENCY_HZ = [40.0, 95.0, 170.0]
DAMPING_RATIO = [0.03, 0.02, 0.015]
CONSTANTS = np.array([[2e-3, 1e-3, 0.6e-3], [2e-3, -0.8e-3, 0.3e-3]])
#: the other point's constants relative to the first's (the hammer moved)
MOVED = np.array([[0.6, -0.5, 1.3], [0.4, 0.9, -0.7]])
SPACING_S = 3.0
MESSAGE = "the hits' FRF changes between hit"


def hammer_record(rng, n_hits: int, scatter: float, change, hum: float, ac_s: float, force_noise: float,
                  response_noise: float) -> tuple[np.ndarray, np.ndarray]:
    """Force (n_samples,) and responses (2, n_samples): the structure's answer to each hit summed (it is
    linear), then the noise, hum and AC coupling. ``change`` multiplies the constants from hit n/2 + 1 on."""
    from scipy.signal import lfilter

    duration = SPACING_S * n_hits
    n = int(duration * SAMPLE_RATE_HZ)
    force, response = np.zeros(n), np.zeros((2, n))
    peaks = np.exp(rng.normal(0.0, 0.25, n_hits))
    for i in range(n_hits):
        constants = CONSTANTS * (1 + scatter * rng.standard_normal(CONSTANTS.shape))
        if change is not None and i >= n_hits // 2:
            constants = constants * change
        plant = DigitalModes(NATURAL_FREQUENCY_HZ, DAMPING_RATIO, constants, SAMPLE_RATE_HZ)
        hit = impact_record(plant, [0.5 + SPACING_S * i + rng.uniform(0.0, 0.5)], duration,
                            amplitude_n=100.0 * peaks[i], width_variation=0.1, seed=rng).record
        force += hit.signals[0]
        response += hit.signals[1:]
    force = force + force_noise * np.abs(force).max() * rng.standard_normal(n)
    response = response + response_noise * np.abs(response).max(axis=1, keepdims=True) * rng.standard_normal((2, n))
    if hum:
        t = np.arange(n) / SAMPLE_RATE_HZ
        phase = rng.uniform(0.0, 2 * np.pi, (2, 1))
        response = response + hum * np.abs(response).max(axis=1, keepdims=True) * np.sin(2 * np.pi * 50.0 * t + phase)
    if ac_s:
        a = np.exp(-1.0 / (ac_s * SAMPLE_RATE_HZ))
        b = [(1 + a) / 2, -(1 + a) / 2]
        force, response = lfilter(b, [1.0, -a], force), lfilter(b, [1.0, -a], response, axis=1)
    return force, response


def warned(records: int, first_seed: int, **case) -> int:
    """How many of ``records`` records (seeds from ``first_seed``) raise the change warning."""
    count = 0
    for seed in range(first_seed, first_seed + records):
        force, response = hammer_record(np.random.default_rng(seed), **case)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            modal.estimate_frf(force, response, SAMPLE_RATE_HZ, impact=True, window="force", kind="accelerance")
        count += any(MESSAGE in str(w.message) for w in caught)
    return count


def warned_in_takes(records: int, first_seed: int, change, **case) -> tuple[int, int]:
    """Of ``records`` two-take records: how many raise the change warning, and how many the takes' warning."""
    counts = [0, 0]
    for seed in range(first_seed, first_seed + records):
        rng = np.random.default_rng(seed)
        f1, r1 = hammer_record(rng, change=None, **case)
        f2, r2 = hammer_record(rng, change=change, **case)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            modal.estimate_frf(np.concatenate([f1, f2]), np.hstack([r1, r2]), SAMPLE_RATE_HZ, impact=True,
                               window="force", kind="accelerance", take_lengths=[f1.size, f2.size])
        said = [str(w.message) for w in caught]
        counts[0] += any(MESSAGE in m for m in said)
        counts[1] += any("the takes' FRFs differ" in m for m in said)
    return counts[0], counts[1]


def takes_table(n: int) -> None:
    """The two-take table (``--takes``)."""
    print("| hits per take | constants' scatter | hum, AC | force / response noise | change | change warned "
          "| takes differ |")
    print("|---|---|---|---|---|---|---|")
    for hits in (4, 6, 10):
        for scatter in (0.0, 0.03):
            for hum, ac in ((0.0, 0.0), (0.005, 0.3)):
                for force_noise, response_noise in ((0.002, 0.002), (0.01, 0.03)):
                    found, differ = warned_in_takes(n, 2000, None, n_hits=hits, scatter=scatter, hum=hum, ac_s=ac,
                                                    force_noise=force_noise, response_noise=response_noise)
                    print(f"| {hits} | {scatter:.0%} | {'yes' if hum else 'no'} | {force_noise:.1%} / "
                          f"{response_noise:.1%} | none | {found} of {n} | {differ} of {n} |", flush=True)
    for hits in (4, 6, 10):
        for change in (0.5, 0.7, 0.9):
            factor = np.array([[1.0, 1.0, 1.0], [change, 1.0, 1.0]])
            found, differ = warned_in_takes(n, 3000, factor, n_hits=hits, scatter=0.0, hum=0.0, ac_s=0.0,
                                            force_noise=0.002, response_noise=0.002)
            print(f"| {hits} | 0% | no | 0.2% / 0.2% | take 2, sensor 2, mode 1 × {change:g} | {found} of {n} | "
                  f"{differ} of {n} |", flush=True)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=20, help="records per case")
    parser.add_argument("--takes", action="store_true", help="two-take records, the change within the second")
    args = parser.parse_args(argv)
    n = args.records
    if args.takes:
        takes_table(n)
        return
    print("| hits | constants' scatter | hum, AC | force / response noise | change | warned |")
    print("|---|---|---|---|---|---|")
    case_index = 0
    for hits in (4, 6, 10):
        for scatter in (0.0, 0.03):
            for hum, ac in ((0.0, 0.0), (0.005, 0.3)):
                for force_noise, response_noise in ((0.002, 0.002), (0.01, 0.03)):
                    count = warned(n, 1000 * case_index, n_hits=hits, scatter=scatter, change=None, hum=hum, ac_s=ac,
                                   force_noise=force_noise, response_noise=response_noise)
                    case_index += 1
                    print(f"| {hits} | {scatter:.0%} | {'yes' if hum else 'no'} | {force_noise:.1%} / "
                          f"{response_noise:.1%} | none | {count} of {n} |", flush=True)
    for hits in (4, 6, 10):
        for change in (-1.0, 0.5, 0.7, 0.9, 0.95):
            factor = np.array([[1.0, 1.0, 1.0], [change, 1.0, 1.0]])
            count = warned(n, 77, n_hits=hits, scatter=0.0, change=factor, hum=0.0, ac_s=0.0, force_noise=0.002,
                           response_noise=0.002)
            print(f"| {hits} | 0% | no | 0.2% / 0.2% | sensor 2, mode 1 × {change:g} | {count} of {n} |", flush=True)
        count = warned(n, 77, n_hits=hits, scatter=0.03, change=MOVED, hum=0.005, ac_s=0.3, force_noise=0.01,
                       response_noise=0.03)
        print(f"| {hits} | 3% | yes | 1.0% / 3.0% | hammer moved | {count} of {n} |", flush=True)


if __name__ == "__main__":
    main()
