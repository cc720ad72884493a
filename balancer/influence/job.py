"""A balancing job as users write it (TOML table or file, CSV readings) and its report.

File format (``READINGS.toml``; the same keys form a scene's ``[balance]`` section)::

    units = "um"                 # readings: um, mm, mil, m, mm/s, in/s, m/s, g, m/s^2
    mass_units = "g"             # trial and correction masses: g or kg
    radius_m = 0.15              # radius of the masses, one number or one per plane
    sensors = ["A 1x @1500", "B 1x @1500"]   # optional labels, one per reading

    [initial]                    # no trial mass
    amplitude = [120.0, 80.0]
    phase_deg = [40.0, 200.0]    # phase lag, positive, against the keyphasor

    [[trial]]                    # one per plane, in plane order
    mass = 20.0
    angle_deg = 0.0              # from the keyphasor mark, against rotation
    amplitude = [150.0, 95.0]
    phase_deg = [70.0, 215.0]

    [after]                      # optional: a check run after the correction (judged against the
                                 # prediction: balancer.influence.checkrun)

Instead of inline amplitudes, ``readings = "runs.csv"`` names a CSV file with the
columns ``run,amplitude,phase_deg`` (``run`` = ``initial``, ``trial1`` ... ``trialN`` or
``after``; rows in reading order); ``[[trial]]`` then gives only ``mass`` and ``angle_deg``.
Options: ``method``, ``weights``, ``max_unbalance_kg_m``, ``holes`` or ``positions_deg``,
``weight_resolution`` (in ``mass_units``: the masses on the holes rounded to multiples of it, the
smallest step of the weights at hand), ``reading_noise`` (the readings' relative repeatability a check
run is judged with, default 0.05) and ``[iso]`` (``grade_mm_s``, ``rotor_mass_kg``, ``speed_rpm``, ``distances_m``).
"""
from __future__ import annotations

import csv
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from modal.errors import FormatError, ParameterError

from .bootstrap import CorrectionSpread, correction_spread, redrawn_jobs
from .checkrun import DEFAULT_READING_NOISE, CheckRun, check_reading_noise, check_run
from .coefficients import correction, influence_matrix
from .iso import IsoCheck, iso_check
from .readings import MASS_UNITS, amplitude_phase, reading_unit, unbalance_kg_m, vibration
from .split import equally_spaced_deg, split_correction

__all__ = ["BalanceJob", "BalanceReport", "parse_job", "load_job", "balance", "check_run_summary", "check_run_lines",
           "spread_summary", "spread_lines",
           "JOB_KEYS"]

JOB_KEYS = ("units", "mass_units", "radius_m", "sensors", "initial", "trial", "after", "readings",
            "method", "weights", "max_unbalance_kg_m", "holes", "positions_deg", "weight_resolution", "iso",
            "reading_noise")
_ISO_KEYS = ("grade_mm_s", "rotor_mass_kg", "speed_rpm", "distances_m")
_UNITS_PER_KG_M = {"m": "m/(kg m)", "m/s": "m/s/(kg m)", "m/s^2": "m/s^2/(kg m)"}


@dataclass(frozen=True, slots=True)
class BalanceJob:
    """Readings and masses of one balancing job, in SI (see :mod:`.readings` for conventions).

    Attributes
    ----------
    initial : ndarray of complex, shape (n_readings,)
        Readings without trial mass (m, m/s or m/s^2).
    trial_runs : ndarray of complex, shape (n_planes, n_readings)
        Readings with the trial mass on each plane in turn.
    trial_unbalance_kg_m : ndarray of complex, shape (n_planes,)
        Trial unbalances (kg m).
    after : ndarray of complex, shape (n_readings,) or (0,)
        Check run after the correction, if measured.
    units, mass_units : str
        The user's units for readings and masses (used to report back).
    radius_m : ndarray, shape (n_planes,)
        Radius of the correction masses in each plane (m).
    sensors : tuple of str
        Reading labels.
    """

    initial: np.ndarray
    trial_runs: np.ndarray
    trial_unbalance_kg_m: np.ndarray
    after: np.ndarray
    units: str
    mass_units: str
    radius_m: np.ndarray
    sensors: tuple[str, ...]


