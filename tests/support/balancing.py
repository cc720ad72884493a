"""Readings shared by the field-balancing tests."""
import tomllib

import numpy as np

from support.paths import ROOT

READINGS = ROOT / "data" / "synthetic" / "balance_readings.toml"
STUDY_SCENE = ROOT / "data" / "synthetic" / "balance_scene.toml"


def polar(amplitude, phase_deg):
    return np.asarray(amplitude) * np.exp(1j * np.deg2rad(phase_deg))


# hsbalance (github.com/MagedMohamedTurk/Turbomachinery-Rotors-Balancing), README "Quick Example",
# taken there from B&K application note 17-227, table 2, example 6: two sensors, two planes,
# 1.15 g trial masses at 0 deg; readings "amplitude @ phase".  Its least-squares answer:
# 1.979 @ 236.2 and 1.071 @ 121.8 (printed to 3 and 1 decimals).
HS_INITIAL = polar([170.0, 53.0], [112.0, 78.0])
HS_RUNS = np.array([polar([235.0, 58.0], [94.0, 68.0]), polar([185.0, 77.0], [115.0, 104.0])])
HS_TRIALS = polar([1.15, 1.15], [0.0, 0.0])


def inline_scene(tmp_path, **extra):
    """A scene whose [balance] holds the bundled readings inline, with holes and an ISO check."""
    job = tomllib.loads(READINGS.read_text())
    section = {**job, "method": "minmax", "holes": 12,
               "iso": {"grade_mm_s": 2.5, "rotor_mass_kg": 100.0, "speed_rpm": 3000.0, "distances_m": [0.4, 0.6]}, **extra}
    return {"scene": {"name": "inline"}, "balance": section,
            "outputs": {"tables": ["balance"], "plots": ["balance"], "archive": True}}
