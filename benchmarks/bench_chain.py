"""Calibration of the whole chain, time records → FRF → modes: z = (estimate − truth) / reported std.

Run ``python -m benchmarks.bench_chain [--records N] [--cells NAME ...]``.

Each cell makes ``N`` records of a two-mode structure sampled exactly
(:class:`modal.synthetic_time.DigitalModes`: the digital poles are the continuous ones),
estimates the FRF with :func:`modal.estimate_frf` as a user would (the cell's
excitation, window and averages) and identifies it with :func:`modal.identify`'s
defaults. Per mode it prints, for the natural frequency and the damping ratio, the
standard deviation of z (1 when the errors are calibrated), its mean (0 when unbiased)
and how often the mode was found. Records where a mode was not found count as missed,
not as z.

The default cells are the two the chain is held to (random excitation with the
default settings; a hammer test with an exponential window); ``--cells all`` adds the
others (rectangular window, burst random, hammer without a window, few and many
averages, light and heavy damping, and hammer tests with one force and 2, 3 or 6
accelerometers in one file, named ``hammer-{exp,force}-{hits}-ch{accelerometers}``,
``-global`` with the global method), and roving-hammer tests (one accelerometer, the hammer at three points,
one record per point joined as ``modal fit`` joins one file per hit point: ``hammer-{exp,force}-{hits}-roving3``).
"""
from __future__ import annotations

import argparse
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

import modal
from modal.synthetic_time import DigitalModes, impact_record, random_record

#: sample rate of every cell, Hz
SAMPLE_RATE_HZ = 1024.0
#: the two modes, Hz, and their damping ratios unless a cell says otherwise
NATURAL_FREQUENCY_HZ = (40.0, 95.0)
DAMPING_RATIO = (0.02, 0.012)
#: receptance modal constants of the driving point, 1/kg
MODAL_CONSTANT = (0.5, 0.8)


@dataclass(frozen=True)
class Cell:
    """One calibration cell: how a record is made and how the FRF is estimated from it."""

    name: str
    description: str
    make: Callable[[int], tuple]  # seed -> (EstimatedFRF, DigitalModes)
    identify_options: dict = field(default_factory=dict)  # passed to modal.identify (e.g. method)


#: where the accelerometers of the multi-channel cells sit on a pinned-pinned beam (fraction of its length),
#: the driving point first; its shapes sin(rπx) give each point's constants relative to the driving point's
ACCELEROMETER_POSITIONS = (0.2, 0.35, 0.8, 0.65, 0.12, 0.9)


def system(damping_ratio=DAMPING_RATIO, n_outputs: int = 1) -> DigitalModes:
    """The two-mode structure; with ``n_outputs`` > 1, seen at the first of :data:`ACCELEROMETER_POSITIONS`
    (the driving point, constants :data:`MODAL_CONSTANT`) and the next ones."""
    if n_outputs == 1:
        constants = np.array(MODAL_CONSTANT)
    else:
        x = np.array(ACCELEROMETER_POSITIONS[:n_outputs])
        shape = np.sin(np.pi * np.outer(x, np.arange(1, len(MODAL_CONSTANT) + 1)))  # (outputs, modes)
        constants = np.array(MODAL_CONSTANT)[None, :] * shape / shape[0]
    return DigitalModes(np.array(NATURAL_FREQUENCY_HZ), np.asarray(damping_ratio, float), constants, SAMPLE_RATE_HZ)


def random_cell(duration_s: float, window: str = "hann", damping_ratio=DAMPING_RATIO, segment_length=None,
                noise: float = 0.05, n_outputs: int = 1):
    def make(seed: int):
        structure = system(damping_ratio, n_outputs)
        rec = random_record(structure, duration_s, response_noise=noise, force_noise=0.0, seed=seed).record
        frf = modal.estimate_frf(rec.signals[0], rec.signals[1] if n_outputs == 1 else rec.signals[1:],
                                 rec.sample_rate_hz, window=window, kind="accelerance", segment_length=segment_length)
        return frf, structure
    return make


def burst_cell(n_bursts: int, segment_s: float = 8.0, burst_fraction: float = 0.5, noise: float = 0.05,
               damping_ratio=DAMPING_RATIO):
    """Burst random: white force over the first part of each segment, silence after (the response decays)."""
    def make(seed: int):
        structure = system(damping_ratio)
        rng = np.random.default_rng(seed)
        length = int(round(segment_s * SAMPLE_RATE_HZ))
        force = rng.standard_normal(n_bursts * length)
        on = (np.arange(force.size) % length) < burst_fraction * length
        force *= on
        response = structure.respond(force, "acceleration")[0]
        response = response + noise * np.sqrt(np.mean(response**2)) * rng.standard_normal(response.size)
        frf = modal.estimate_frf(force, response, SAMPLE_RATE_HZ, window="rect", kind="accelerance",
                                 segment_length=length, overlap=0.0)
        return frf, structure
    return make


