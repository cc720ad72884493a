"""The papers' slider-cranks, shared by the crank tests (``../shared/reference/crank_drive.md``)."""
import numpy as np

from balancer.compressor.crank import SliderCrank, slider_crank_from_components

SPEED_000_RPM = 2950.0
R_000_M = 0.0119
DEG_GRID = np.deg2rad(np.arange(360.0))  # the paper's 1 deg angle grid


def seed000_mechanism() -> SliderCrank:
    """Seed 000's compressor, Table 1: m_A = 0.067, m_G = 0.044, m_B = 0.134 kg, a = 16.3 mm, l = 50 mm."""
    return slider_crank_from_components(
        crank_radius_m=R_000_M, rod_length_m=0.050, rod_mass_kg=0.044,
        rod_cg_to_crank_pin_m=0.0163, crank_pin_mass_kg=0.067, piston_mass_kg=0.134)


def seed004_mechanism() -> SliderCrank:
    """Seed 004's slider-crank: R = 35 mm, L = 140 mm."""
    return SliderCrank(0.035, 0.140, 0.55, 1.13)


def mass_written_out(mech: SliderCrank, k: float) -> float:
    """The counterweight mass m_rot + k m_rec, written out here rather than calling counterweight_mass, so
    the table tests do not depend on the function they could be checking."""
    return mech.rotating_mass_kg + k * mech.reciprocating_mass_kg
