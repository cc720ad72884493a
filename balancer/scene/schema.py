"""Scene files: the TOML schema, validation before any work, and references.

A scene describes one case. Every section is optional except ``[outputs]``;
the runner only does the stages the outputs need. Values that come from an
earlier stage are written as references:

* ``"identified:mode1.stiffness"`` (also ``.damping``, ``.mass``,
  ``.frequency``, ``.damping_ratio``): mode 1 of ``[identify]``, on the channel
  ``[identify] channel`` (default: the first driving point);
* ``"drive:speed"`` (rad/s) and ``"drive:stiffness"`` (N/m): the drive's
  hand-over to the rotor.

Every problem is reported as one :class:`~modal.errors.SceneError` naming the
file, the key and what was expected.
"""
from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from modal.errors import SceneError

__all__ = ["Scene", "load_scene", "parse_scene", "STAGES", "DEPENDS", "Reference", "parse_reference"]

#: every stage and the sections its configuration comes from
STAGES = ("frf", "identify", "drive", "rotor", "adb_stability", "adb_response", "compressor", "mounts", "balance")
#: fixed dependencies (references add ``identify`` / ``drive`` where used)
DEPENDS = {
    "frf": (), "identify": ("frf",), "drive": (), "rotor": (), "adb_stability": ("rotor",),
    "adb_response": ("rotor",), "compressor": (), "mounts": ("compressor",),
    "balance": (),  # [balance.simulate] adds rotor (and adb_response when configured): see dependencies
}
IDENTIFIED_FIELDS = {
    "stiffness": "stiffness_n_per_m", "damping": "damping_n_s_per_m", "mass": "mass_kg",
    "frequency": "natural_frequency_hz", "damping_ratio": "damping_ratio",
}
DRIVE_FIELDS = {"speed": "speed_rad_s", "stiffness": "stiffness_n_per_m"}
_REF = re.compile(r"^(identified):mode(\d+)\.(\w+)$|^(drive):(\w+)$")

# --- value checkers: each returns the cleaned value or raises ValueError(expected) ---


def _num(v, *, positive=False, nonneg=False):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError("a number")
    try:
        v = float(v)
    except OverflowError:  # TOML integers may be arbitrarily long
        raise ValueError("a finite number") from None
    if v != v or v in (float("inf"), float("-inf")):
        raise ValueError("a finite number")
    if positive and v <= 0:
        raise ValueError("a number > 0")
    if nonneg and v < 0:
        raise ValueError("a number >= 0")
    return v


def POS(v):
    return _num(v, positive=True)


def NONNEG(v):
    return _num(v, nonneg=True)


def NUM(v):
    return _num(v)


def INT(v):
    if isinstance(v, bool) or not isinstance(v, int):
        raise ValueError("an integer")
    return v


def BOOL(v):
    if not isinstance(v, bool):
        raise ValueError("true or false")
    return v


def STR(v):
    if not isinstance(v, str) or not v:
        raise ValueError("a non-empty string")
    return v


def choice(*options):
    def check(v):
        if v not in options:
            raise ValueError("one of " + ", ".join(repr(o) for o in options))
        return v
    return check


def list_of(check, length=None, min_length=1):
    def run(v):
        if not isinstance(v, list):
            raise ValueError(f"a list{f' of {length}' if length else ''}")
        if length is not None and len(v) != length:
            raise ValueError(f"a list of {length} values, got {len(v)}")
        if len(v) < min_length:
            raise ValueError(f"a list of at least {min_length} values")
        return [check(x) for x in v]
    return run


def ref_or(check, sources=("identified", "drive")):
    def run(v):
        if isinstance(v, str):
            ref = parse_reference(v)
            if ref.source not in sources:
                raise ValueError(f"a number or a reference to {' or '.join(sources)}")
            return ref
        return check(v)
    return run


def complex_value(v):
    if isinstance(v, list):
        re_, im = list_of(NUM, length=2)(v)
        return complex(re_, im)
    return complex(NUM(v))


@dataclass(frozen=True)
class Reference:
    """A value taken from an earlier stage."""

    source: str  # "identified" or "drive"
    field: str
    mode: int = 0  # 1-based for identified
    text: str = ""