def _err(source: str, key: str, expected: str) -> ParameterError:
    return ParameterError(f"{source}: key '{key}': {expected}")


def _readings(table, key: str, units: str, source: str) -> np.ndarray:
    if not isinstance(table, dict) or "amplitude" not in table or "phase_deg" not in table:
        raise _err(source, key, "expected a table with 'amplitude' and 'phase_deg' lists")
    amplitude, phase = table["amplitude"], table["phase_deg"]
    if not isinstance(amplitude, list) or not isinstance(phase, list) or not amplitude:
        raise _err(source, key, "expected 'amplitude' and 'phase_deg' as non-empty lists of numbers")
    try:
        return vibration(amplitude, phase, units, field=key)
    except ParameterError as exc:
        raise ParameterError(f"{source}: {exc}") from None


def _csv_runs(path: Path, source: str) -> dict[str, tuple[list[float], list[float]]]:
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise FormatError(f"{path}: cannot read the readings file ({exc.strerror or exc})") from None
    runs: dict[str, tuple[list[float], list[float]]] = {}
    reader = csv.DictReader(text.splitlines())
    if reader.fieldnames is None or not {"run", "amplitude", "phase_deg"} <= {f.strip() for f in reader.fieldnames}:
        raise FormatError(f"{path}: expected a header with the columns run, amplitude, phase_deg")
    for line, row in enumerate(reader, start=2):
        row = {k.strip(): (v or "").strip() for k, v in row.items() if k is not None}
        try:
            amplitude, phase = float(row["amplitude"]), float(row["phase_deg"])
        except ValueError:
            raise FormatError(f"{path}: line {line}: amplitude and phase_deg must be numbers") from None
        run = row["run"].lower()
        if run not in ("initial", "after") and not (run.startswith("trial") and run[5:].isdigit() and int(run[5:]) >= 1):
            raise FormatError(f"{path}: line {line}: run = {row['run']!r}; expected initial, trial1, trial2, ... or after")
        runs.setdefault(run, ([], []))
        runs[run][0].append(amplitude)
        runs[run][1].append(phase)
    if "initial" not in runs:
        raise FormatError(f"{path}: no rows with run = initial")
    return runs


#: a job with at least this many phase readings, every one within ±2π, was probably written in radians: with
#: phases spread over the circle, six degree readings all within ±6.3° happen with odds of about 1 in 10⁸
RADIAN_PHASE_READINGS = 6


def _warn_radian_phases(phases: list[float], where, key_prefix: str) -> None:
    """Warn when every phase of a job lies within ±2π: radians written where degrees are expected."""
    values = np.abs(np.asarray(phases, dtype=float))
    if values.size >= RADIAN_PHASE_READINGS and np.all(values <= 2 * np.pi) and np.any(values > 0):
        from modal.errors import warn

        warn(f"{where}: key '{key_prefix}phase_deg': all {values.size} phases lie within ±2π (largest "
             f"{values.max():.4g}); expected degrees: radians would put every correction at the wrong angle")