def hammer_cell(n_hits: int, window: str = "exponential", decay_s: float | None = 0.5, spacing_s: float = 4.0,
                noise: float = 0.002, damping_ratio=DAMPING_RATIO, n_outputs: int = 1):
    """Hammer hits at the driving point, ``n_outputs`` accelerometers (one file: one force, all responses)."""
    def make(seed: int):
        structure = system(damping_ratio, n_outputs)
        hits = 0.5 + spacing_s * np.arange(n_hits)
        rec = impact_record(structure, hits, hits[-1] + spacing_s, amplitude_variation=0.2, width_variation=0.1,
                            pulse_width_s=0.002, response_noise=noise, force_noise=0.002, seed=seed).record
        points = {} if n_outputs == 1 else {"excitation_points": ["1"],
                                            "response_points": [f"{k + 1}" for k in range(n_outputs)]}
        frf = modal.estimate_frf(rec.signals[0], rec.signals[1:] if n_outputs > 1 else rec.signals[1],
                                 rec.sample_rate_hz, impact=True, window=window,
                                 exponential_decay_s=decay_s if window == "exponential" else None,
                                 kind="accelerance", **points)
        return frf, structure
    return make


def roving_cell(n_hits: int, window: str = "exponential", n_points: int = 3, spacing_s: float = 4.0,
                noise: float = 0.002):
    """A roving hammer: one accelerometer at the driving point (:data:`ACCELEROMETER_POSITIONS`' first), the
    hammer at ``n_points`` points in turn (the first the driving point), ``n_hits`` hits each, one record per
    point; each point's FRF estimated from its own record and the points joined
    (:func:`modal.roving.join_estimates`), as ``modal fit`` joins one file per hit point. By reciprocity the
    response at the driving point to a hit at x is the response at x to a hit at the driving point: the
    structure of the multi-channel cells, one output per point."""
    from modal.roving import join_estimates

    def make(seed: int):
        structure = system(n_outputs=n_points)
        hits = 0.5 + spacing_s * np.arange(n_hits)
        estimates = []
        for point in range(n_points):
            seen = DigitalModes(structure.natural_frequency_hz, structure.damping_ratio,
                                structure.modal_constant[point], SAMPLE_RATE_HZ)
            rec = impact_record(seen, hits, hits[-1] + spacing_s, amplitude_variation=0.2, width_variation=0.1,
                                pulse_width_s=0.002, response_noise=noise, force_noise=0.002,
                                seed=seed * n_points + point).record
            estimates.append(modal.estimate_frf(rec.signals[0], rec.signals[1], rec.sample_rate_hz, impact=True,
                                                window=window, exponential_decay_s=0.5 if window == "exponential"
                                                else None, kind="accelerance", excitation_points=[f"{point + 1}"],
                                                response_points=["1"]))
        frf = join_estimates(estimates, [(f"{point + 1}", [f"point {point + 1}"]) for point in range(n_points)])
        return frf, structure
    return make


#: where the two shakers of the two-shaker cells sit (:data:`ACCELEROMETER_POSITIONS`' indices: 0.2 and 0.8), and the
#: accelerometers (0.2, 0.35, 0.8: the shakers' driving points and one between)
SHAKER_POINTS = (0, 2)
TWO_SHAKER_OUTPUTS = 3


def two_shaker_cell(duration_s: float = 120.0, noise: float = 0.05):
    """Two independent white forces at two points of the beam (:data:`SHAKER_POINTS`), three accelerometers,
    white noise of ``noise`` times each response's RMS; the FRF of both inputs estimated at once (H1 over the
    two inputs, the default Hann segments). The system returned is the first input's (the poles are shared)."""
    def make(seed: int):
        x = np.array(ACCELEROMETER_POSITIONS[:TWO_SHAKER_OUTPUTS])
        modes = np.arange(1, len(MODAL_CONSTANT) + 1)
        shape = np.sin(np.pi * np.outer(x, modes)) / np.sin(np.pi * x[0] * modes)  # (outputs, modes)
        rng = np.random.default_rng(seed)
        n = int(round(duration_s * SAMPLE_RATE_HZ))
        forces = rng.standard_normal((len(SHAKER_POINTS), n))
        response = np.zeros((TWO_SHAKER_OUTPUTS, n))
        structures = []
        for point, force in zip(SHAKER_POINTS, forces):
            constants = np.array(MODAL_CONSTANT)[None, :] * shape * shape[point]  # reciprocity: A_op = c φ_o φ_p
            seen = DigitalModes(np.array(NATURAL_FREQUENCY_HZ), np.array(DAMPING_RATIO), constants, SAMPLE_RATE_HZ)
            structures.append(seen)
            response += seen.respond(force, "acceleration")
        response += noise * np.sqrt(np.mean(response**2, axis=1))[:, None] * rng.standard_normal(response.shape)
        frf = modal.estimate_frf(forces, response, SAMPLE_RATE_HZ, kind="accelerance",
                                 excitation_points=[f"{p + 1}" for p in SHAKER_POINTS],
                                 response_points=[f"{o + 1}" for o in range(TWO_SHAKER_OUTPUTS)])
        return frf, structures[0]
    return make