def parse_reference(text: str) -> Reference:
    """Parse ``identified:modeN.field`` or ``drive:field``; ValueError says what was expected."""
    match = _REF.match(text.strip())
    if not match:
        raise ValueError("a number or a reference like \"identified:mode1.stiffness\" or \"drive:speed\"")
    if match.group(1):
        mode, field = int(match.group(2)), match.group(3)
        if field not in IDENTIFIED_FIELDS:
            raise ValueError(f"an identified field among {', '.join(IDENTIFIED_FIELDS)} (got {field!r})")
        if mode < 1:
            raise ValueError("a mode number >= 1")
        return Reference("identified", field, mode, text)
    field = match.group(5)
    if field not in DRIVE_FIELDS:
        raise ValueError(f"a drive field among {', '.join(DRIVE_FIELDS)} (got {field!r})")
    return Reference("drive", field, 0, text)


SCHEMA: dict[str, Any] = {
    "scene": {"name": STR, "description": STR},
    "frf": {
        "file": STR, "kind": choice("receptance", "mobility", "accelerance"),
        # the read options of `python -m modal fit`, under the same names
        "frequency_axis": choice("hz", "khz", "rad/s", "cpm", "rpm"), "frequency_step": POS,
        "frequency_start": NONNEG, "layout": STR, "delimiter": STR, "decimal": STR, "dataset": INT,
        "synthetic": {
            "natural_frequency_hz": list_of(POS), "damping_ratio": list_of(NONNEG),
            "modal_constant": list_of(complex_value), "kind": choice("receptance", "mobility", "accelerance"),
            "f_min_hz": NONNEG, "f_max_hz": POS, "n_lines": INT, "noise": NONNEG, "seed": INT,
        },
    },
    "identify": {
        "method": choice("nls", "circle", "halfpower"), "bands_hz": list_of(list_of(NONNEG, length=2)),
        "channel": INT, "min_prominence_db": POS, "max_modes": INT, "accept_flagged": BOOL,
    },
    "rotor": {
        "M": ref_or(POS, ("identified",)), "k": ref_or(POS), "c": ref_or(NONNEG, ("identified",)), "e": NONNEG,
        "mass_includes_balls": BOOL,
    },
    "adb": {
        "m": POS, "n": INT, "R": POS, "D": NONNEG,
        "stability": {"speed_max_rad_s": POS, "speed_max_ratio": POS, "grid_points": INT},
        "response": {
            "speed_rad_s": ref_or(POS, ("drive",)), "speed_start_rad_s": NONNEG, "speed_end_rad_s": ref_or(POS, ("drive",)),
            "ramp_s": POS, "t_end_s": POS, "initial_ball_angles_rad": list_of(NUM), "rtol": POS,
        },
    },
    "drive": {
        "motor_speed_rpm": POS, "power_w": POS, "service_factor": POS,
        "stages": [{"driver_diameter_m": POS, "driven_diameter_m": POS, "center_distance_m": POS,
                    "per_belt_rating_w": POS, "name": STR}],
        "shaft": {"length_m": POS, "bearing_a_m": NONNEG, "bearing_b_m": NONNEG, "diameter_m": POS,
                  "rotor_position_m": NONNEG, "rotor_mass_kg": POS, "youngs_modulus_pa": POS},
    },
    "compressor": {
        "crank_radius_m": POS, "rod_length_m": POS, "rotating_mass_kg": NONNEG, "reciprocating_mass_kg": NONNEG,
        "speed_rpm": POS, "harmonics": lambda v: v if v == "exact" else tuple(list_of(INT)(v)),
        "counterweight_k": NONNEG,
        "body": {"mass_kg": POS, "inertia_kg_m2": list_of(list_of(NUM, length=3), length=3),
                 "crank_centre_m": list_of(NUM, length=3), "damping_ratio": NONNEG},
        "mounts": [{"position_m": list_of(NUM, length=3),
                    "stiffness_n_per_m": lambda v: v if isinstance(v, str) and ref_or(POS, ("identified",))(v) else list_of(NONNEG, length=3)(v),
                    "damping_n_s_per_m": lambda v: v if isinstance(v, str) and ref_or(POS, ("identified",))(v) else list_of(NONNEG, length=3)(v)}],
    },
    "balance": {
        "readings": STR, "units": STR, "mass_units": choice("g", "kg"),
        "radius_m": lambda v: list_of(POS)(v) if isinstance(v, list) else POS(v), "sensors": list_of(STR),
        "initial": {"amplitude": list_of(NONNEG), "phase_deg": list_of(NUM)},
        "trial": [{"mass": POS, "angle_deg": NUM, "amplitude": list_of(NONNEG), "phase_deg": list_of(NUM)}],
        "after": {"amplitude": list_of(NONNEG), "phase_deg": list_of(NUM)},
        "method": choice("least_squares", "minmax"), "weights": list_of(POS), "max_unbalance_kg_m": POS,
        "holes": INT, "positions_deg": list_of(NUM),
        "iso": {"grade_mm_s": POS, "rotor_mass_kg": POS, "speed_rpm": POS, "distances_m": list_of(NONNEG, length=2)},
        "simulate": {"speeds_rad_s": list_of(POS), "trial_mass": POS, "trial_angle_deg": NUM, "noise": NONNEG, "seed": INT,
                     "rotor_mass_kg": POS, "stiffness_n_per_m": POS, "damping_n_s_per_m": NONNEG},
    },
    "outputs": {"tables": list_of(choice(*STAGES), min_length=0), "plots": list_of(choice(*STAGES), min_length=0),
                "archive": lambda v: v if isinstance(v, bool) else list_of(choice(*STAGES), min_length=0)(v)},
}

