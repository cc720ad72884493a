"""Scene sections shared by the scene tests."""

#: a one-stage V-belt drive on a two-bearing shaft (seed 002's machine, rounded)
DRIVE = {"motor_speed_rpm": 930.0, "power_w": 750.0, "service_factor": 1.3,
         "stages": [{"driver_diameter_m": 0.100, "driven_diameter_m": 0.120, "center_distance_m": 0.300,
                     "per_belt_rating_w": 1275.0}],
         "shaft": {"length_m": 1.30, "bearing_a_m": 0.0, "bearing_b_m": 1.15, "diameter_m": 0.025,
                   "rotor_position_m": 1.30, "rotor_mass_kg": 2.0, "youngs_modulus_pa": 205e9}}
