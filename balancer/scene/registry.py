"""Every stage of a scene, declared once.

A :class:`Stage` says all there is to know about one stage: the configuration it owns
(its keys and their rules), the sections it needs, the stages whose results it takes,
the files it reads, the function that computes it, its figures and the results they
read, and its rows in the summary.  Its ``name`` is at once the ``[outputs]`` entry,
the archive group its result is stored under and the keyword its dependents receive
that result by.  Checking a scene (:mod:`.schema`), planning and hashing, running
(:mod:`.runner`), plotting (:mod:`.plots` and the plotting processes) and summaries
(:mod:`.summary`) all read :data:`REGISTRY`; a new stage is one more entry here (and
its functions).

Functions are named as ``"module:function"`` strings and imported when first used:
the plotting processes read this registry without loading the stages' computations,
and the runner loads a stage's module only when the stage runs.

This module imports only the standard library and :mod:`.rules`.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from typing import Any, Mapping

from .rules import BOOL, FILES, INT, NONNEG, NUM, POS, STR, choice, complex_value, list_of, ref_or

__all__ = ["Stage", "REGISTRY", "STAGES", "load", "result_modules"]

_KINDS = choice("receptance", "mobility", "accelerance")
#: modal.estimate.ESTIMATORS and WINDOWS (the time options' choices; a test keeps them equal)
_ESTIMATORS = ("H1", "H2", "Hv")
_WINDOWS = ("rect", "hann", "force", "exponential")


def _harmonics(v):
    return v if v == "exact" else tuple(list_of(INT)(v))


def _mount_vector(field):
    """A mount's stiffness or damping (``field``): three values (x, y, z), or one identified value for all three."""
    def check(v):
        return ref_or(POS, ("identified",), (field,))(v) if isinstance(v, str) else list_of(NONNEG, length=3)(v)
    return check


def _time_channel(v):
    """A channel of a time record: its number (from 1, in file order) or its name."""
    if isinstance(v, str):
        return STR(v)
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise ValueError("a channel number from 1 (in file order) or a channel name")
    return v


def _positive_int(v):
    if INT(v) < 1:
        raise ValueError("a positive integer")
    return v


def _fraction(v):
    v = NONNEG(v)
    if v >= 1:
        raise ValueError("a fraction 0 <= f < 1")
    return v


def _channel_name(v):
    """A channel as ``modal oma`` names it: its number counted from 1 in the file's order, or its name."""
    if isinstance(v, bool) or not isinstance(v, (int, str)) or (isinstance(v, int) and v < 1) or v == "":
        raise ValueError("a channel number counted from 1, or a channel name")
    return str(v)


def _added_masses(v):
    """``{channel: kg}``: the masses added for the second record of a mass-change test."""
    if not isinstance(v, dict) or not v:
        raise ValueError("a table {channel = kg, ...} of the added masses (channels numbered from 1, or names)")
    return {_channel_name(k): POS(kg) for k, kg in v.items()}


def _channel_number(v):
    """A channel counted from 1 (as the command line and the results table number them)."""
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise ValueError("a channel number counted from 1")
    return v


def _channels(v):
    """Channels by number (counted from 1) or response point id: one, or a list of them."""
    def one(x):
        if isinstance(x, str) and x.strip():
            return x
        if isinstance(x, bool) or not isinstance(x, int) or x < 1:
            raise ValueError("a channel number counted from 1 or a response point id, or a list of them")
        return x
    return list_of(one)(v) if isinstance(v, list) else one(v)


def _radius(v):
    return list_of(POS)(v) if isinstance(v, list) else POS(v)


