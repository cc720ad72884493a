"""Seed 002's machine drive (``../shared/reference/crank_drive.md`` section 4), shared by the drive tests."""
from balancer.drive import belt_stage
from balancer.drive.shaft import PointLoad, ShaftGeometry, analyse_shaft

# Stage A of the report: 0.75 kW motor at 930 rpm, pulleys 100 -> 120 mm, C = 300 mm,
# service factor 1.3, A-section belt rated 1.275 kW, K_theta = 1 and K_L = 0.88 as printed,
# k2 = 0.217 kg/m, standard length 975 mm.
STAGE_A = dict(
    driver_diameter_m=0.100, driven_diameter_m=0.120, center_distance_m=0.300,
    driver_speed_rpm=930.0, power_w=750.0, service_factor=1.3,
)
STAGE_A_CATALOGUE = dict(
    per_belt_rating_w=1275.0, arc_correction_factor=1.0, length_correction_factor=0.88,
    centrifugal_factor_kg_per_m=0.217, standard_lengths_m=(0.900, 0.975, 1.050),
)
# (the report's length table is not legible; 975 mm is the length it picks as next above
# 945.73 mm, so the test series has no length between them)
# Stage B: 4 kW at 950 rpm (the calculation's speed), 140 -> 400 mm, C = 600 mm, B-section
# rated 2.75 kW, K_theta = 1, K_L = 0.99, k2 = 0.385 kg/m.
STAGE_B = dict(
    driver_diameter_m=0.140, driven_diameter_m=0.400, center_distance_m=0.600,
    driver_speed_rpm=950.0, power_w=4000.0, service_factor=1.3,
)
STAGE_B_CATALOGUE = dict(
    per_belt_rating_w=2750.0, arc_correction_factor=1.0, length_correction_factor=0.99,
    centrifugal_factor_kg_per_m=0.385,
)


def seed002_stage_a():
    return belt_stage(**STAGE_A, **STAGE_A_CATALOGUE, name="A")


def seed002_stage_b():
    return belt_stage(**STAGE_B, **STAGE_B_CATALOGUE, name="B")


# Shaft 1: bearings A at 0 and B at 1150 mm, pulley on a 150 mm overhang; belt load at 5 deg.
SHAFT_1 = ShaftGeometry(length_m=1.30, bearing_a_m=0.0, bearing_b_m=1.15)
# Shaft 2: A at 0, B at 845 mm; 2 x 3455 N at 805 and 885 mm; belt load at 1790 mm; all at 10 deg.
SHAFT_2 = ShaftGeometry(length_m=1.79, bearing_a_m=0.0, bearing_b_m=0.845)


def shaft_1(load_n: float = 235.88, torque_n_m: float = 0.0):
    return analyse_shaft(SHAFT_1, [PointLoad.from_direction(1.30, load_n, 5.0, "pulley")], torque_n_m)


def shaft_2(belt_load_n: float = 805.58):
    loads = [
        PointLoad.from_direction(0.805, 3455.0, 10.0, "F1"),
        PointLoad.from_direction(0.885, 3455.0, 10.0, "F2"),
        PointLoad.from_direction(1.790, belt_load_n, 10.0, "belt"),
    ]
    return analyse_shaft(SHAFT_2, loads)
