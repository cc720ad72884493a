"""ADB simulator benchmarks: ``python -m benchmarks.bench_adb [--quick]``.

1. 200 x 200 stability map (speed ratio 0.3-4 x drag 1e-6-0.1 N m s): Routh verdicts
   (``margin=False``) and batched eigenvalues.
2. 1000 parameter sets for 1 s of rotor time: one stacked ``solve_ivp`` against a loop of
   plain ``solve_ivp`` calls (a straightforward RHS: build the (n+2)x(n+2) mass matrix and
   call ``np.linalg.solve``), errors against a tight reference, worst member.
3. One 10 s simulation with stiff ball drag: LSODA with the exact Jacobian against plain
   explicit ``solve_ivp`` (DOP853).

Times are medians of several runs (``time.perf_counter``); where a loop would take minutes
it is timed on a subset and scaled, and the table says so.
"""
from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np
from scipy.integrate import solve_ivp

from balancer.adb import ADBParameters, stability_map
from balancer.adb.equations import fixed_to_rotating
from balancer.adb.integrate import integrate
from balancer.adb.simulate import default_initial_ball_angles

S1 = ADBParameters(M=1.0, m=0.02, n=2, R=0.05, e=0.5e-3, k=1e4, c=20.0, D=1e-3)
SEED = ADBParameters(M=8.0, m=0.005, n=5, R=0.028, e=8e-5, k=15000.0, c=70.1, D=0.2)


def median_time(function, repeats: int) -> tuple[float, object]:
    times, value = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        value = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), value


def plain_rhs(params: ADBParameters, omega: float):
    """A straightforward rotating-frame RHS: full mass matrix and ``np.linalg.solve``."""
    M, m, n, R, e, k, c, D = (params.M, params.m, params.n, params.R, params.e, params.k, params.c, params.D)
    total = M + n * m

    def rhs(t, y):
        u, v = y[0], y[1]
        phi = y[2:2 + n]
        du, dv = y[2 + n], y[3 + n]
        dphi = y[4 + n:]
        s, co = np.sin(phi), np.cos(phi)
        mass = np.zeros((n + 2, n + 2))
        mass[0, 0] = mass[1, 1] = total
        mass[0, 2:] = -m * R * s
        mass[1, 2:] = m * R * co
        mass[2:, 0] = -m * R * s
        mass[2:, 1] = m * R * co
        mass[2:, 2:] = m * R * R * np.eye(n)
        force = np.empty(n + 2)
        spin = (omega + dphi) ** 2
        force[0] = (M * e * omega**2 + m * R * np.sum(spin * co) + total * (2 * omega * dv + omega**2 * u)
                    - c * (du - omega * v) - k * u)
        force[1] = (m * R * np.sum(spin * s) - total * (2 * omega * du - omega**2 * v)
                    - c * (dv + omega * u) - k * v)
        force[2:] = -D * dphi - m * R * (co * (2 * omega * du - omega**2 * v) + s * (2 * omega * dv + omega**2 * u))
        acc = np.linalg.solve(mass, force)
        return np.concatenate([[du, dv], dphi, acc])

    return rhs


def initial_state(params: ADBParameters, omega: float) -> np.ndarray:
    n = params.n
    fixed = np.zeros(5 + 2 * n)
    fixed[2:2 + n] = default_initial_ball_angles(n)
    return fixed_to_rotating(fixed, omega, n)


def bench_map(repeats: int) -> None:
    speeds = np.linspace(0.3, 4.0, 200) * S1.natural_frequency_rad_s
    drags = np.geomspace(1e-6, 0.1, 200)
    print("\n1. Stability map, 200 x 200 (speed ratio 0.3-4 x D 1e-6-0.1 N m s), n = 2")
    print(f"{'variant':<44}{'median (s)':>12}{'stable':>9}{'marginal':>10}{'unstable':>10}")
    for label, cap, margin in (("Routh verdicts, no margin (margin=False)", 1e8, False),
                               ("screened condition numbers (default)", 1e8, True),
                               ("condition number at every point", None, True)):
        elapsed, result = median_time(lambda: stability_map(S1, speeds, "D", drags, condition_cap=cap, margin=margin),
                                      repeats)
        counts = result.class_counts
        print(f"{label:<44}{elapsed:>12.3f}{counts['stable']:>9}{counts['marginal']:>10}{counts['unstable']:>10}")


def batch_members(count: int, seed: int = 7) -> list[ADBParameters]:
    rng = np.random.default_rng(seed)
    return [S1.replace(D=float(10 ** rng.uniform(-3.3, -2.3)), c=float(rng.uniform(10, 30)),
                       m=float(rng.uniform(0.016, 0.024)))
            for _ in range(count)]