@dataclass(frozen=True)
class Stage:
    """One stage of a scene.

    Attributes
    ----------
    name : str
        The ``[outputs]`` entry, the archive group of its result and the keyword under which
        the stages that depend on it receive that result.
    run : str
        ``"module:function"``: ``function(scene, **results of its dependencies) -> result``.
    config : mapping
        The configuration the stage owns: dotted key -> rule (a callable, a table of rules,
        or ``[table]`` for an array of tables).  These keys make up the scene's schema, and
        their values (with the bytes of ``files`` and the dependencies' hashes) the stage's
        inputs hash.  Values that may be references are found in them.
    needs : tuple of str
        Sections the scene must have for the stage to run (checked for every stage an
        output needs).
    required : mapping
        Section path -> the keys it must have when the scene gives it.
    depends : tuple of str
        Stages whose results it always takes (references add the stage they name).
    depends_when : tuple of (str, tuple of str)
        Stages it takes only when the scene has all of the given sections.
    files : tuple of str
        Dotted keys naming files (relative to the scene) whose bytes are inputs too; hashed
        as ``<last key>_sha256``.
    prepare : str or None
        ``"module:function"``: ``function(scene) -> value`` called when the scene is checked
        (when it has the ``needs`` sections): checks beyond the rules, and reads what only
        reading can check (the balancing readings), once; the value is ``scene.inputs[name]``.
    archive_whole : bool
        Whether the result read back from an archive is all a later stage computes from. When not (an FRF's noise
        model and record influences are not archived), the stage runs again whenever a stage that takes it does.
    figures : str or None
        ``"module:function"``: ``function(results) -> [(name, Figure), ...]``.
    plot_inputs : tuple of str
        The results its figures read: all a plotting process is handed.
    plot_modules : tuple of str
        Modules drawing them imports (the plotting functions and the classes of the pickled
        results), imported once by the plotting process before it forks its helper.
    digest : str or None
        ``"module:function"``: ``function(result) -> dict``, a few headline numbers (JSON-ready, SI).
    rows : str or None
        ``"module:function"``: ``function(result, digest) -> list of str``, its lines of the summary.
    """

    name: str
    run: str
    config: Mapping[str, Any]
    needs: tuple[str, ...] = ()
    required: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    depends: tuple[str, ...] = ()
    depends_when: tuple[tuple[str, tuple[str, ...]], ...] = ()
    files: tuple[str, ...] = ()
    prepare: str | None = None
    archive_whole: bool = True
    figures: str | None = None
    plot_inputs: tuple[str, ...] = ()
    plot_modules: tuple[str, ...] = ()
    digest: str | None = None
    rows: str | None = None


def load(target: str):
    """The object a ``"module:name"`` string names (the module is imported on first use)."""
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


_STAGES = "balancer.scene.stages"
_PLOTS = "balancer.scene.plots"
_SUMMARY = "balancer.scene.summary"