#: keys each section must have when present
REQUIRED = {
    "frf.synthetic": ("natural_frequency_hz", "damping_ratio", "modal_constant", "f_max_hz", "n_lines"),
    "rotor": ("M", "k", "c", "e"),
    "adb": ("m", "n", "R", "D"),
    "drive": ("motor_speed_rpm", "power_w", "stages"),
    "drive.stages": ("driver_diameter_m", "driven_diameter_m", "center_distance_m"),
    "drive.shaft": ("length_m", "bearing_a_m", "bearing_b_m", "diameter_m", "rotor_position_m", "rotor_mass_kg"),
    "compressor": ("crank_radius_m", "rod_length_m", "rotating_mass_kg", "reciprocating_mass_kg", "speed_rpm"),
    "compressor.body": ("mass_kg", "inertia_kg_m2", "crank_centre_m"),
    "compressor.mounts": ("position_m", "stiffness_n_per_m"),
    "balance": ("units", "radius_m"),
    "balance.iso": ("grade_mm_s", "rotor_mass_kg", "speed_rpm"),
    "balance.simulate": ("speeds_rad_s", "trial_mass"),
}


@dataclass(frozen=True)
class Scene:
    """A validated scene: its configuration, source text and folder."""

    config: dict
    text: str
    source: str
    folder: Path

    def section(self, dotted: str, default=None):
        node = self.config
        for part in dotted.split("."):
            if not isinstance(node, dict) or part not in node:
                return default
            node = node[part]
        return node


def _validate(node: dict, schema: dict, where: str, src: str) -> dict:
    out = {}
    for key, value in node.items():
        path = f"{where}.{key}" if where else key
        if key not in schema:
            allowed = ", ".join(sorted(schema))
            raise SceneError(f"{src}: unknown key '{path}'; expected one of: {allowed}")
        rule = schema[key]
        if isinstance(rule, dict):
            if not isinstance(value, dict):
                raise SceneError(f"{src}: key '{path}' must be a table [{path}], got {type(value).__name__}")
            out[key] = _validate(value, rule, path, src)
        elif isinstance(rule, list):
            if not isinstance(value, list) or not all(isinstance(v, dict) for v in value) or not value:
                raise SceneError(f"{src}: key '{path}' must be an array of tables [[{path}]]")
            out[key] = [_validate(v, rule[0], f"{path}[{i}]", src) for i, v in enumerate(value)]
            for i, v in enumerate(value):
                _require(v, path, f"{path}[{i}]", src)
        else:
            try:
                out[key] = rule(value)
            except ValueError as exc:
                shown = repr(value) if len(repr(value)) <= 60 else repr(value)[:57] + "..."
                raise SceneError(f"{src}: key '{path}' = {shown}: expected {exc}") from None
        if isinstance(rule, dict):
            _require(value, path, path, src)
    return out


def _require(node: dict, schema_path: str, where: str, src: str) -> None:
    for key in REQUIRED.get(schema_path, ()):
        if key not in node:
            raise SceneError(f"{src}: key '{where}.{key}' is missing; [{schema_path}] needs {', '.join(REQUIRED[schema_path])}")


