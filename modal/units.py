"""Unit helpers. Inside the toolkit everything is SI (rad/s, N, m, kg, s);
Hz, rpm and degrees exist only at the edges, and names say which."""
from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi
#: standard gravity, m/s² (the g of accelerometers' units and of weights)
STANDARD_GRAVITY_M_S2 = 9.80665


def hz_to_rad_s(frequency_hz):
    """Convert a frequency in Hz to an angular frequency in rad/s."""
    return np.multiply(frequency_hz, TWO_PI)


def rad_s_to_hz(omega_rad_s):
    """Convert an angular frequency in rad/s to Hz."""
    return np.divide(omega_rad_s, TWO_PI)


def rpm_to_rad_s(speed_rpm):
    """Convert a rotational speed in rev/min to rad/s."""
    return np.multiply(speed_rpm, TWO_PI / 60.0)


def rad_s_to_rpm(omega_rad_s):
    """Convert a rotational speed in rad/s to rev/min."""
    return np.multiply(omega_rad_s, 60.0 / TWO_PI)


def deg_to_rad(angle_deg):
    """Convert degrees to radians."""
    return np.deg2rad(angle_deg)


def rad_to_deg(angle_rad):
    """Convert radians to degrees."""
    return np.rad2deg(angle_rad)
