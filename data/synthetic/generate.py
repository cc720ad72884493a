"""Make the small synthetic files the demo and the tests use (reproducible from the seed).

Run ``python data/synthetic/generate.py``; the files are committed, and a test
checks that running this again gives the same bytes.

demo_frf.csv
    Driving-point accelerance of a rotor rig hit with an impact hammer: the
    rotor's bending mode (M = 1.04 kg rotor with balls, k = 1e4 N/m,
    c = 20 N s/m: 15.61 Hz, ζ = 9.8 %) and two housing modes (120 Hz, 2 %;
    310 Hz, 1.5 %), 0.25 Hz lines up to 400 Hz, noise 0.5 % of max |H|.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SEED = 20261122

#: truth of the demo rig (SI)
RIG_MASS_KG = 1.04
RIG_STIFFNESS_N_PER_M = 1.0e4
RIG_DAMPING_N_S_PER_M = 20.0
HOUSING_FREQUENCY_HZ = (120.0, 310.0)
HOUSING_DAMPING_RATIO = (0.02, 0.015)
HOUSING_MODAL_CONSTANT = (0.35, 0.6)  # 1/kg
NOISE_LEVEL = 0.005


def demo_frf():
    """The demo FRF object (accelerance, one driving-point channel)."""
    from modal.synthetic import add_noise, modal_frf

    wn = np.sqrt(RIG_STIFFNESS_N_PER_M / RIG_MASS_KG)
    zeta = RIG_DAMPING_N_S_PER_M / (2 * np.sqrt(RIG_STIFFNESS_N_PER_M * RIG_MASS_KG))
    f = np.arange(1, 1601) * 0.25
    frf = modal_frf(
        f,
        [wn / (2 * np.pi), *HOUSING_FREQUENCY_HZ],
        [zeta, *HOUSING_DAMPING_RATIO],
        [1 / RIG_MASS_KG, *HOUSING_MODAL_CONSTANT],
        kind="accelerance",
        response_points=["1+X"],
        reference_points=["1+X"],
    )
    return add_noise(frf, NOISE_LEVEL, seed=SEED)


def main(out_dir: Path = HERE) -> list[Path]:
    from modal.io import write_frf

    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "demo_frf.csv"
    write_frf(demo_frf(), path)
    return [path]


if __name__ == "__main__":
    for written in main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE):
        print(written)