def parse_job(config: dict, source: str = "<balance>", folder: Path | str = ".", key_prefix: str = "") -> BalanceJob:
    """Validate a job given as a dict (a TOML file's content or a scene's ``[balance]``).

    ``key_prefix`` (e.g. ``"balance."``) is put before every key named in an error.

    Raises
    ------
    ParameterError, FormatError
        One line naming ``source``, the key and what was expected.
    """
    if not isinstance(config, dict):
        raise ParameterError(f"{source}: expected a table of balancing readings")
    unknown = sorted(set(config) - set(JOB_KEYS))
    if unknown:
        raise _err(source, key_prefix + unknown[0], f"unknown key; expected one of: {', '.join(JOB_KEYS)}")
    if "units" not in config:
        raise _err(source, key_prefix + "units", "missing; expected the readings' unit (um, mil, mm/s, in/s, g, ...)")
    units = str(config["units"])
    try:
        reading_unit(units)
    except ParameterError as exc:
        raise ParameterError(f"{source}: {exc}") from None
    mass_units = config.get("mass_units", "g")
    if mass_units not in MASS_UNITS:
        raise _err(source, key_prefix + "mass_units", f"{mass_units!r}; expected one of {', '.join(MASS_UNITS)}")
    trials = config.get("trial")
    if not isinstance(trials, list) or not trials or not all(isinstance(t, dict) for t in trials):
        raise _err(source, key_prefix + "trial", "missing; expected one [[trial]] table per plane (mass, angle_deg and readings)")
    csv_runs = None
    if "readings" in config:
        csv_runs = _csv_runs(Path(folder) / str(config["readings"]), source)
        if "initial" in config:
            raise _err(source, key_prefix + "initial", "given twice: inline and in the readings file; keep one")
        initial = vibration(*csv_runs["initial"], units, field=f"{config['readings']}:initial")
    else:
        if "initial" not in config:
            raise _err(source, key_prefix + "initial", "missing; expected [initial] with amplitude and phase_deg")
        initial = _readings(config["initial"], key_prefix + "initial", units, source)
    n_planes = len(trials)
    radius = config.get("radius_m")
    if radius is None:
        raise _err(source, key_prefix + "radius_m", "missing; expected the radius of the masses (m), one number or one per plane")
    radius = np.broadcast_to(np.asarray(radius, dtype=float), (n_planes,)) if np.ndim(radius) == 0 else np.asarray(radius, dtype=float)
    if radius.shape != (n_planes,) or not np.all(np.isfinite(radius)) or np.any(radius <= 0):
        raise _err(source, key_prefix + "radius_m", f"expected a number > 0 or {n_planes} numbers > 0 (one per plane)")
    runs, unbalances = [], []
    for j, trial in enumerate(trials):
        key = f"trial[{j}]"
        for needed in ("mass", "angle_deg"):
            if needed not in trial:
                raise _err(source, key_prefix + f"{key}.{needed}", "missing; expected the trial mass and its angle")
        try:
            unbalances.append(complex(unbalance_kg_m(trial["mass"], radius[j], trial["angle_deg"], mass_units, field=f"{key_prefix}{key}.mass")))
        except ParameterError as exc:
            raise ParameterError(f"{source}: {exc}") from None
        if csv_runs is not None:
            name = f"trial{j + 1}"
            if name not in csv_runs:
                raise FormatError(f"{Path(folder) / str(config['readings'])}: no rows with run = {name} (plane {j + 1})")
            runs.append(vibration(*csv_runs[name], units, field=f"{config['readings']}:{name}"))
        else:
            runs.append(_readings(trial, key_prefix + key, units, source))
    for j, run in enumerate(runs):
        if run.shape != initial.shape:
            raise _err(source, key_prefix + f"trial[{j}].amplitude", f"{run.size} readings but initial has {initial.size}; "
                       "expected the same sensors and speeds in every run")
    after = np.zeros(0, dtype=complex)
    if csv_runs is not None and "after" in csv_runs:
        after = vibration(*csv_runs["after"], units, field=f"{config['readings']}:after")
    elif "after" in config:
        after = _readings(config["after"], key_prefix + "after", units, source)
    if after.size and after.shape != initial.shape:
        raise _err(source, key_prefix + "after.amplitude", f"{after.size} readings but initial has {initial.size}")
    raw_phases = ([p for _, phases in csv_runs.values() for p in phases] if csv_runs is not None else
                  [p for table in [config["initial"], *trials, config.get("after", {})] for p in table.get("phase_deg", [])])
    _warn_radian_phases(raw_phases, Path(folder) / str(config["readings"]) if csv_runs is not None else source,
                        key_prefix)
    sensors = config.get("sensors", [f"reading {i + 1}" for i in range(initial.size)])
    if not isinstance(sensors, list) or len(sensors) != initial.size:
        raise _err(source, key_prefix + "sensors", f"expected {initial.size} labels, one per reading")
    return BalanceJob(initial=initial, trial_runs=np.array(runs), trial_unbalance_kg_m=np.array(unbalances), after=after,
                      units=units, mass_units=mass_units, radius_m=np.array(radius, dtype=float),
                      sensors=tuple(str(s) for s in sensors))


