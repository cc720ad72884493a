"""Scene sections shared by the scene tests."""
import copy


#: a one-stage V-belt drive on a two-bearing shaft (seed 002's machine, rounded)
DRIVE = {"motor_speed_rpm": 930.0, "power_w": 750.0, "service_factor": 1.3,
         "stages": [{"driver_diameter_m": 0.100, "driven_diameter_m": 0.120, "center_distance_m": 0.300,
                     "per_belt_rating_w": 1275.0}],
         "shaft": {"length_m": 1.30, "bearing_a_m": 0.0, "bearing_b_m": 1.15, "diameter_m": 0.025,
                   "rotor_position_m": 1.30, "rotor_mass_kg": 2.0, "youngs_modulus_pa": 205e9}}

#: a two-mode synthetic accelerance (mode 1: 15.6 Hz, zeta 5 %, A = 0.96 1/kg), 0.2 % noise
SYNTH_FRF = {"synthetic": {"natural_frequency_hz": [15.6, 120.0], "damping_ratio": [0.05, 0.02],
                           "modal_constant": [0.96, 0.35], "kind": "accelerance", "f_min_hz": 0.0,
                           "f_max_hz": 200.0, "n_lines": 800, "noise": 0.002, "seed": 5}}
#: a Jeffcott rotor with the identified mode 1's k, c, M
ROTOR = {"M": "identified:mode1.mass", "k": "identified:mode1.stiffness", "c": "identified:mode1.damping",
         "e": 0.0005, "mass_includes_balls": True}
ADB = {"m": 0.02, "n": 2, "R": 0.05, "D": 0.001, "stability": {"speed_max_ratio": 3.0, "grid_points": 400}}
#: seed 000's compressor
COMPRESSOR = {"crank_radius_m": 0.0119, "rod_length_m": 0.05, "rotating_mass_kg": 0.096656,
              "reciprocating_mass_kg": 0.148344, "speed_rpm": 2950.0}


def scene(**sections):
    """A scene of the given sections (copied: tests may change them)."""
    return copy.deepcopy(sections)