def parse_scene(config: dict, text: str = "", source: str = "<scene>", folder: Path | str = ".") -> Scene:
    """Validate a scene given as a dict (as parsed from TOML)."""
    if not isinstance(config, dict):
        raise SceneError(f"{source}: a scene is a table of sections, got {type(config).__name__}")
    clean = _validate(config, SCHEMA, "", source)
    for section in ("rotor", "adb", "drive", "compressor", "balance"):
        if section in clean:
            _require(clean[section], section, section, source)
    outputs = clean.get("outputs")
    if not outputs or not (outputs.get("tables") or outputs.get("plots") or outputs.get("archive")):
        raise SceneError(f"{source}: key 'outputs' is missing or empty; expected [outputs] with tables, plots or archive")
    if "frf" in clean and "file" in clean["frf"] and "synthetic" in clean["frf"]:
        raise SceneError(f"{source}: key 'frf' has both 'file' and 'synthetic'; expected one of them")
    if "frf" in clean and "file" not in clean["frf"] and "synthetic" not in clean["frf"]:
        raise SceneError(f"{source}: key 'frf' needs 'file' or a [frf.synthetic] table")
    if "balance" in clean and "simulate" not in clean["balance"]:
        _check_balance(clean["balance"], source, Path(folder))
    scene = Scene(clean, text, source, Path(folder))
    # every stage an output names must have its sections, and every reference its source
    for stage in set(outputs.get("tables", [])) | set(outputs.get("plots", [])) | (
            set(outputs["archive"]) if isinstance(outputs.get("archive"), list) else set()):
        check_stage_configured(scene, stage)
    return scene


def _check_balance(config: dict, source: str, folder: Path) -> None:
    """The [balance] readings are consistent (shapes, units, files) before any work."""
    from balancer.influence.job import parse_job
    from modal.errors import ModalError

    try:
        parse_job(config, source, folder, key_prefix="balance.")
    except ModalError as exc:
        raise SceneError(str(exc)) from None


def stage_sections(stage: str) -> tuple[str, ...]:
    """Sections a stage needs in the scene."""
    return {
        "frf": ("frf",), "identify": ("frf",), "drive": ("drive",), "rotor": ("rotor", "adb"),
        "adb_stability": ("rotor", "adb"), "adb_response": ("rotor", "adb", "adb.response"),
        "compressor": ("compressor",), "mounts": ("compressor", "compressor.body", "compressor.mounts"),
        "balance": ("balance",),
    }[stage]


def references(scene: Scene, stage: str) -> list[tuple[str, Reference]]:
    """(key, reference) pairs used by a stage's own configuration."""
    keys = {"rotor": ["rotor"], "adb_response": ["adb.response"], "mounts": []}.get(stage, [])
    found = []
    for dotted in keys:
        for key, value in (scene.section(dotted) or {}).items():
            if isinstance(value, Reference):
                found.append((f"{dotted}.{key}", value))
    if stage == "mounts":
        for i, mount in enumerate(scene.section("compressor.mounts") or []):
            for key in ("stiffness_n_per_m", "damping_n_s_per_m"):
                value = mount.get(key)
                if isinstance(value, str):
                    found.append((f"compressor.mounts[{i}].{key}", parse_reference(value)))
    return found


def check_stage_configured(scene: Scene, stage: str, seen: tuple[str, ...] = ()) -> None:
    """Raise SceneError when a stage, or a stage it refers to, lacks its sections; detect cycles."""
    if stage in seen:
        raise SceneError(f"{scene.source}: stages form a cycle: {' -> '.join(seen + (stage,))}")
    for section in stage_sections(stage):
        if scene.section(section) is None:
            raise SceneError(f"{scene.source}: output '{stage}' needs section [{section}], which the scene does not have")
    for dep in dependencies(scene, stage):
        check_stage_configured(scene, dep, seen + (stage,))


def dependencies(scene: Scene, stage: str) -> tuple[str, ...]:
    """Stages this stage needs: fixed ones plus those its references point at."""
    deps = list(DEPENDS[stage])
    for key, ref in references(scene, stage):
        source = "identify" if ref.source == "identified" else "drive"
        needed = ("frf",) if source == "identify" else ("drive",)
        if scene.section(needed[0]) is None:
            raise SceneError(f"{scene.source}: key '{key}' = {ref.text!r} refers to stage '{source}', "
                             f"but the scene has no [{needed[0]}] section")
        if source not in deps:
            deps.append(source)
    if stage == "balance" and scene.section("balance.simulate") is not None:
        deps.append("rotor")  # the simulated rotor is the [rotor] stage's
        if scene.section("adb.response.speed_rad_s") is not None:
            deps.append("adb_response")  # the ball balancer at constant speed, for comparison
    return tuple(deps)


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene TOML file."""
    path = Path(path)
    src = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError(f"{src}: no such scene file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"{src}: cannot read the scene ({exc})") from None
    try:
        config = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{src}: not valid TOML ({exc})") from None
    return parse_scene(config, text, src, path.parent)
