"""Stress: the automatic ball balancer over random physical parameters.

Parameters span rotor mass 0.1…100 kg, ball mass 1e-3…0.1 of it, 2…6 balls, race
radius 1 cm…0.5 m, unbalance 5…90 % of the balls' capacity ``n m R``, stiffness
1e2…1e7 N/m, support damping ratio 1e-3…0.3 and ball drag ratio ``D / (m R² ωn)``
1e-4…1e3 (the upper end is stiff drag: the ball time constant is 1e-3 of a period).

Properties:

* **Energy with the drive removed.**  At zero shaft speed nothing feeds energy in;
  support damping and ball drag only take it out, so ``E(t) <= E(0)``.  With the balls
  moving with the race at t = 0, ``E(0) = (M + n m) v0²/2 + k r0²/2`` and
  ``k r(t)²/2 <= E(t)``, hence ``r(t) <= sqrt(r0² + (M + n m) v0² / k)`` at every
  sample; no value of the run may be NaN or Inf.
* **Linear verdict against long simulations (n = 2).**  Where the balanced state's
  largest growth rate ``λ = max Re`` is clear (not marginal, ``|λ|`` above 100 times
  its rounding bound) a simulation started 1e-4 rad off the balanced state (a generic, not
  symmetric, perturbation of the two balls) and run
  for ``8 / |λ|`` (e^8 ≈ 3000 in amplitude) must decay (stable: the deviation ends
  below e^-6 of its start; the generic start and non-normal transients may cost e^2) or
  grow (unstable: the deviation exceeds e^4 times its start at some time; a generic start
  has at least e^-4 along the unstable mode).  Runs that would
  exceed ``MAX_REVOLUTIONS`` are not clear within the budget and are skipped
  (counted).
* **Near the boundary.**  At the refined ends of the stable speed intervals the
  verdict is marginal or the growth rate is within rounding of zero.

``-m stress`` draws many cases; the default run a few.
"""
from __future__ import annotations

import math
import os
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, note, seed, settings
from hypothesis import strategies as st

from balancer.adb import ADBParameters, balanced_stability, simulate, stable_speed_intervals
from modal.errors import ModalWarning, ParameterError

STRESS_SEED = int(os.environ.get("STRESS_SEED", "8"))
STRESS = settings(max_examples=int(os.environ.get("STRESS_EXAMPLES", "300")), deadline=None, database=None,
                  suppress_health_check=list(HealthCheck), print_blob=True)
FAST = settings(max_examples=4, deadline=None, database=None, derandomize=True,
                suppress_health_check=list(HealthCheck))
#: simulations longer than this many shaft revolutions are skipped (cost)
MAX_REVOLUTIONS = 4000.0
#: the integrator runs at rtol 1e-9; 1e-6 covers its accumulated error on a bound
ENERGY_RTOL = 1e-6


def log_uniform(lo: float, hi: float):
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda x: 10.0**x)


@st.composite
def adb_parameters(draw, n_balls=st.integers(2, 6)) -> ADBParameters:
    M = draw(log_uniform(0.1, 100.0))
    m = M * draw(log_uniform(1e-3, 0.1))
    n = draw(n_balls)
    R = draw(log_uniform(0.01, 0.5))
    e = draw(st.floats(0.05, 0.9)) * n * m * R / M
    k = draw(log_uniform(1e2, 1e7))
    total = M + n * m
    wn = math.sqrt(k / total)
    c = 2 * draw(log_uniform(1e-3, 0.3)) * math.sqrt(k * total)
    D = draw(log_uniform(1e-4, 1e3)) * m * R**2 * wn
    return ADBParameters(M=M, m=m, n=n, R=R, e=e, k=k, c=c, D=D)


def _finite_run(result) -> None:
    for name in ("time_s", "speed_rad_s", "rotor_x_m", "rotor_y_m", "rotor_u_m", "rotor_v_m", "amplitude_m",
                 "ball_angles_rad", "ball_rates_rad_s"):
        value = np.asarray(getattr(result, name))
        assert value.size and np.all(np.isfinite(value)), name