def bench_batch(count: int, loop_subset: int, repeats: int) -> None:
    omega = 2.0 * S1.natural_frequency_rad_s
    t_end = 1.0
    times = np.linspace(0.0, t_end, 101)
    members = batch_members(count)
    y0 = np.array([initial_state(p, omega) for p in members])
    print(f"\n2. Batch of {count} parameter sets (n = 2, D 5e-4-5e-3, c 10-30, m 16-24 g), 1 s at "
          f"{omega:.1f} rad/s, DOP853")
    reference = integrate(members, omega, y0, times, rtol=1e-12, method="DOP853").states
    print("   reference: stacked DOP853 at rtol 1e-12 per member (1e-12/sqrt(B) on the stack)")

    def worst(states) -> float:
        return float(np.max(np.abs(states[..., :2] - reference[..., :2])))

    print(f"{'method':<52}{'rtol':>8}{'time (s)':>11}{'worst error (m)':>17}{'evals':>9}")
    rows = {}
    for rtol in (1e-6, 1e-8, 1e-10):
        elapsed, run = median_time(lambda: integrate(members, omega, y0, times, rtol=rtol, method="DOP853"), repeats)
        rows[("batch", rtol)] = (elapsed, worst(run.states))
        print(f"{'stacked batch (one solve_ivp)':<52}{rtol:>8.0e}{elapsed:>11.2f}{worst(run.states):>17.2e}"
              f"{run.n_function_evaluations:>9}")
    subset = list(range(0, count, max(1, count // loop_subset)))[:loop_subset]
    for rtol in (1e-6, 1e-8, 1e-10):
        atol = np.r_[[1e-3 * rtol * S1.R] * 2, [1e-3 * rtol] * 2,
                     [1e-3 * rtol * S1.R * omega] * 2, [1e-3 * rtol * omega] * 2]

        def loop():
            states, evals = [], 0
            for index in subset:
                sol = solve_ivp(plain_rhs(members[index], omega), (0, t_end), y0[index], method="DOP853",
                                t_eval=times, rtol=rtol, atol=atol)
                states.append(sol.y.T)
                evals += sol.nfev
            return np.array(states), evals

        elapsed, (states, evals) = median_time(loop, 1)
        error = float(np.max(np.abs(states[..., :2] - reference[subset][..., :2])))
        scaled = elapsed * count / len(subset)
        rows[("loop", rtol)] = (scaled, error)
        print(f"{'loop of plain solve_ivp (' + str(len(subset)) + ' timed once, x' + str(count // len(subset)) + ')':<52}"
              f"{rtol:>8.0e}{scaled:>11.2f}{error:>17.2e}{evals // len(subset):>9}")
    loop_errors = np.log([rows[("loop", r)][1] for r in (1e-6, 1e-8, 1e-10)])
    loop_times = np.log([rows[("loop", r)][0] for r in (1e-6, 1e-8, 1e-10)])
    print("   speed-up at equal worst-member error (loop time interpolated log-log at the batch's error):")
    for rtol in (1e-6, 1e-8, 1e-10):
        tb, eb = rows[("batch", rtol)]
        if loop_errors.min() <= math.log(eb) <= loop_errors.max():
            tl = math.exp(np.interp(math.log(eb), loop_errors[::-1], loop_times[::-1]))
            print(f"     worst error {eb:.1e} m: batch {tb:.2f} s, loop {tl:.1f} s -> {tl / tb:.1f}x")
        else:
            tl, el = rows[("loop", rtol)]
            print(f"     batch rtol {rtol:.0e} (error {eb:.1e} m) is outside the loop's error range; at the same "
                  f"rtol the loop (error {el:.1e} m) is {tl / tb:.1f}x slower")


def bench_stiff(t_end: float, explicit_seconds: float, repeats: int) -> None:
    omega = 2.0 * SEED.natural_frequency_rad_s
    print(f"\n3. Stiff ball drag ('SEED?' set: n = 5, D = 0.2 N m s, D/(m R^2) = "
          f"{SEED.D / (SEED.m * SEED.R**2):.3g} /s), {t_end:g} s at {omega:.1f} rad/s")
    y0 = initial_state(SEED, omega)
    samples = np.linspace(0.0, t_end, 201)
    reference = integrate(SEED, omega, y0, samples, method="Radau", rtol=1e-12).states[0]
    print("   reference: Radau, exact Jacobian, rtol 1e-12")
    print(f"{'method':<54}{'time (s)':>10}{'error (m)':>12}{'evals':>10}{'per sim. s':>12}")
    for rtol in (1e-6, 1e-9):
        elapsed, run = median_time(lambda: integrate(SEED, omega, y0, samples, method="auto", rtol=rtol), repeats)
        error = float(np.max(np.abs(run.states[0, :, :2] - reference[:, :2])))
        print(f"{run.method + ' + exact Jacobian, rtol ' + format(rtol, '.0e'):<54}{elapsed:>10.2f}{error:>12.2e}"
              f"{run.n_function_evaluations:>10}{run.n_function_evaluations / t_end:>12.0f}")
    short = samples[samples <= explicit_seconds + 1e-12]
    atol = np.r_[[1e-12 * SEED.R] * 2, [1e-12] * 5, [1e-12 * SEED.R * omega] * 2, [1e-12 * omega] * 5]
    start = time.perf_counter()
    sol = solve_ivp(plain_rhs(SEED, omega), (0.0, explicit_seconds), y0, method="DOP853", t_eval=short,
                    rtol=1e-9, atol=atol)
    elapsed = time.perf_counter() - start
    error = float(np.max(np.abs(sol.y[:2].T - reference[: short.size, :2])))
    label = f"plain DOP853 rtol 1e-9 (first {explicit_seconds:g} s, scaled)"
    print(f"{label:<54}{elapsed * t_end / explicit_seconds:>10.2f}{error:>12.2e}"
          f"{int(sol.nfev * t_end / explicit_seconds):>10}{sol.nfev / explicit_seconds:>12.0f}")
    print("   errors: largest rotor-position difference from the reference over the samples of each run")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes (smoke run)")
    args = parser.parse_args(argv)
    repeats = 2 if args.quick else 5
    bench_map(repeats)
    bench_batch(count=100 if args.quick else 1000, loop_subset=10 if args.quick else 40, repeats=1 if args.quick else 3)
    bench_stiff(t_end=1.0 if args.quick else 10.0, explicit_seconds=0.1 if args.quick else 0.5,
                repeats=1 if args.quick else 3)


if __name__ == "__main__":
    main()