#: the stages in the order they run (every stage after those it may depend on)
REGISTRY: dict[str, Stage] = {stage.name: stage for stage in (
    Stage(
        "frf", run=f"{_STAGES}:stage_frf", needs=("frf",), files=("frf.file",), prepare=f"{_STAGES}:check_frf",
        archive_whole=False,  # the archive holds the FRF and its noise, not its noise model or record influences
        config={"frf": {
            "file": FILES, "kind": _KINDS,
            # the read options of `python -m modal fit`, under the same names
            "frequency_axis": choice("hz", "khz", "rad/s", "cpm", "rpm"), "frequency_step": POS,
            "frequency_start": NONNEG, "layout": STR, "delimiter": STR, "decimal": STR, "dataset": INT,
            # a time record (hammer or shaker test): the time options of `python -m modal fit`, same names
            "excitation": _time_channel, "response": list_of(_time_channel), "impact": BOOL,
            "estimator": choice(*_ESTIMATORS), "window": choice(*_WINDOWS), "exponential_decay_s": POS,
            "segment_length": _positive_int, "overlap": _fraction,
            "synthetic": {
                "natural_frequency_hz": list_of(POS), "damping_ratio": list_of(NONNEG),
                "modal_constant": list_of(complex_value), "kind": _KINDS,
                "f_min_hz": NONNEG, "f_max_hz": POS, "n_lines": INT, "noise": NONNEG, "seed": INT,
            },
        }},
        required={"frf.synthetic": ("natural_frequency_hz", "damping_ratio", "modal_constant", "f_max_hz", "n_lines")},
        figures=f"{_PLOTS}:frf_figures", plot_inputs=("frf",), plot_modules=("modal.estimate.plots",),
        digest=f"{_SUMMARY}:frf_digest", rows=f"{_SUMMARY}:frf_rows"),
    Stage(
        "identify", run=f"{_STAGES}:stage_identify", needs=("frf",), depends=("frf",),
        config={"identify": {
            "method": choice("nls", "circle", "halfpower"), "bands_hz": list_of(list_of(NONNEG, length=2)),
            "channel": _channel_number, "driving_point": _channels, "min_prominence_db": POS, "max_modes": INT,
            "accept_flagged": BOOL,
        }},
        figures=f"{_PLOTS}:identify_figures", plot_inputs=("frf", "identify"),
        plot_modules=("modal.plots", "modal.flags"),
        digest=f"{_SUMMARY}:identify_digest", rows=f"{_SUMMARY}:identify_rows"),
    Stage(
        # an operational test (responses only): the options of `python -m modal oma` under the same names;
        # scaled by mass change (mass_change, added_mass_kg) its modes give k, c, m as an impact test does
        "oma", run=f"{_STAGES}:stage_oma", needs=("oma",), files=("oma.file", "oma.mass_change"),
        prepare=f"{_STAGES}:check_oma",
        config={"oma": {
            "file": STR, "band_hz": list_of(NONNEG, length=2), "method": choice("ssi", "plscf", "fdd", "efdd"),
            "reference_channels": list_of(_channel_name), "rotor_speed_hz": POS, "max_order": INT,
            "mass_change": STR, "added_mass_kg": _added_masses, "channel": _channel_name, "accept_flagged": BOOL,
        }},
        required={"oma": ("file",)},
        digest=f"{_SUMMARY}:identify_digest", rows=f"{_SUMMARY}:identify_rows"),
    Stage(
        "drive", run=f"{_STAGES}:stage_drive", needs=("drive",),
        config={"drive": {
            "motor_speed_rpm": POS, "power_w": POS, "service_factor": POS,
            "stages": [{"driver_diameter_m": POS, "driven_diameter_m": POS, "center_distance_m": POS,
                        "per_belt_rating_w": POS, "name": STR}],
            "shaft": {"length_m": POS, "bearing_a_m": NONNEG, "bearing_b_m": NONNEG, "diameter_m": POS,
                      "rotor_position_m": NONNEG, "rotor_mass_kg": POS, "youngs_modulus_pa": POS},
        }},
        required={"drive": ("motor_speed_rpm", "power_w", "stages"),
                  "drive.stages": ("driver_diameter_m", "driven_diameter_m", "center_distance_m"),
                  "drive.shaft": ("length_m", "bearing_a_m", "bearing_b_m", "diameter_m", "rotor_position_m",
                                  "rotor_mass_kg")},
        figures=f"{_PLOTS}:drive_figures", plot_inputs=("drive",),
        plot_modules=("balancer.drive", "balancer.drive.shaft", _STAGES),
        digest=f"{_SUMMARY}:drive_digest", rows=f"{_SUMMARY}:drive_rows"),
    Stage(
        "rotor", run=f"{_STAGES}:stage_rotor", needs=("rotor", "adb"),
        config={
            "rotor": {"M": ref_or(POS, ("identified",), ("mass",)), "k": ref_or(POS, fields=("stiffness",)),
                      "c": ref_or(NONNEG, ("identified",), ("damping",)),
                      "e": NONNEG, "mass_includes_balls": BOOL},
            "adb.m": POS, "adb.n": INT, "adb.R": POS, "adb.D": NONNEG,
        },
        required={"rotor": ("M", "k", "c", "e"), "adb": ("m", "n", "R", "D")},
        digest=f"{_SUMMARY}:rotor_digest", rows=f"{_SUMMARY}:rotor_rows"),
    Stage(
        "adb_stability", run=f"{_STAGES}:stage_adb_stability", needs=("rotor", "adb"), depends=("rotor",),
        config={"adb.stability": {"speed_max_rad_s": POS, "speed_max_ratio": POS, "grid_points": INT}},
        figures=f"{_PLOTS}:stability_figures", plot_inputs=("adb_stability",),
        plot_modules=(_STAGES,),  # the stage results' classes (StabilityStage, ...)
        digest=f"{_SUMMARY}:stability_digest", rows=f"{_SUMMARY}:stability_rows"),
    Stage(
        "adb_response", run=f"{_STAGES}:stage_adb_response", needs=("rotor", "adb", "adb.response"),
        depends=("rotor",),
        config={"adb.response": {
            "speed_rad_s": ref_or(POS, ("drive",), ("speed",)), "speed_start_rad_s": NONNEG,
            "speed_end_rad_s": ref_or(POS, ("drive",), ("speed",)), "ramp_s": POS, "t_end_s": POS,
            "initial_ball_angles_rad": list_of(NUM), "rtol": POS,
        }},
        figures=f"{_PLOTS}:response_figures", plot_inputs=("adb_response", "rotor"),
        plot_modules=("balancer.adb.plots", _STAGES),
        digest=f"{_SUMMARY}:response_digest", rows=f"{_SUMMARY}:response_rows"),
    Stage(
        "compressor", run=f"{_STAGES}:stage_compressor", needs=("compressor",), prepare=f"{_STAGES}:check_compressor",
        config={"compressor.crank_radius_m": POS, "compressor.rod_length_m": POS,
                "compressor.rotating_mass_kg": NONNEG, "compressor.reciprocating_mass_kg": NONNEG,
                "compressor.speed_rpm": POS, "compressor.harmonics": _harmonics, "compressor.counterweight_k": NONNEG},
        required={"compressor": ("crank_radius_m", "rod_length_m", "rotating_mass_kg", "reciprocating_mass_kg",
                                 "speed_rpm")},
        figures=f"{_PLOTS}:compressor_figures", plot_inputs=("compressor",),
        plot_modules=("balancer.compressor.crank_plots", _STAGES),
        digest=f"{_SUMMARY}:compressor_digest", rows=f"{_SUMMARY}:compressor_rows"),
    Stage(
        "mounts", run=f"{_STAGES}:stage_mounts", needs=("compressor", "compressor.body", "compressor.mounts"),
        depends=("compressor",), prepare=f"{_STAGES}:check_mounts",
        config={
            "compressor.body": {"mass_kg": POS, "inertia_kg_m2": list_of(list_of(NUM, length=3), length=3),
                                "crank_centre_m": list_of(NUM, length=3), "damping_ratio": NONNEG},
            "compressor.mounts": [{"position_m": list_of(NUM, length=3),
                                   "stiffness_n_per_m": _mount_vector("stiffness"),
                                   "damping_n_s_per_m": _mount_vector("damping")}],
        },
        required={"compressor.body": ("mass_kg", "inertia_kg_m2", "crank_centre_m"),
                  "compressor.mounts": ("position_m", "stiffness_n_per_m")},
        figures=f"{_PLOTS}:mounts_figures", plot_inputs=("mounts",),
        plot_modules=("balancer.compressor.mounts", _STAGES),
        digest=f"{_SUMMARY}:mounts_digest", rows=f"{_SUMMARY}:mounts_rows"),
    Stage(
        "balance", run=f"{_STAGES}:stage_balance", needs=("balance",), files=("balance.readings",),
        prepare=f"{_STAGES}:read_balance_job",
        # [balance.simulate] balances the simulated [rotor] and, given a constant-speed
        # [adb.response], compares with the ball balancer at that speed
        depends_when=(("rotor", ("balance.simulate",)),
                      ("adb_response", ("balance.simulate", "adb.response.speed_rad_s"))),
        config={"balance": {
            "readings": STR, "units": STR, "mass_units": choice("g", "kg"), "radius_m": _radius,
            "sensors": list_of(STR),
            "initial": {"amplitude": list_of(NONNEG), "phase_deg": list_of(NUM)},
            "trial": [{"mass": POS, "angle_deg": NUM, "amplitude": list_of(NONNEG), "phase_deg": list_of(NUM)}],
            "after": {"amplitude": list_of(NONNEG), "phase_deg": list_of(NUM)},
            "method": choice("least_squares", "minmax"), "weights": list_of(POS), "max_unbalance_kg_m": POS,
            "holes": INT, "positions_deg": list_of(NUM), "weight_resolution": POS, "reading_noise": POS,
            "iso": {"grade_mm_s": POS, "rotor_mass_kg": POS, "speed_rpm": POS, "distances_m": list_of(NONNEG, length=2)},
            "simulate": {"speeds_rad_s": list_of(POS), "trial_mass": POS, "trial_angle_deg": NUM, "noise": NONNEG,
                         "seed": INT, "rotor_mass_kg": POS, "stiffness_n_per_m": POS, "damping_n_s_per_m": NONNEG},
        }},
        required={"balance": ("units", "radius_m"), "balance.iso": ("grade_mm_s", "rotor_mass_kg", "speed_rpm"),
                  "balance.simulate": ("speeds_rad_s", "trial_mass")},
        figures=f"{_PLOTS}:balance_figures", plot_inputs=("balance",),
        plot_modules=("balancer.influence.plots", "balancer.influence.study", _STAGES),
        digest=f"{_SUMMARY}:balance_digest", rows=f"{_SUMMARY}:balance_rows"),
)}

#: the stages' names, in the order they run
STAGES = tuple(REGISTRY)


def result_modules(scene, stages) -> tuple[str, ...]:
    """Modules a plotting process needs beyond the ``plot_modules`` of ``stages`` to read what this scene's figures
    are handed: an FRF estimated from a time record (``modal.estimate``'s EstimatedFRF, or ``modal.roving``'s
    RovingEstimate for a roving hammer's files) where a figure reads the frf; nothing for an FRF file or a
    synthetic FRF."""
    timed = scene.inputs.get("frf") is not None
    wanted = timed and any("frf" in REGISTRY[s].plot_inputs for s in stages)
    return ("modal.estimate", "modal.roving") if wanted else ()