def check_energy(params: ADBParameters, r0: float, v0: float, direction: float, periods: float) -> None:
    note(repr(params))
    wn = params.natural_frequency_rad_s
    t_end = periods * 2 * math.pi / wn
    position = (r0 * math.cos(direction), r0 * math.sin(direction))
    velocity = (-v0 * math.sin(direction), v0 * math.cos(direction))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModalWarning)
        result = simulate(params, 0.0, t_end, initial_rotor_position_m=position, initial_rotor_velocity_m_s=velocity,
                          compare_without_balls=False)
    _finite_run(result)
    bound = math.sqrt(r0**2 + params.total_mass_kg * v0**2 / params.k)
    # at every sample, so also at the end (a separate check of the last sample, as there was,
    # is implied; E(t) <= E(0) is the whole statement the amplitudes allow: the result
    # carries no rotor velocity from which E(t) itself could be checked to decrease)
    assert np.max(result.amplitude_m) <= bound * (1 + ENERGY_RTOL), (np.max(result.amplitude_m), bound)


ENERGY_ARGS = (adb_parameters(), log_uniform(1e-6, 1e-2), log_uniform(1e-6, 1.0), st.floats(0.0, 2 * math.pi),
               st.floats(1.0, 20.0))


@pytest.mark.stress
@pytest.mark.stress_quick
@seed(STRESS_SEED)
@STRESS
@given(*ENERGY_ARGS)
def test_stress_energy_bound_without_drive(params, r0, v0, direction, periods):
    check_energy(params, r0, v0, direction, periods)


@FAST
@given(*ENERGY_ARGS)
def test_energy_bound_without_drive(params, r0, v0, direction, periods):
    check_energy(params, r0, v0, direction, periods)


def _deviation(result, balanced: np.ndarray, R: float) -> np.ndarray:
    """Distance from the balanced state: ball angles (rad, wrapped) and rotor offset / R."""
    dphi = np.angle(np.exp(1j * (result.ball_angles_rad - balanced[None, :])))
    return np.sqrt(np.sum(dphi**2, axis=1) + (result.rotor_u_m**2 + result.rotor_v_m**2) / R**2)


def check_verdict(params: ADBParameters, speed_ratio: float, start: tuple[float, float]) -> None:
    note(repr(params))
    speed = speed_ratio * params.natural_frequency_rad_s
    lin = balanced_stability(params, [speed])
    growth = float(lin.max_real_part_per_s[0])
    bound = float(lin.rounding_bound_per_s[0])
    assert np.isfinite(growth) and np.all(np.isfinite(lin.eigenvalues_per_s))
    note(f"speed ratio {speed_ratio:.4g}, growth {growth:.4g} 1/s, rounding bound {bound:.3g}, "
         f"class {int(lin.stability_class[0])}")
    if lin.stability_class[0] == 0 or abs(growth) < 100 * bound:
        event("verdict: marginal (not simulated)")
        return
    t_end = 8.0 / abs(growth)
    if t_end * speed / (2 * math.pi) > MAX_REVOLUTIONS:
        event("verdict: margin not clear within the revolution budget (skipped)")
        return
    balanced = lin.ball_angles_rad
    # a generic start: a perturbation symmetric in the two balls stays in the symmetric
    # subspace (an invariant set) and never sees an antisymmetric unstable mode
    sign, ratio = start
    delta = 1e-4 * sign * np.array([1.0, -ratio])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModalWarning)
        result = simulate(params, speed, t_end, initial_ball_angles_rad=balanced + delta,
                          compare_without_balls=False, n_samples=801)
    _finite_run(result)
    dev = _deviation(result, balanced, params.R)
    # linear prediction for the least stable mode over 8 / |λ|: a factor e^{±8} (2981). The
    # start is generic, not along that mode: its share of the start and the non-normal
    # transients of the others may cost a factor e^2 when stable (the others decay faster)
    # and e^4 when unstable (a start with >= 1.8 % along the unstable mode); e^4 of the 1e-4 rad
    # start stays far below the nonlinear saturation (~1 rad). Stress run (STRESS_SEED 8, 162
    # simulated): stable end/start <= 7.9e-4 = 2.4 e^-8, unstable max/start >= 252 = e^5.5.
    if growth < 0:
        event("verdict: stable, simulated")
        assert dev[-1] <= math.exp(-6.0) * dev[0], (dev[0], dev[-1], growth)
    else:
        event("verdict: unstable, simulated")
        assert dev.max() >= math.exp(4.0) * dev[0], (dev[0], dev.max(), growth)