#: the cells the chain is held to (z spread 0.75–1.3, |mean| ≤ 0.35 for fn and ζ of every mode)
TARGET_CELLS = ("random-hann-default", "hammer-exp-6")

CELLS = {c.name: c for c in [
    Cell("random-hann-default", "random, 120 s, Hann, default segments (8192), 5 % response noise",
         random_cell(120.0)),
    Cell("hammer-exp-6", "hammer, 6 hits, exponential window τ = 0.5 s, 0.2 % noise", hammer_cell(6)),
    Cell("random-rect-default", "random, 120 s, rectangular window, default segments", random_cell(120.0, "rect")),
    Cell("random-hann-3avg", "random, 16 s, Hann, 4096-sample segments (≈ 3 averages)",
         random_cell(8.0, segment_length=4096)),
    Cell("random-hann-50avg", "random, 200 s, Hann, 8192-sample segments (≈ 50 averages)",
         random_cell(200.0, segment_length=8192)),
    Cell("random-hann-zeta0.1", "random, 240 s, Hann, default segments, ζ 0.1 % and 0.2 %",
         random_cell(240.0, damping_ratio=(0.001, 0.002))),
    Cell("random-hann-zeta5", "random, 60 s, Hann, default segments, ζ 5 % and 3 %",
         random_cell(60.0, damping_ratio=(0.05, 0.03))),
    Cell("burst-10", "burst random, 10 bursts of 4 s in 8 s segments, rectangular", burst_cell(10)),
    Cell("hammer-rect-6", "hammer, 6 hits of 4 s, rectangular window", hammer_cell(6, "rect", None)),
    Cell("hammer-exp-3", "hammer, 3 hits, exponential window τ = 0.5 s", hammer_cell(3)),
    Cell("hammer-exp-1", "hammer, 1 hit, exponential window τ = 0.5 s", hammer_cell(1)),
    Cell("hammer-rect-1", "hammer, 1 hit, rectangular window (each hit of a repeated test on its own)",
         hammer_cell(1, "rect", None)),
    Cell("hammer-force-6", "hammer, 6 hits, force window, one accelerometer", hammer_cell(6, "force", None)),
    # one force, several accelerometers in one file (modal fit's default is nls for them: one reference, two
    # peaks); the global method on three of them
    *[Cell(f"hammer-{short}-{hits}-ch{outputs}{suffix}",
           f"hammer, {hits} hits, {long}, {outputs} accelerometers in one file{said}",
           hammer_cell(hits, window, 0.5 if window == "exponential" else None, n_outputs=outputs), options)
      for suffix, said, options, counts in (("", "", {}, (2, 3, 6)),
                                            ("-global", ", global method", {"method": "global"}, (3,)))
      for short, window, long in (("exp", "exponential", "exponential window τ = 0.5 s"),
                                  ("force", "force", "force window"))
      for hits in (3, 6, 12) for outputs in counts],
    # 16384-sample records (hits 17 s apart): the force window's 266 samples × 3 hits are 798 rows of 8193 lines,
    # the excitation's shared error formed per fit band (modal.estimate.common_error.CommonError)
    Cell("hammer-force-3-ch3-16k", "hammer, 3 hits 17 s apart (16384-sample records), force window, "
         "3 accelerometers in one file", hammer_cell(3, "force", None, spacing_s=17.0, n_outputs=3)),
    Cell("hammer-force-3-ch3-16k-global", "hammer-force-3-ch3-16k, global method (the factor on every line)",
         hammer_cell(3, "force", None, spacing_s=17.0, n_outputs=3), {"method": "global"}),
    Cell("random-hann-ch3", "random, 120 s, Hann, default segments, one shaker, 3 accelerometers",
         random_cell(120.0, n_outputs=3)),
    # two shakers: band-wise nls over the six channels, and the default for a poly-reference grid (global)
    Cell("shakers-2-ch3", "two shakers (independent white forces), 120 s, Hann, default segments, "
         "3 accelerometers, 5 % response noise, method nls", two_shaker_cell(), {"method": "nls"}),
    Cell("shakers-2-ch3-global", "two shakers as shakers-2-ch3, global method (identify's default for them)",
         two_shaker_cell()),
    # a roving hammer: one accelerometer, the hammer at three points, one record per point, joined
    *[Cell(f"hammer-{short}-{hits}-roving3", f"roving hammer, 3 points × {hits} hits, {long}, one accelerometer",
           roving_cell(hits, window))
      for short, window, long in (("exp", "exponential", "exponential window τ = 0.5 s"),
                                  ("force", "force", "force window"))
      for hits in (3, 6)],
]}