def load_job(path: str | Path) -> BalanceJob:
    """Read a readings TOML file (format in the module notes)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FormatError(f"{path}: no such readings file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise FormatError(f"{path}: cannot read the readings file ({exc})") from None
    try:
        config = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise FormatError(f"{path}: not valid TOML ({exc})") from None
    return parse_job(config, str(path), path.parent)


@dataclass(frozen=True, slots=True)
class BalanceReport:
    """Correction, split onto holes, predicted residual and ISO verdict of one job.

    Vibration values are SI (``si_units``); ``reading_units`` is what the user gave.
    Masses are at ``radius_m`` in kg; angles in degrees from the mark against rotation.

    Attributes
    ----------
    method : str
    reading_units, si_units, mass_units : str
    sensors : tuple of str
    initial, residual, after : ndarray of complex
        Readings before, predicted after the correction, and measured after (if any).
    trial_runs : ndarray of complex, shape (n_planes, n_readings)
    trial_unbalance_kg_m : ndarray of complex
    alpha : ndarray of complex, shape (n_readings, n_planes)
        Influence coefficients (SI reading per kg m).
    correction_kg_m : ndarray of complex
        Unbalance to add per plane.
    correction_mass_kg, correction_angle_deg, radius_m : ndarray
    worst_initial, rms_initial, worst_residual, rms_residual : float
    condition_number, minmax_gap : float
    flags : tuple of str
    positions_deg : ndarray
        Holes used for the split (empty: no split).
    split_mass_kg : ndarray, shape (n_planes, n_positions)
        Masses on the holes (multiples of ``weight_resolution_kg`` when that is given).
    residual_unbalance_kg_m : ndarray, shape (n_planes,)
        Residual unbalance per plane equivalent to the vibration left (the check run if
        measured, else the prediction): ``max_i |v_i| / max_i |alpha_ij|``.
    iso : IsoCheck or None
    weight_resolution_kg : float or None
        The step the masses on the holes were rounded to (None: not rounded).
    check : CheckRun or None
        The check run set against the prediction, with the trim correction (None: no check run).
    spread : CorrectionSpread or None
        How the correction and the vibration it leaves scatter with the readings' repeatability.
    """

    method: str
    reading_units: str
    si_units: str
    mass_units: str
    sensors: tuple[str, ...]
    initial: np.ndarray
    trial_runs: np.ndarray
    trial_unbalance_kg_m: np.ndarray
    alpha: np.ndarray
    correction_kg_m: np.ndarray
    correction_mass_kg: np.ndarray
    correction_angle_deg: np.ndarray
    radius_m: np.ndarray
    residual: np.ndarray
    after: np.ndarray
    worst_initial: float
    rms_initial: float
    worst_residual: float
    rms_residual: float
    condition_number: float
    minmax_gap: float
    flags: tuple[str, ...]
    positions_deg: np.ndarray
    split_mass_kg: np.ndarray
    residual_unbalance_kg_m: np.ndarray
    iso: IsoCheck | None
    weight_resolution_kg: float | None = None
    check: CheckRun | None = None
    spread: CorrectionSpread | None = None

    def archive_units(self) -> dict[str, str]:
        """Units of the numeric fields whose unit depends on the readings (for the archive)."""
        per = _UNITS_PER_KG_M[self.si_units]
        return {"initial": self.si_units, "residual": self.si_units, "after": self.si_units, "trial_runs": self.si_units,
                "worst_initial": self.si_units, "rms_initial": self.si_units, "worst_residual": self.si_units,
                "rms_residual": self.si_units, "alpha": per, "condition_number": "1", "minmax_gap": "1",
                "correction_angle_deg": "deg", "positions_deg": "deg"}

    def in_user_units(self, values) -> tuple[np.ndarray, np.ndarray]:
        """Complex SI readings as (amplitude in the user's units, phase lag in deg)."""
        return amplitude_phase(values, self.reading_units)


def balance(job: BalanceJob, method: str = "least_squares", *, weights=None, max_unbalance_kg_m=None,
            holes: int | None = None, positions_deg=None, grade_mm_s: float | None = None,
            rotor_mass_kg: float | None = None, speed_rpm: float | None = None,
            distances_m: tuple[float, float] | None = None, weight_resolution_kg: float | None = None,
            reading_noise: float | None = None) -> BalanceReport:
    """Influence matrix, correction, split onto holes and ISO verdict of a job.

    Parameters
    ----------
    job : BalanceJob
    method : {"least_squares", "minmax"}
    weights, max_unbalance_kg_m
        As in :func:`~balancer.influence.correction`.
    holes : int, optional
        Equally spaced holes (the first at the keyphasor mark) to split the correction onto.
    positions_deg : array_like, optional
        Explicit hole positions (deg) instead of ``holes``.
    grade_mm_s, rotor_mass_kg, speed_rpm : float, optional
        ISO 21940-11 check (all three needed); ``distances_m`` as in :func:`~balancer.influence.iso_check`.
    weight_resolution_kg : float, optional
        Round the masses on the holes to multiples of this (kg): the smallest step of the weights at hand
        (a hole whose mass rounds to zero gets none). Default: not rounded.
    reading_noise : float, optional
        Relative repeatability of a reading (default 0.05): the correction's spread
        (:func:`~balancer.influence.bootstrap.correction_spread`) and the judgement of a check run
        (``job.after``, :func:`~balancer.influence.checkrun.check_run`) rest on it.

    Returns
    -------
    BalanceReport
    """
    noise = DEFAULT_READING_NOISE if reading_noise is None else check_reading_noise(reading_noise)
    alpha = influence_matrix(job.initial, job.trial_runs, job.trial_unbalance_kg_m)
    result = correction(alpha, job.initial, method=method, weights=weights, max_unbalance_kg_m=max_unbalance_kg_m)
    if holes is not None and positions_deg is not None:
        raise ParameterError("holes and positions_deg: give one of them, not both")
    positions = equally_spaced_deg(holes) if holes is not None else (
        np.asarray(positions_deg, dtype=float) if positions_deg is not None else np.zeros(0))
    n_planes = alpha.shape[1]
    split = split_correction(result.unbalance_kg_m, positions) / job.radius_m[:, None] if positions.size else np.zeros((n_planes, 0))
    if weight_resolution_kg is not None:
        step = float(weight_resolution_kg)
        if not np.isfinite(step) or step <= 0:
            raise ParameterError(f"weight_resolution = {weight_resolution_kg!r}: expected a mass step > 0")
        # multiples of the step, written as the step's own digits would be (0.1 g steps give 0.3 g, not 0.30000000000000004)
        split = np.array([float(f"{v:.12g}") for v in (np.round(split / step) * step).ravel()]).reshape(split.shape)
    left = job.after if job.after.size else result.residual
    check = None
    # one bootstrap of the readings serves the correction's spread and the check run's limit
    draws = redrawn_jobs(job.initial, job.trial_runs, job.trial_unbalance_kg_m, noise, weights)
    if job.after.size:
        check = check_run(alpha, job.initial, job.trial_runs, job.trial_unbalance_kg_m, result.unbalance_kg_m,
                          job.after, method=method, weights=weights, si_units=reading_unit(job.units).si_unit,
                          reading_noise=noise, draws=draws)
    spread = correction_spread(job.initial, job.trial_runs, job.trial_unbalance_kg_m, job.radius_m, noise,
                               weights=weights, si_units=reading_unit(job.units).si_unit, draws=draws)
    sensitivity = np.max(np.abs(alpha), axis=0)
    residual_unbalance = np.max(np.abs(left)) / sensitivity
    iso = None
    given = [v is not None for v in (grade_mm_s, rotor_mass_kg, speed_rpm)]
    if any(given):
        if not all(given):
            raise ParameterError("ISO check: grade_mm_s, rotor_mass_kg and speed_rpm are all needed")
        if n_planes > 2:
            raise ParameterError(f"ISO check: {n_planes} planes; ISO 21940-11 allocation covers one or two planes")
        iso = iso_check(residual_unbalance, grade_mm_s, rotor_mass_kg, speed_rpm, distances_m)
    u = result.unbalance_kg_m
    return BalanceReport(
        method=method, reading_units=job.units, si_units=reading_unit(job.units).si_unit, mass_units=job.mass_units,
        sensors=job.sensors, initial=job.initial, trial_runs=job.trial_runs, trial_unbalance_kg_m=job.trial_unbalance_kg_m,
        alpha=alpha, correction_kg_m=u, correction_mass_kg=np.abs(u) / job.radius_m,
        correction_angle_deg=np.mod(np.rad2deg(np.angle(u)), 360.0), radius_m=job.radius_m, residual=result.residual,
        after=job.after, worst_initial=result.worst_initial, rms_initial=result.rms_initial,
        worst_residual=result.worst_residual, rms_residual=result.rms_residual,
        condition_number=result.condition_number, minmax_gap=result.minmax_gap,
        flags=result.flags + (check.flags if check is not None else ()),
        positions_deg=positions, split_mass_kg=split, residual_unbalance_kg_m=residual_unbalance, iso=iso,
        weight_resolution_kg=None if weight_resolution_kg is None else float(weight_resolution_kg), check=check,
        spread=spread,
    )


def check_run_summary(report: BalanceReport) -> dict:
    """A report's check run as a JSON-ready dict (user units for readings and masses; SI where named).

    ``trim_worthwhile`` says whether the trim lowers the worst reading by more than the readings' noise
    (``reading_noise`` times the worst measured reading).
    """
    check = report.check
    scale = MASS_UNITS[report.mass_units]
    measured, _ = report.in_user_units(check.measured)
    doc = {"agrees": check.agrees, "discrepancy": check.discrepancy, "discrepancy_limit": check.discrepancy_limit,
           "reading_noise": check.reading_noise, "cause": check.cause, "cause_plane": check.cause_plane,
           "other_causes": list(check.other_causes),
           "message": check.message, "worst_measured": float(measured.max()), "alpha_updated": check.alpha_updated,
           "trim": [{"plane": j + 1, "mass": float(abs(u) / report.radius_m[j] / scale),
                     "angle_deg": float(np.mod(np.rad2deg(np.angle(u)), 360.0)), "unbalance_kg_m": float(abs(u))}
                    for j, u in enumerate(check.trim_kg_m)]}
    if check.trim_residual.size:
        left = float(report.in_user_units(check.trim_residual)[0].max())
        doc["trim_worst_residual"] = left
        doc["trim_worthwhile"] = bool(doc["worst_measured"] - left > check.reading_noise * doc["worst_measured"])
    return doc


def check_run_lines(check: dict, unit: str, mass_units: str) -> list[str]:
    """A check run's summary (:func:`check_run_summary`) as text: the verdict, then the trim (if any)."""
    lines = [f"check run: worst {check['worst_measured']:.4g} {unit} measured; {check['message']}"]
    if check["trim"]:
        masses = "; ".join(f"plane {t['plane']}: {t['mass']:.4g} {mass_units} at {t['angle_deg']:.1f} deg"
                           for t in check["trim"])
        if check["trim_worthwhile"]:
            lines.append(f"trim (add): {masses} -> worst {check['trim_worst_residual']:.3g} {unit} predicted"
                         + (" (alpha updated by the check run)" if check["alpha_updated"] else ""))
        else:
            lines.append(f"no trim needed: a trim ({masses}) would lower the worst reading by less than the readings' noise")
    return lines


def spread_summary(report: BalanceReport) -> dict:
    """The correction's spread as a JSON-ready dict (the masses in ``mass_units``, the vibration in the readings'
    unit)."""
    spread = report.spread
    scale = MASS_UNITS[report.mass_units]
    worst = float(report.in_user_units(np.array([spread.worst_residual_p90]))[0][0])
    return {"reading_noise": spread.reading_noise, "mass_std": [float(m / scale) for m in spread.mass_std_kg],
            "angle_std_deg": [float(a) for a in spread.angle_std_deg], "worst_residual_p90": worst}


def spread_lines(spread: dict, unit: str, mass_units: str) -> list[str]:
    """The correction's spread (:func:`spread_summary`) as text."""
    planes = "; ".join(f"plane {j + 1} ± {m:.2g} {mass_units}, ± {a:.2g} deg"
                       for j, (m, a) in enumerate(zip(spread["mass_std"], spread["angle_std_deg"])))
    return [f"at {100 * spread['reading_noise']:g} % reading noise: {planes}; the worst reading left is below "
            f"{spread['worst_residual_p90']:.3g} {unit} in 90 % of repeats"]