VERDICT_ARGS = (adb_parameters(st.just(2)), st.floats(0.3, 5.0),
                st.tuples(st.sampled_from([-1.0, 1.0]), st.sampled_from([-1.0, 1.0]), st.floats(0.2, 0.8)).map(
                    lambda t: (t[0], t[1] * t[2])))


@pytest.mark.stress
@seed(STRESS_SEED + 1)
@STRESS
@given(*VERDICT_ARGS)
def test_stress_linear_verdict_agrees_with_simulation(params, speed_ratio, start):
    check_verdict(params, speed_ratio, start)


@FAST
@given(*VERDICT_ARGS)
def test_linear_verdict_agrees_with_simulation(params, speed_ratio, start):
    check_verdict(params, speed_ratio, start)


def check_boundary(params: ADBParameters) -> None:
    note(repr(params))
    wn = params.natural_frequency_rad_s
    intervals = stable_speed_intervals(params, 5.0 * wn, grid_points=400)
    assert np.all(np.isfinite(intervals.intervals_rad_s))
    assert np.all(np.diff(intervals.intervals_rad_s.ravel()) >= 0), "intervals must be sorted and disjoint"
    ends = [x for lo, hi in intervals for x in (lo, hi)
            if intervals.speed_max_rad_s / intervals.grid_points < x < intervals.speed_max_rad_s]
    if not ends:
        event("boundary: no interior boundary")
        return
    lin = balanced_stability(params, ends)
    for growth, rounding, cls, speed in zip(lin.max_real_part_per_s, lin.rounding_bound_per_s, lin.stability_class,
                                            ends):
        # the root finder stops within 1e-10 ωn of the root: the growth rate there is that times its slope
        near = abs(growth) <= max(1e3 * rounding, 1e-6 * wn)
        assert cls == 0 or near, (speed / wn, growth, rounding, cls)
    event("boundary: checked")


@pytest.mark.stress
@pytest.mark.stress_quick
@seed(STRESS_SEED + 2)
@STRESS
@given(adb_parameters())
def test_stress_boundaries_are_marginal(params):
    check_boundary(params)


@FAST
@given(adb_parameters())
def test_boundaries_are_marginal(params):
    check_boundary(params)


GOOD = dict(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)


@pytest.mark.parametrize("field, bad", [(f, v) for f in ("M", "m", "R", "k") for v in (0.0, -1.0, math.nan, math.inf)]
                         + [(f, v) for f in ("e", "c", "D") for v in (-1.0, math.nan, math.inf)]
                         + [("n", 0), ("n", 2.5), ("n", -1), ("M", "x")])
def test_invalid_parameters_are_parameter_errors(field, bad):
    with pytest.raises(ParameterError):
        ADBParameters(**{**GOOD, field: bad})


def test_invalid_simulation_requests_are_parameter_errors():
    params = ADBParameters(**GOOD)
    for t_end in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ParameterError):
            simulate(params, 100.0, t_end)
    with pytest.raises(ParameterError):
        stable_speed_intervals(params, -5.0)
    with pytest.raises(ParameterError):
        stable_speed_intervals(ADBParameters(**{**GOOD, "e": 0.1}), 500.0)  # n m R < M e: cannot balance
