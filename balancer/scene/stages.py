"""The scene's stages: each a plain function from its configuration and the
results of the stages it depends on to a frozen result dataclass, and the checks
a stage makes when the scene is read (its ``prepare``; see :mod:`.registry`).

They only wire the library together; a script can call any of them directly.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import modal
from modal.errors import SceneError, warn
from modal.units import STANDARD_GRAVITY_M_S2, TWO_PI

from ..adb import ADBParameters, ParameterStd, identified_std, stable_speed_intervals
from ..adb.parameters import STD_ORDER, identified_correlation
from ..adb.simulate import SimulationResult, simulate
from ..adb.speed import LinearRunUp
from ..adb.stability import SpeedIntervals
from .rules import DRIVE_FIELDS, IDENTIFIED_FIELDS, Reference, parse_reference
from .schema import Scene

__all__ = [
    "RotorStage", "StabilityStage", "DriveStage", "CompressorStage", "MountsStage",
    "stage_frf", "stage_identify", "stage_drive", "stage_rotor", "stage_adb_stability", "stage_adb_response",
    "stage_compressor", "stage_mounts", "resolve", "BalanceStage", "stage_balance", "check_frf", "read_balance_job",
    "stage_oma", "check_oma", "check_compressor", "check_mounts", "RovingFiles",
]


@dataclass(frozen=True)
class RotorStage:
    """Ball-balancer parameters as used, with the standard errors carried from identification.

    ``sources`` says where each of M, k, c came from (a number or a reference).
    """

    params: ADBParameters
    std: ParameterStd
    sources: tuple[str, ...]


@dataclass(frozen=True)
class StabilityStage:
    """Speed intervals (rad/s) where the balanced state is stable, and the eigenvalue curve."""

    intervals: SpeedIntervals
    speeds_rad_s: np.ndarray
    max_real_part_per_s: np.ndarray
    can_balance: bool


@dataclass(frozen=True)
class DriveStage:
    """Belt drive and, when a shaft is given, its hand-over to the rotor."""

    drive: object  # balancer.drive.BeltDrive
    handover: object | None  # balancer.drive.shaft.RotorHandover


@dataclass(frozen=True)
class CompressorStage:
    """Crank counterweight study: mechanism, exact optimum and the chosen counterweight."""

    mechanism: object  # balancer.compressor.crank.SliderCrank
    optimum: object  # balancer.compressor.crank.OptimalCounterweight
    counterweight_mass_kg: float
    counterweight_radius_m: float
    speed_rpm: float


@dataclass(frozen=True)
class MountsStage:
    """The compressor body on its mounts: modes and base forces before/after balancing."""

    system: object  # balancer.compressor.mounts.MountedBody
    natural_frequencies_hz: np.ndarray
    comparison: object  # balancer.compressor.mounts.BalancingComparison


#: [frf] keys passed to modal.io.read_frf: the read options of ``python -m modal fit`` under the same names
FRF_READ_OPTIONS = ("kind", "frequency_axis", "frequency_step", "frequency_start", "layout", "delimiter", "decimal",
                    "dataset")
#: [frf] keys of a time record: the time options of ``python -m modal fit`` (modal.time_frf.TIME_OPTIONS), and ``kind``
TIME_FRF_OPTIONS = ("excitation", "response", "impact", "estimator", "window", "exponential_decay_s",
                    "segment_length", "overlap")


# ---------------------------------------------------------------- references
def _serious_flags(mode) -> list[str]:
    from modal.flags import serious_flags

    return sorted(serious_flags(mode.flags))


def _test_section(scene: Scene) -> str:
    """The section of the test that ``identified:`` references read: ``oma`` (an operational test) when the
    scene has [oma] and no [frf], else ``identify``."""
    return "oma" if scene.section("oma") is not None and scene.section("frf") is None else "identify"


def describe_mode(identified, ref: Reference, scene: Scene) -> str:
    """Which identified mode a reference used: number, frequency, damping, channel and flags."""
    mode = identified[ref.mode - 1]
    flags = _serious_flags(mode)
    return (f"mode {ref.mode} at {mode.natural_frequency_hz:.6g} Hz, zeta {100 * mode.damping_ratio:.4g} %, "
            f"channel {_channel(identified, scene) + 1}, flags: {', '.join(flags) or 'none'}"
            + (f" (accepted: {_test_section(scene)}.accept_flagged)" if flags else ""))


def _identified_mode(identified, ref: Reference, key: str, scene: Scene):
    if ref.mode > len(identified):
        raise SceneError(f"{scene.source}: key '{key}' = {ref.text!r}: identification found "
                         f"{len(identified)} mode(s), expected at least {ref.mode}")
    return identified[ref.mode - 1]


def _channel(identified, scene: Scene) -> int:
    """The 0-based channel references read: ``[identify] channel`` (counted from 1), else the first
    driving point; ``[oma] channel`` for an operational test."""
    if _test_section(scene) == "oma":
        return _oma_channel(identified, scene)
    channel = scene.section("identify.channel")
    mode = identified[0]
    driving = np.atleast_1d(mode.driving_point)
    if channel is None:
        hits = np.flatnonzero(driving)
        return int(hits[0]) if hits.size else 0
    if not 1 <= channel <= driving.size:
        raise SceneError(f"{scene.source}: key 'identify.channel' = {channel}: no such channel; expected "
                         f"1..{driving.size}")
    return channel - 1


def _oma_channel(identified, scene: Scene) -> int:
    """0-based index of ``[oma] channel`` (a number from 1 or a name, as ``modal oma`` takes it; default 1)."""
    spec = scene.section("oma.channel", "1")
    names = [str(n) for n in identified.settings.get("channel_names", [])]
    if spec in names:
        return names.index(spec)
    if spec.isdigit() and 1 <= int(spec) <= identified.n_channels:
        return int(spec) - 1
    raise SceneError(f"{scene.source}: key 'oma.channel' = {spec!r}: no such channel; expected a number "
                     f"1..{identified.n_channels} or a name ({', '.join(names)})")


def _check_oma_channel_moves(mode, ref: Reference, key: str, identified, scene: Scene) -> None:
    """Refuse k, c, m at an ``[oma] channel`` whose shape entry lies within a few of its standard errors of
    zero: there ψ² rests on noise and m = 1/ψ² is any number (a node of the mode, or a dead channel)."""
    from modal.operational.screen import NODE_SIGMAS

    channel = _channel(identified, scene)
    if mode.std.mode_shape is None:
        return
    entry, error = abs(mode.mode_shape[channel]), float(mode.std.mode_shape[channel])
    if entry <= NODE_SIGMAS * error:
        mass, mass_std = np.atleast_1d(mode.mass_kg)[channel], np.atleast_1d(mode.std.mass_kg)[channel]
        raise SceneError(f"{scene.source}: key '{key}' = {ref.text!r}: mode {ref.mode}'s shape at channel "
                         f"{channel + 1} ({entry:.3g} ± {error:.3g}) is within {NODE_SIGMAS:g} standard errors of "
                         f"zero: its k, c, m there rest on noise (m = {mass:.3g} ± {mass_std:.3g} kg); expected "
                         "oma.channel where the mode moves (a node of the mode, or a dead sensor?)")


def resolve(value, key: str, scene: Scene, identified=None, drive=None) -> float:
    """A number, or the value a reference points at (SI units)."""
    if isinstance(value, str):
        value = parse_reference(value)
    if not isinstance(value, Reference):
        return value
    if value.source == "identified":
        mode = _identified_mode(identified, value, key, scene)
        flags = _serious_flags(mode)
        test = _test_section(scene)
        if flags and not scene.section(f"{test}.accept_flagged", False):
            narrow = "identify.bands_hz" if test == "identify" else "oma.band_hz"
            raise SceneError(
                f"{scene.source}: key '{key}' = {value.text!r}: mode {value.mode} ({mode.natural_frequency_hz:.6g} Hz) "
                f"is flagged ({', '.join(flags)}; see docs/flags.md); expected an unflagged mode: refer to another "
                f"mode, give {narrow}, or set {test}.accept_flagged = true to use it anyway")
        raw = np.atleast_1d(getattr(mode, IDENTIFIED_FIELDS[value.field]))
        number = float(raw[_channel(identified, scene)] if raw.size > 1 else raw[0])
        if test == "oma" and math.isfinite(number):
            _check_oma_channel_moves(mode, value, key, identified, scene)
        if not math.isfinite(number) and test == "oma" and scene.section("oma.mass_change") is None:
            raise SceneError(f"{scene.source}: key '{key}' = {value.text!r}: an operational test alone gives no "
                             "k, c, m; expected oma.mass_change and oma.added_mass_kg (a second record with known "
                             "masses added) to scale its modes")
        if not math.isfinite(number):
            if "units_unknown" in mode.flags:
                advice = ("the FRF's unit is not one k, c, m can be given in: record the channels in physical units "
                          "(N and m/s^2, m/s or m; g, mm/s and lbf are converted)")
            elif "driving_point_unknown" in mode.flags:
                advice = ("the FRF does not say which channel was measured at the excitation point: declare it with "
                          "driving_point = CHANNEL under [identify] (counted from 1)")
            else:
                advice = "choose a driving-point channel"
            raise SceneError(f"{scene.source}: key '{key}' = {value.text!r} is not defined for that channel "
                             f"(flags: {', '.join(mode.flags) or 'none'}); {advice}")
        return number
    handover = getattr(drive, "handover", None)
    if handover is None:
        raise SceneError(f"{scene.source}: key '{key}' = {value.text!r} needs [drive.shaft] for the hand-over")
    return float(getattr(handover, DRIVE_FIELDS[value.field]))


# -------------------------------------------------------------------- checks when the scene is read
def check_frf(scene: Scene):
    """[frf] names a file or describes a synthetic FRF: one of them, with the options that apply to it.

    A time record (a hammer or shaker test) is read here, its channels chosen and their roles
    checked before any work: returns ``(record, plan)`` (:func:`modal.time_frf.plan_time_frf`)
    for the stage to estimate from, several files being takes of one test; :class:`RovingFiles`
    for the files of a roving-hammer test (the force channel's name changes from file to file, the
    responses stay), refused as ``modal fit`` refuses them when they are not one; None for an FRF
    file or a synthetic FRF.
    """
    cfg = scene.section("frf")
    if "file" in cfg and "synthetic" in cfg:
        raise SceneError(f"{scene.source}: key 'frf' has both 'file' and 'synthetic'; expected one of them")
    if "file" not in cfg and "synthetic" not in cfg:
        raise SceneError(f"{scene.source}: key 'frf' needs 'file' or a [frf.synthetic] table")
    time_keys = [k for k in TIME_FRF_OPTIONS if k in cfg]
    if "synthetic" in cfg:
        if time_keys:
            raise SceneError(f"{scene.source}: key 'frf.{time_keys[0]}' applies to a time record in 'file'; "
                             "expected no time options with [frf.synthetic]")
        return None
    from modal.errors import ModalError
    from modal.time_frf import wants_time

    paths = _frf_paths(scene)
    if not any(wants_time(_time_options(cfg), path) for path in paths):
        return None
    read_keys = [k for k in FRF_READ_OPTIONS if k in cfg and k != "kind"]
    if read_keys:
        raise SceneError(f"{scene.source}: key 'frf.{read_keys[0]}' applies to an FRF file, but {cfg['file']!r} is a "
                         f"time record; expected its time options ({', '.join(TIME_FRF_OPTIONS)}, kind)")
    from modal.io.timedata import read_time
    from modal.io.timejoin import join_takes

    try:
        records = [read_time(path) for path in paths]
    except ModalError as exc:
        raise SceneError(f"{scene.source}: key 'frf.file' = {cfg['file']!r}: {exc}") from None
    if len(records) > 1 and len({r.names for r in records}) > 1:  # a roving hammer, or files that are not one test
        from modal.roving import roving_points

        plans = [_plan_record(scene, record) for record in records]  # as `modal fit` plans each file
        try:
            points = roving_points(records, plans)
        except ModalError as exc:
            raise SceneError(f"{scene.source}: key 'frf.file' = {cfg['file']!r}: {exc}") from None
        if points is not None:
            return RovingFiles(tuple(records), tuple(plans), tuple(points))
    try:
        record = join_takes(records)  # several files: takes of one test
    except ModalError as exc:
        raise SceneError(f"{scene.source}: key 'frf.file' = {cfg['file']!r}: {exc}") from None
    return record, _plan_record(scene, record)


@dataclass(frozen=True)
class RovingFiles:
    """The files of a roving-hammer test in [frf] file, as the scene's check read them
    (:func:`modal.roving.roving_points`): each file's record and channels, and the hit points with the
    indices of the files hit at each."""

    records: tuple
    plans: tuple
    points: tuple


def _plan_record(scene: Scene, record):
    """A record's channels as [frf] names them (:func:`modal.time_frf.plan_time_frf`), each named channel
    looked up under its own key, so that an error names it."""
    from modal.errors import ModalError
    from modal.time_frf import plan_time_frf

    cfg = scene.section("frf")
    for key, spec in [("excitation", cfg.get("excitation"))] + [
            (f"response[{i}]", r) for i, r in enumerate(cfg.get("response", []))]:
        if spec is None:
            continue
        try:
            record.channel_index(spec)
        except ModalError as exc:
            raise SceneError(f"{scene.source}: key 'frf.{key}' = {spec!r}: {exc}") from None
    try:
        return plan_time_frf(record, _time_options(cfg), option=lambda name: f"frf.{name}")
    except ModalError as exc:
        raise SceneError(f"{scene.source}: key 'frf': {exc}") from None


def _frf_paths(scene: Scene) -> list:
    """The files [frf] file names: one, or several (FRFs on one axis, takes of one test, or a roving hammer's)."""
    names = scene.section("frf")["file"]
    return [scene.folder / name for name in (names if isinstance(names, list) else [names])]


def _time_options(cfg: dict):
    """The [frf] time options as the attributes :mod:`modal.time_frf` reads (the command line's names)."""
    from types import SimpleNamespace

    values = {name: cfg.get(name) for name in TIME_FRF_OPTIONS}
    values["impact"] = bool(values["impact"])
    values["excitation"] = None if values["excitation"] is None else str(values["excitation"])
    values["response"] = None if values["response"] is None else [str(r) for r in values["response"]]
    return SimpleNamespace(kind=cfg.get("kind"), **values)


#: [oma] keys that are the options of ``python -m modal oma`` (:class:`modal.operational.files.OMAOptions`)
OMA_OPTIONS = ("band_hz", "method", "reference_channels", "rotor_speed_hz", "max_order")


def _oma_options(scene: Scene):
    from modal.errors import ModalError
    from modal.operational.files import OMAOptions

    cfg = scene.section("oma")
    try:
        return OMAOptions(**{k: cfg[k] for k in OMA_OPTIONS if k in cfg})
    except ModalError as exc:
        raise SceneError(f"{scene.source}: key 'oma': {exc}") from None


def check_oma(scene: Scene) -> None:
    """[oma] options as ``modal oma`` checks them, and a mass change given whole (the record and its masses)."""
    cfg = scene.section("oma")
    if ("mass_change" in cfg) != ("added_mass_kg" in cfg):
        given, missing = ("mass_change", "added_mass_kg") if "mass_change" in cfg else ("added_mass_kg", "mass_change")
        raise SceneError(f"{scene.source}: key 'oma.{missing}' is missing; oma.{given} needs it (a mass-change test "
                         "is the record with the masses added and the masses, {channel = kg})")
    _oma_options(scene)


def read_balance_job(scene: Scene):
    """The [balance] readings, parsed and checked (shapes, units, files) before any work; None for a
    simulated study ([balance.simulate]), whose readings the stage makes."""
    from modal.errors import ModalError

    from ..influence.job import parse_job

    cfg = scene.section("balance")
    if "simulate" in cfg:
        return None
    try:
        return parse_job(cfg, scene.source, scene.folder, key_prefix="balance.")
    except ModalError as exc:
        raise SceneError(str(exc)) from None


# -------------------------------------------------------------------- stages
def stage_frf(scene: Scene) -> modal.FRF:
    """Read the FRF file, estimate the FRF of a time record (an :class:`~modal.estimate.EstimatedFRF`), or
    make the synthetic FRF."""
    cfg = scene.section("frf")
    timed = scene.inputs["frf"]
    if isinstance(timed, RovingFiles):  # each hit point estimated from its own file(s), joined as `modal fit` does
        from modal.time_frf import estimate_roving

        return estimate_roving(timed.records, timed.plans, list(timed.points), _time_options(cfg))
    if timed is not None:  # a time record, read and checked with the scene
        from modal.time_frf import estimate_time_frf

        record, plan = timed
        return estimate_time_frf(record, plan, _time_options(cfg))
    if "file" in cfg:
        from modal.io import read_frf

        hints = {k: cfg[k] for k in FRF_READ_OPTIONS if k in cfg}
        paths = _frf_paths(scene)
        return read_frf(paths[0] if len(paths) == 1 else paths, **hints)
    syn = cfg["synthetic"]
    from modal.synthetic import add_noise, modal_frf

    f = np.linspace(syn.get("f_min_hz", 0.0), syn["f_max_hz"], syn["n_lines"] + 1)[1:]
    n_modes = len(syn["natural_frequency_hz"])
    for key in ("damping_ratio", "modal_constant"):
        if len(syn[key]) != n_modes:
            raise SceneError(f"{scene.source}: key 'frf.synthetic.{key}' has {len(syn[key])} values; "
                             f"expected one per natural frequency ({n_modes})")
    frf = modal_frf(f, syn["natural_frequency_hz"], syn["damping_ratio"], syn["modal_constant"],
                    kind=syn.get("kind", "receptance"), response_points=["1"], reference_points=["1"])
    return add_noise(frf, syn.get("noise", 0.0), seed=syn.get("seed", 0)) if syn.get("noise", 0.0) > 0 else frf


def stage_identify(scene: Scene, frf: modal.FRF) -> modal.IdentificationResult:
    """Identify the modes of the FRF."""
    cfg = scene.section("identify", {})
    bands = [tuple(b) for b in cfg["bands_hz"]] if "bands_hz" in cfg else None
    driving = None
    if "driving_point" in cfg:
        from modal.errors import ModalError
        from modal.fitting import driving_channels

        declared = cfg["driving_point"] if isinstance(cfg["driving_point"], list) else [cfg["driving_point"]]
        try:
            driving = driving_channels(frf, declared, option="key 'identify.driving_point' =",
                                       where=f"{scene.source}: ")
        except ModalError as exc:
            raise SceneError(str(exc)) from None
    result = modal.identify(frf, cfg.get("method", "nls"), bands_hz=bands, driving_point=driving,
                            min_prominence_db=cfg.get("min_prominence_db", 6.0), max_modes=cfg.get("max_modes"))
    from modal.roving import RovingEstimate

    if isinstance(frf, RovingEstimate):  # what the hit points' estimates shared, as `modal fit` says it
        from dataclasses import replace

        result = replace(result, settings={**result.settings, "roving_hammer": frf.join_note})
    return result


def stage_oma(scene: Scene) -> modal.IdentificationResult:
    """Identify the modes of an operational test, scaled to unit modal mass when [oma] gives a mass change."""
    from modal.operational.files import oma_file, scale_files

    cfg = scene.section("oma")
    options = _oma_options(scene)
    if "mass_change" in cfg:
        result, _ = scale_files(scene.folder / cfg["file"], scene.folder / cfg["mass_change"], cfg["added_mass_kg"],
                                options)
        return result
    return oma_file(scene.folder / cfg["file"], options)


def stage_drive(scene: Scene) -> DriveStage:
    """Belt stages in series and the shaft's hand-over (speed, stiffness, critical-speed margin)."""
    from ..drive.belt import BeltStageSpec, belt_drive
    from ..drive.shaft import ShaftGeometry, rotor_handover

    from modal.errors import ModalError

    cfg = scene.section("drive")
    specs = [BeltStageSpec(**{k: v for k, v in s.items()}) for s in cfg["stages"]]
    try:
        drive = belt_drive(cfg["motor_speed_rpm"], cfg["power_w"], specs,
                           service_factor=cfg.get("service_factor", 1.0))
    except ModalError as exc:
        raise SceneError(f"{scene.source}: key 'drive': {exc}") from None
    handover = None
    shaft = cfg.get("shaft")
    if shaft:
        last = drive.stages[-1]
        kwargs = {"youngs_modulus_pa": shaft["youngs_modulus_pa"]} if "youngs_modulus_pa" in shaft else {}
        try:
            geometry = ShaftGeometry(shaft["length_m"], shaft["bearing_a_m"], shaft["bearing_b_m"])
            handover = rotor_handover(last.driven_speed_rpm * TWO_PI / 60, geometry, shaft["diameter_m"],
                                      shaft["rotor_position_m"], shaft["rotor_mass_kg"], **kwargs)
        except ModalError as exc:
            raise SceneError(f"{scene.source}: key 'drive.shaft': {exc}") from None
    return DriveStage(drive, handover)


def _check_one_mode(scene: Scene, rotor) -> None:
    """A Jeffcott rotor's M, k and c are those of one mode: references to different modes are refused."""
    modes = {key: rotor[key].mode for key in ("M", "k", "c")
             if isinstance(rotor[key], Reference) and rotor[key].source == "identified"}
    if len(set(modes.values())) > 1:
        taken = ", ".join(f"{key} from mode {mode}" for key, mode in modes.items())
        raise SceneError(f"{scene.source}: key 'rotor': {taken}; expected M, k and c of one mode (the rotor's "
                         "bending mode): a rotor built from several modes has a natural frequency none of them has")


#: relative difference between the rotor's sqrt(k/M) and the identified mode's natural frequency above which
#: the scene warns: a hammer test's frequency is known to a fraction of a percent, so 10 % is a wrong number
#: (a mass weighed without the hub, a stiffness from the wrong support), not scatter
NATURAL_FREQUENCY_MISMATCH = 0.10


def _check_natural_frequency(scene: Scene, rotor, params: ADBParameters, identified) -> None:
    """Warn when a rotor mixing identified and given values has a natural frequency the test did not find."""
    refs = [rotor[key] for key in ("M", "k") if isinstance(rotor[key], Reference) and rotor[key].source == "identified"]
    if identified is None or len(refs) != 1:
        return  # both from the mode: sqrt(k/M) is its frequency by construction; neither: nothing to compare
    mode = identified[refs[0].mode - 1]
    measured = TWO_PI * float(mode.natural_frequency_hz)
    model = math.sqrt(params.k / (params.M + params.n * params.m))
    if abs(model / measured - 1.0) > NATURAL_FREQUENCY_MISMATCH:
        given = "M" if refs[0].field == "stiffness" else "k"
        warn(f"{scene.source}: key 'rotor.{given}': the rotor's natural frequency sqrt(k/(M + n m)) = "
             f"{model / TWO_PI:.4g} Hz differs by {100 * (model / measured - 1):+.0f} % from mode {refs[0].mode}'s "
             f"{measured / TWO_PI:.4g} Hz, which {refs[0].text!r} comes from; expected the rotor's own "
             f"{'mass' if given == 'M' else 'stiffness'} (the ball balancer's stability follows that frequency)")


def stage_rotor(scene: Scene, identify=None, drive=None, oma=None) -> RotorStage:
    """Ball-balancer parameters, with M, k, c resolved from identification (an impact or an operational test)
    or the drive."""
    identify = identify if identify is not None else oma
    rotor, adb = scene.section("rotor"), scene.section("adb")
    values, sources = {}, []
    for key in ("M", "k", "c"):
        raw = rotor[key]
        values[key] = resolve(raw, f"rotor.{key}", scene, identify, drive)
        used = (f" ({describe_mode(identify, raw, scene)})"
                if isinstance(raw, Reference) and raw.source == "identified" else "")
        sources.append(f"{key} = {raw.text if isinstance(raw, Reference) else raw!r}{used}")
    _check_one_mode(scene, rotor)
    std = {"k": 0.0, "c": 0.0, "M": 0.0}
    modes_of: dict[str, int] = {}
    correlation = np.eye(3)
    if identify is not None:
        channel = _channel(identify, scene)
        for key, field in (("M", "mass"), ("k", "stiffness"), ("c", "damping")):
            raw = rotor[key]
            if isinstance(raw, Reference) and raw.source == "identified" and raw.field == field:
                mode = identify[raw.mode - 1]
                value = getattr(identified_std(mode, channel if np.ndim(mode.mass_kg) else None), key)
                std[key] = value if math.isfinite(value) else 0.0
                modes_of[key] = raw.mode
        # k, c, M of one identified mode are correlated (they share ωn, ζ and the modal constant)
        for i, a in enumerate(STD_ORDER):
            for j, b in enumerate(STD_ORDER):
                if i != j and a in modes_of and modes_of.get(b) == modes_of[a]:
                    mode = identify[modes_of[a] - 1]
                    r = identified_correlation(mode, channel if np.ndim(mode.mass_kg) else None)
                    correlation[i, j] = 0.0 if r is None else r[i, j]
    M = values["M"]
    if isinstance(rotor["M"], Reference) and rotor.get("mass_includes_balls", True):
        M -= adb["n"] * adb["m"]
        sources[0] += (f"; M = {values['M']:.6g} kg identified less the {adb['n']} balls ({adb['n']} x {adb['m']:g} kg:"
                       " mass_includes_balls)")
        if M <= 0:
            raise SceneError(f"{scene.source}: key 'rotor.M': identified mass {values['M']:.6g} kg minus the balls "
                             f"({adb['n']} x {adb['m']} kg) is not positive")
    params = ADBParameters(M=M, m=adb["m"], n=adb["n"], R=adb["R"], e=rotor["e"], k=values["k"], c=values["c"],
                           D=adb["D"])
    _check_natural_frequency(scene, rotor, params, identify)
    return RotorStage(params, ParameterStd(**std, correlation=correlation), tuple(sources))


#: fastest speed of the balls' race accepted (m/s): a spinning steel ring bursts near √(σ/ρ), about 450 m/s for
#: the strongest steels; ball balancers run 10-150 m/s
MAX_RACE_SPEED_M_S = 500.0


def _check_race_speed(scene: Scene, params: ADBParameters, speed_rad_s: float, what: str) -> None:
    """A race that would burst at ``speed_rad_s``: a radius in the wrong unit."""
    race_speed = params.R * speed_rad_s
    if race_speed > MAX_RACE_SPEED_M_S:
        raise SceneError(f"{scene.source}: key 'adb.R' = {params.R:.6g} m at {speed_rad_s:.6g} rad/s ({what}) moves "
                         f"the balls at {race_speed:.4g} m/s; expected below {MAX_RACE_SPEED_M_S:.0f} m/s (a steel "
                         "race bursts near 450 m/s): a radius in mm or cm written as m?")


def stage_adb_stability(scene: Scene, rotor: RotorStage) -> StabilityStage:
    """Stable speed intervals of the balanced state, and max Re λ against speed."""
    from ..adb import balanced_stability

    cfg = scene.section("adb.stability", {})
    params = rotor.params
    wn = params.natural_frequency_rad_s
    # the balls balance only above the natural frequency: a race that cannot reach it leaves nothing to study
    _check_race_speed(scene, params, wn, "the rotor's natural frequency")
    speed_max = cfg.get("speed_max_rad_s", cfg.get("speed_max_ratio", 4.0) * wn)
    can = params.can_balance
    if not can:
        raise SceneError(f"{scene.source}: [adb] cannot balance: n·m·R = {params.n * params.m * params.R:.3g} kg m "
                         f"< M·e = {params.M * params.e:.3g} kg m; use more or heavier balls or a larger race")
    intervals = stable_speed_intervals(params, speed_max, grid_points=cfg.get("grid_points", 2000))
    speeds = np.linspace(0.05 * wn, speed_max, 400)
    curve = balanced_stability(params, speeds)
    return StabilityStage(intervals, speeds, np.asarray(curve.max_real_part_per_s), can)


def stage_adb_response(scene: Scene, rotor: RotorStage, drive=None) -> SimulationResult:
    """Time response: constant speed, or a run-up through the critical speed."""
    cfg = scene.section("adb.response")
    if "speed_rad_s" in cfg:
        speed = resolve(cfg["speed_rad_s"], "adb.response.speed_rad_s", scene, drive=drive)
    else:
        if "speed_end_rad_s" not in cfg or "ramp_s" not in cfg:
            raise SceneError(f"{scene.source}: key 'adb.response' needs speed_rad_s, or speed_end_rad_s and ramp_s")
        end = resolve(cfg["speed_end_rad_s"], "adb.response.speed_end_rad_s", scene, drive=drive)
        speed = LinearRunUp(cfg.get("speed_start_rad_s", 0.0), end, cfg["ramp_s"])
    top = speed if isinstance(speed, (int, float)) else max(speed.start_speed, speed.end_speed)
    _check_race_speed(scene, rotor.params, float(top), "the response's top speed")
    t_end = cfg.get("t_end_s", 2 * cfg.get("ramp_s", 1.0))
    return simulate(rotor.params, speed, t_end, cfg.get("initial_ball_angles_rad"), rtol=cfg.get("rtol", 1e-8))


#: fastest mean piston speed accepted (m/s): compressors run 2-6 m/s, racing engines about 25 m/s
MAX_MEAN_PISTON_SPEED_M_S = 30.0
#: below this mean piston speed (m/s) a slider-crank is warned of: the slowest machines (large gas compressors,
#: oil-field pump jacks) run about 0.5 m/s; a speed in rev/s or Hz written as rpm lands near 0.04 m/s
MIN_MEAN_PISTON_SPEED_M_S = 0.2


def _mean_piston_speed_m_s(cfg) -> float:
    """Mean piston speed of the [compressor] section's crank, m/s: two strokes of twice the radius a turn."""
    return 4.0 * cfg["crank_radius_m"] * cfg["speed_rpm"] / 60.0


def check_compressor(scene: Scene) -> None:
    """A crank whose mean piston speed no machine reaches: a radius in the wrong unit."""
    cfg = scene.section("compressor")
    piston_speed = _mean_piston_speed_m_s(cfg)
    if piston_speed > MAX_MEAN_PISTON_SPEED_M_S:
        raise SceneError(f"{scene.source}: key 'compressor.crank_radius_m' = {cfg['crank_radius_m']:.6g} m at "
                         f"{cfg['speed_rpm']:.6g} rpm moves the piston at {piston_speed:.4g} m/s on average; expected "
                         f"below {MAX_MEAN_PISTON_SPEED_M_S:.0f} m/s (the fastest engines run about 25 m/s): "
                         "a radius in mm written as m?")


def check_mounts(scene: Scene) -> None:
    """A body lighter than the crank's moving parts it holds: masses in the wrong unit."""
    cfg = scene.section("compressor")
    moving = cfg["rotating_mass_kg"] + cfg["reciprocating_mass_kg"]
    body_mass = scene.section("compressor.body")["mass_kg"]
    if moving >= body_mass:
        raise SceneError(f"{scene.source}: key 'compressor.body.mass_kg' = {body_mass:.6g} kg is not above the "
                         f"crank's moving masses ({moving:.6g} kg), which are part of the body; expected the whole "
                         "body's mass: masses in g written as kg?")


#: largest static sag of the body on its mounts accepted (m): the softest spring isolators (near 0.7 Hz) sag about
#: half a metre, a compressor's mounts a few millimetres
MAX_MOUNT_SAG_M = 0.5


def _check_sag(scene: Scene, body_mass_kg: float, mounts) -> None:
    """A body that would sink further under its own weight than any isolator lets it, even along the mounts'
    stiffest direction (whichever is vertical): a stiffness or a mass in the wrong unit."""
    stiffest = max(sum(float(m.stiffness_n_per_m[axis]) for m in mounts) for axis in range(3))
    sag = body_mass_kg * STANDARD_GRAVITY_M_S2 / stiffest if stiffest > 0 else math.inf
    if sag > MAX_MOUNT_SAG_M:
        raise SceneError(f"{scene.source}: key 'compressor.mounts': the {body_mass_kg:.6g} kg body would sag "
                         f"{sag:.3g} m under its weight even along the mounts' stiffest direction ({stiffest:.6g} N/m "
                         f"together); expected below {MAX_MOUNT_SAG_M:g} m (the softest spring isolators): a stiffness "
                         "in kN/m written as N/m, or a mass in g written as kg?")


def stage_compressor(scene: Scene) -> CompressorStage:
    """Exact optimum counterweight of the slider-crank (lightest: r_c = r, or a given k)."""
    from ..compressor.crank import SliderCrank, counterweight_on_curve, optimal_counterweight

    cfg = scene.section("compressor")
    piston_speed = _mean_piston_speed_m_s(cfg)
    if piston_speed < MIN_MEAN_PISTON_SPEED_M_S:  # (warned here, where the stage's warnings are kept with it)
        warn(f"{scene.source}: key 'compressor.speed_rpm' = {cfg['speed_rpm']:.6g} rpm with crank_radius_m = "
             f"{cfg['crank_radius_m']:.6g} m moves the piston at {piston_speed:.3g} m/s on average, slower than any "
             f"machine runs (above {MIN_MEAN_PISTON_SPEED_M_S:g} m/s): a speed in rev/s or Hz written as rpm? The "
             "balance fraction does not depend on the speed; the shaking forces scale with its square")
    mech = SliderCrank(cfg["crank_radius_m"], cfg["rod_length_m"], cfg["rotating_mass_kg"],
                       cfg["reciprocating_mass_kg"], harmonics=cfg.get("harmonics", (1, 2)))
    optimum = optimal_counterweight(mech, cfg["speed_rpm"])
    chosen = counterweight_on_curve(mech, optimum, k=cfg["counterweight_k"]) if "counterweight_k" in cfg \
        else counterweight_on_curve(mech, optimum)
    return CompressorStage(mech, optimum, float(chosen.mass_kg), float(chosen.radius_m), cfg["speed_rpm"])


def stage_mounts(scene: Scene, compressor: CompressorStage, identify=None) -> MountsStage:
    """Body on mounts: natural frequencies and the base force before and after balancing."""
    from ..compressor.mounts import Mount, MountedBody, RigidBody, balancing_comparison, natural_modes

    body_cfg = scene.section("compressor.body")
    mounts = []
    for i, m in enumerate(scene.section("compressor.mounts")):
        vectors = {}
        for key in ("stiffness_n_per_m", "damping_n_s_per_m"):
            raw = m.get(key, [0.0, 0.0, 0.0])
            if isinstance(raw, Reference):
                value = resolve(raw, f"compressor.mounts[{i}].{key}", scene, identify)
                raw = [value, value, value]
            vectors[key] = raw
        mounts.append(Mount(m["position_m"], vectors["stiffness_n_per_m"], vectors["damping_n_s_per_m"]))
    _check_sag(scene, body_cfg["mass_kg"], mounts)
    system = MountedBody(RigidBody(body_cfg["mass_kg"], np.array(body_cfg["inertia_kg_m2"])), tuple(mounts),
                         damping_ratio=body_cfg.get("damping_ratio", 0.0))
    modes = natural_modes(system)
    comparison = balancing_comparison(system, compressor.mechanism, compressor.speed_rpm, body_cfg["crank_centre_m"],
                                      compressor.counterweight_mass_kg, compressor.counterweight_radius_m)
    return MountsStage(system, np.asarray(modes.natural_frequency_hz), comparison)


@dataclass(frozen=True)
class BalanceStage:
    """Field balancing: the report of the scene's method and, for [balance.simulate], the study."""

    report: object  # balancer.influence.BalanceReport
    study: object | None  # balancer.influence.study.FieldBalancingStudy


def stage_balance(scene: Scene, rotor: RotorStage | None = None, adb_response=None) -> BalanceStage:
    """Correction, split, predicted residual and ISO verdict; or the simulated study on the [rotor]."""
    from ..influence.job import balance
    from ..influence.readings import MASS_UNITS
    from ..influence.study import field_balancing_study

    cfg = scene.section("balance")
    iso = cfg.get("iso", {})
    options = {"weights": cfg.get("weights"), "max_unbalance_kg_m": cfg.get("max_unbalance_kg_m"),
               "holes": cfg.get("holes"), "positions_deg": cfg.get("positions_deg"),
               "grade_mm_s": iso.get("grade_mm_s"), "rotor_mass_kg": iso.get("rotor_mass_kg"),
               "speed_rpm": iso.get("speed_rpm"), "distances_m": tuple(iso["distances_m"]) if "distances_m" in iso else None,
               "weight_resolution_kg": (cfg["weight_resolution"] * MASS_UNITS[cfg.get("mass_units", "g")]
                                        if "weight_resolution" in cfg else None),
               "reading_noise": cfg.get("reading_noise")}
    method = cfg.get("method", "least_squares")
    sim = cfg.get("simulate")
    if sim is None:  # the readings as read when the scene was checked
        return BalanceStage(balance(scene.inputs["balance"], method, **options), None)
    p = rotor.params
    # the simulated rotor's truth (default: the identified [rotor] itself); alpha_model uses the identified k, c, M
    true_M, true_k, true_c = (sim.get("rotor_mass_kg", p.M), sim.get("stiffness_n_per_m", p.k),
                              sim.get("damping_n_s_per_m", p.c))
    radius = cfg["radius_m"][0] if isinstance(cfg["radius_m"], list) else cfg["radius_m"]
    study = field_balancing_study(true_M, true_k, true_c, p.e, sim["speeds_rad_s"], model_k_c_M=(p.k, p.c, p.M),
                                  trial_mass=sim["trial_mass"],
                                  trial_angle_deg=sim.get("trial_angle_deg", 0.0), radius_m=radius,
                                  noise=sim.get("noise", 0.05), seed=sim.get("seed", 0), units=cfg["units"],
                                  mass_units=cfg.get("mass_units", "g"), adb=adb_response)
    report = study.minmax if method == "minmax" else study.least_squares
    if any(options[k] is not None for k in ("holes", "positions_deg", "grade_mm_s", "weight_resolution_kg")):
        from ..influence.study import simulated_job

        job = simulated_job(true_M, true_k, true_c, p.e, sim["speeds_rad_s"], sim["trial_mass"], sim.get("trial_angle_deg", 0.0),
                            radius, sim.get("noise", 0.05), sim.get("seed", 0), cfg["units"], cfg.get("mass_units", "g"))
        report = balance(job, method, **options)
    return BalanceStage(report, study)

