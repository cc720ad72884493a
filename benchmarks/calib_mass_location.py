"""Calibration of the mass-location check of mass-change scaling (``modal.flags.MAX_LOCATION_MISFIT``).

Run ``python -m benchmarks.calib_mass_location [--pairs 12]`` from the repository root (about a minute per
case and 12 pairs on one core).

The 4-mass chain of ``tests/modal/operational/test_scaling.py`` is recorded twice per pair (ambient response,
10 % sensor noise, independent seeds): as it is, and with one mass of 50, 150 or 300 g at a random channel.
Each pair is scaled with the mass given where it was added ("right") and at the next channel ("wrong"); the
table gives the misfit of the modes' shape changes in their errors (:func:`modal.operational.scaling.
_location_misfit`) over the pairs. Cases: 1500 s records with all four modes in the band, 300 s records, and
1500 s records with a band holding two of the four modes. The limit must stay above every "right" value.
"""
from __future__ import annotations

import argparse
import warnings

import numpy as np

import modal
from modal.flags import MAX_LOCATION_MISFIT
from modal.operational import scaling
from modal.synthetic import ambient_response, chain_matrices

MASSES_KG = np.array([2.0, 1.5, 1.0, 1.2])
SPRINGS_N_PER_M = np.array([8e3, 6e3, 5e3, 4e3])
SAMPLE_RATE_HZ = 200.0
CASES = {"all modes, 1500 s": (300_000, (1.0, 60.0)), "all modes, 300 s": (60_000, (1.0, 60.0)),
         "2 of 4 modes, 1500 s": (300_000, (1.0, 12.0))}


def _record(mass, damping, stiffness, added_kg, seed, samples, band_hz):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        signals = ambient_response(mass + np.diag(added_kg), damping, stiffness, SAMPLE_RATE_HZ, samples, noise=0.1,
                                   seed=seed).signals
        return modal.oma(signals, SAMPLE_RATE_HZ, band_hz=band_hz)


def misfit(before, after, added_kg) -> float:
    """The check's statistic for masses ``added_kg`` (one entry per channel, kg) given at their channels."""
    pairs = []
    for mode in before:
        other = scaling._pair(mode, after)
        if other is None:
            continue
        alpha2, p0, _, _ = scaling._scale(mode, other, added_kg)
        if np.isfinite(alpha2) and alpha2 > 0:
            pairs.append((mode, other, alpha2, p0, scaling._aligned(p0, np.asarray(other.mode_shape, complex)).real))
    return scaling._location_misfit(pairs, added_kg)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=12, help="pairs of records per case (default 12)")
    args = parser.parse_args(argv)
    mass, damping, stiffness = chain_matrices(MASSES_KG, SPRINGS_N_PER_M, 0.01)
    print(f"limit MAX_LOCATION_MISFIT = {MAX_LOCATION_MISFIT:g}; {args.pairs} pairs per case\n")
    print("| case | right: median | right: largest | wrong: median | wrong: smallest | wrong above the limit |")
    print("|---|---|---|---|---|---|")
    for name, (samples, band_hz) in CASES.items():
        right, wrong = [], []
        for k in range(args.pairs):
            rng = np.random.default_rng(k)
            channel, kg = int(rng.integers(4)), float(rng.choice([0.05, 0.15, 0.3]))
            added = np.zeros(4)
            added[channel] = kg
            before = _record(mass, damping, stiffness, np.zeros(4), 1000 + k, samples, band_hz)
            after = _record(mass, damping, stiffness, added, 2000 + k, samples, band_hz)
            right.append(misfit(before, after, added))
            wrong.append(misfit(before, after, np.roll(added, 1)))
        right, wrong = np.array(right), np.array(wrong)
        print(f"| {name} | {np.nanmedian(right):.2f} | {np.nanmax(right):.2f} | {np.nanmedian(wrong):.2f} | "
              f"{np.nanmin(wrong):.2f} | {np.sum(wrong > MAX_LOCATION_MISFIT)} of {np.sum(np.isfinite(wrong))} |")


if __name__ == "__main__":
    main()