def z_scores(cell: Cell, records: int, first_seed: int = 0) -> dict:
    """z of fn and ζ per mode over ``records`` seeds, |error| / reported error of the first channel's (complex)
    modal constant ("A": its RMS is 1 for calibrated errors, the error being sqrt(var Re + var Im)), and the
    count of records where each mode was found."""
    n_modes = len(NATURAL_FREQUENCY_HZ)
    z = {(q, r): [] for q in ("fn", "zeta", "A") for r in range(n_modes)}
    found = np.zeros(n_modes, int)
    for seed in range(first_seed, first_seed + records):
        frf, structure = cell.make(seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = modal.identify(frf, **cell.identify_options)
        fn_est = np.array([m.natural_frequency_hz for m in result.modes], float)
        for r in range(n_modes):
            if fn_est.size == 0:
                continue
            i = int(np.argmin(np.abs(fn_est - structure.natural_frequency_hz[r])))
            if abs(fn_est[i] - structure.natural_frequency_hz[r]) > 3 * structure.damping_ratio[r] * \
                    structure.natural_frequency_hz[r] + 1.0:
                continue
            mode = result.modes[i]
            found[r] += 1
            z[("fn", r)].append((mode.natural_frequency_hz - structure.natural_frequency_hz[r])
                                / mode.std.natural_frequency_hz)
            z[("zeta", r)].append((mode.damping_ratio - structure.damping_ratio[r]) / mode.std.damping_ratio)
            constant = np.atleast_1d(mode.modal_constant)[0]
            true_constant = np.atleast_2d(np.asarray(structure.modal_constant))[0, r]
            z[("A", r)].append(abs(constant - true_constant) / np.atleast_1d(mode.std.modal_constant)[0])
    return {"z": {k: np.asarray(v, float) for k, v in z.items()}, "found": found, "records": records}


def summary(z: np.ndarray) -> tuple[float, float]:
    """Standard deviation and mean of the finite z-values."""
    a = z[np.isfinite(z)]
    return (float(np.std(a)), float(np.mean(a))) if a.size else (np.nan, np.nan)


def rms(values: np.ndarray) -> float:
    """Root mean square of the finite values."""
    a = values[np.isfinite(values)]
    return float(np.sqrt(np.mean(a * a))) if a.size else np.nan


def rows(name: str, scores: dict, seconds: float) -> list[str]:
    out = []
    for r in range(len(NATURAL_FREQUENCY_HZ)):
        fn = summary(scores["z"][("fn", r)])
        zeta = summary(scores["z"][("zeta", r)])
        out.append(f"| {name} | {r + 1} | {fn[0]:.2f} / {fn[1]:+.2f} | {zeta[0]:.2f} / {zeta[1]:+.2f} | "
                   f"{rms(scores['z'][('A', r)]):.2f} | {scores['found'][r]}/{scores['records']} | {seconds:.0f} |")
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.bench_chain", description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=80, help="records per cell (default 80)")
    parser.add_argument("--cells", nargs="+", default=list(TARGET_CELLS), help="cell names, or 'all'")
    parser.add_argument("--first-seed", type=int, default=0, help="seed of the first record (default 0)")
    args = parser.parse_args(argv)
    names = list(CELLS) if args.cells == ["all"] else args.cells
    print(f"Chain calibration over {args.records} records per cell (seeds {args.first_seed}–"
          f"{args.first_seed + args.records - 1}): per mode SD of z / mean of z for fn and ζ "
          "(calibrated: 1 / 0), RMS of |error| / reported error of channel 1's modal constant (calibrated: 1), "
          "records where the mode was found, CPU s for the cell.\n")
    for name in names:
        print(f"- {name}: {CELLS[name].description}")
    print("\n| cell | mode | fn z: SD / mean | ζ z: SD / mean | A: RMS | found | s |")
    print("|---|---|---|---|---|---|---|")
    for name in names:
        start = time.process_time()
        scores = z_scores(CELLS[name], args.records, args.first_seed)
        print("\n".join(rows(name, scores, time.process_time() - start)), flush=True)


if __name__ == "__main__":
    main()
