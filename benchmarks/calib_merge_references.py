"""Calibration of the reference check of ``modal.merge_setups`` (how many modes' reference entries may disagree).

Run ``python -m benchmarks.calib_merge_references [--pairs 8] [--noise 0.1]`` from the repository root (about
4 s per pair on one core).

Each pair is two records of the anchor case of ``tests/support/ambient.py`` (six modes, 300 s, white sensor
noise of ``--noise`` of each channel's RMS, independent seeds) taken as two setups of five sensors with the
references at channels 0 and 5: setup 1 holds channels [0, 5, 1, 2, 3], setup 2 the references and three roving
channels. Setup 2 is taken right, with its second reference moved from channel 5 to each other channel (the
roving channels then the next free ones), and with its references swapped. For each, the table gives how many of
the modes both setups hold have reference entries with a MAC below ``REF_MAC``, and the smallest MAC of the modes
that pass. A merge is refused when at least half the modes (and two or more) disagree: the limit must never be
reached by the right setups.
"""
from __future__ import annotations

import argparse
import sys
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

import modal
from modal.operational.selection import shape_mac
from modal.operational.setups import REF_MAC, _near

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))  # the shared ambient cases
from support.ambient import anchor_record  # noqa: E402

SETUP1 = [0, 5, 1, 2, 3]
ROVING = [4, 6, 7, 1, 2, 3]


def _oma(signals):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return modal.oma(signals, 100.0, band_hz=(1.0, 30.0))


def reference_macs(first, second) -> list[float]:
    """The best reference-entry MAC of each mode of ``first`` that ``second`` holds at its frequency."""
    refs = [0, 1]
    out = []
    for mode in first:
        near = [other for other in second if _near(mode, other)]
        if near:
            out.append(max(shape_mac(mode.mode_shape[refs], other.mode_shape[refs]) for other in near))
    return out


def setups(seed: int, noise: float) -> dict[str, list[float]]:
    one = anchor_record(2 * seed, noise=noise, tones=False, duration_s=300)
    two = anchor_record(2 * seed + 1, noise=noise, tones=False, duration_s=300).signals
    first = _oma(one.signals[SETUP1])
    cases = {"right": [0, 5, 4, 6, 7], "swapped": [5, 0, 4, 6, 7]}
    for moved in (1, 2, 3, 4, 6, 7):
        cases[f"reference 5 moved to {moved}"] = [0, moved] + [c for c in ROVING if c != moved][:3]
    return {name: reference_macs(first, _oma(two[channels])) for name, channels in cases.items()}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=8)
    parser.add_argument("--noise", type=float, default=0.1)
    args = parser.parse_args(argv)
    counts: dict[str, Counter] = {}
    passing: dict[str, list[float]] = {}
    for seed in range(args.pairs):
        for name, macs in setups(seed, args.noise).items():
            bad = sum(m < REF_MAC for m in macs)
            counts.setdefault(name, Counter())[f"{bad}/{len(macs)}"] += 1
            passing.setdefault(name, []).extend(m for m in macs if m >= REF_MAC)
    print(f"{args.pairs} pairs, noise {args.noise:g}; disagreeing/matched modes: number of pairs; "
          f"smallest MAC that passes (>= {REF_MAC:g})")
    for name, counter in counts.items():
        refused = sum(n for key, n in counter.items()
                      if int(key.split("/")[0]) >= 2 and 2 * int(key.split("/")[0]) >= int(key.split("/")[1]))
        low = min(passing[name]) if passing[name] else float("nan")
        print(f"{name:26s} {dict(sorted(counter.items()))}  refused {refused}/{args.pairs}  min passing MAC {low:.3f}")


if __name__ == "__main__":
    main()
