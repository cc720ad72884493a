"""Scene files: the schema, validation before any work, and the stages' dependency graph.

A scene describes one case. Every section is optional except ``[outputs]``; the runner
only does the stages the outputs need. The schema is the stages' own configuration
(:data:`.registry.REGISTRY`) with ``[scene]`` and ``[outputs]``; values that come from an
earlier stage are written as references (:mod:`.rules`).

Every problem is reported as one :class:`~modal.errors.SceneError` naming the file, the
key and what was expected.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

from modal.errors import SceneError

from .registry import REGISTRY, STAGES, load
from .rules import REFERENCE_STAGES, STR, Reference, choice, list_of, parse_reference

__all__ = ["Scene", "load_scene", "parse_scene", "STAGES", "SCHEMA", "REQUIRED", "Reference", "parse_reference",
           "dependencies", "references"]


def _outputs(v):
    return v if isinstance(v, bool) else list_of(choice(*STAGES), min_length=0)(v)


def _build() -> tuple[dict[str, Any], dict[str, tuple[str, ...]]]:
    """The scene's schema (section -> key -> rule) and required keys, from the stages' own."""
    schema: dict[str, Any] = {"scene": {"name": STR, "description": STR}}
    required: dict[str, tuple[str, ...]] = {}
    for stage in REGISTRY.values():
        for dotted, rule in stage.config.items():
            *sections, key = dotted.split(".")
            node = schema
            for section in sections:
                node = node.setdefault(section, {})
            if key in node:
                raise ValueError(f"stages declare the scene key '{dotted}' twice")  # pragma: no cover - registry bug
            node[key] = rule
        for path, keys in stage.required.items():
            if path in required:
                raise ValueError(f"stages declare the keys [{path}] needs twice")  # pragma: no cover - registry bug
            required[path] = keys
    schema["outputs"] = {"tables": list_of(choice(*STAGES), min_length=0),
                         "plots": list_of(choice(*STAGES), min_length=0), "archive": _outputs}
    return schema, required


#: section -> key -> rule: a callable, a table of rules, or ``[table]`` for an array of tables
#: keys each section must have when present
SCHEMA, REQUIRED = _build()


@dataclass(frozen=True)
class Scene:
    """A validated scene: its configuration, source text and folder.

    Attributes
    ----------
    config : dict
        The validated configuration (references as :class:`.rules.Reference`).
    text : str
        The scene file's text ("" for a scene given as a dict).
    source : str
        The file (or a name) errors name.
    folder : Path
        Where the files the scene names are.
    """

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

    @cached_property
    def inputs(self) -> dict[str, Any]:
        """Stage name -> what checking the scene read for it (the ``prepare`` of each stage whose
        sections the scene has: checks beyond the rules, and the balancing readings, read once)."""
        return {stage.name: load(stage.prepare)(self) for stage in REGISTRY.values()
                if stage.prepare and all(self.section(s) is not None for s in stage.needs)}

    @cached_property
    def wanted(self) -> tuple[str, ...]:
        """The stages the outputs name (tables, plots, archived stages), in run order."""
        outputs = self.section("outputs") or {}
        archive = outputs.get("archive")
        named = set(outputs.get("tables", [])) | set(outputs.get("plots", [])) | (
            set(archive) if isinstance(archive, list) else set())
        return tuple(stage for stage in STAGES if stage in named)

    @cached_property
    def graph(self) -> dict[str, tuple[str, ...]]:
        """Every stage the outputs need (those they name and all upstream) -> the stages it takes results from.

        Computed once: a stage lacking a section it needs, a reference to a stage whose section
        is missing, or a cycle is a :class:`~modal.errors.SceneError`.
        """
        graph: dict[str, tuple[str, ...]] = {}

        def visit(stage: str, seen: tuple[str, ...]) -> None:
            if stage in seen:
                raise SceneError(f"{self.source}: stages form a cycle: {' -> '.join(seen + (stage,))}")
            if stage in graph:
                return
            for section in REGISTRY[stage].needs:
                if self.section(section) is None:
                    raise SceneError(f"{self.source}: output '{stage}' needs section [{section}], which the scene "
                                     f"does not have")
            deps = dependencies(self, stage)
            for dep in deps:
                visit(dep, seen + (stage,))
            graph[stage] = deps

        for stage in self.wanted:
            visit(stage, ())
        return {stage: graph[stage] for stage in STAGES if stage in graph}


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
    outputs = clean.get("outputs")
    if not outputs or not (outputs.get("tables") or outputs.get("plots") or outputs.get("archive")):
        raise SceneError(f"{source}: key 'outputs' is missing or empty; expected [outputs] with tables, plots or archive")
    scene = Scene(clean, text, source, Path(folder))
    scene.inputs  # noqa: B018 - the stages' own checks, and the balancing readings read, before any work
    scene.graph  # noqa: B018 - every stage an output needs has its sections, and every reference its source
    return scene


def references(scene: Scene, stage: str) -> list[tuple[str, Reference]]:
    """(key, reference) pairs in a stage's own configuration, in the scene's order."""
    found = []
    for dotted in REGISTRY[stage].config:  # a key, a table of keys, or an array of tables
        value = scene.section(dotted)
        if isinstance(value, Reference):
            found.append((dotted, value))
        tables = [(dotted, value)] if isinstance(value, dict) else (
            [(f"{dotted}[{i}]", item) for i, item in enumerate(value) if isinstance(item, dict)]
            if isinstance(value, list) else [])
        for where, table in tables:
            found += [(f"{where}.{key}", item) for key, item in table.items() if isinstance(item, Reference)]
    return found


def dependencies(scene: Scene, stage: str) -> tuple[str, ...]:
    """Stages this stage needs: fixed ones, those its references point at, and those its sections add."""
    entry = REGISTRY[stage]
    deps = list(entry.depends)
    for key, ref in references(scene, stage):
        candidates = REFERENCE_STAGES[ref.source]
        given = [s for s in candidates if scene.section(REGISTRY[s].needs[0]) is not None]
        named = " or ".join(f"'{s}'" for s in candidates)
        if not given:
            sections = " or ".join(f"[{REGISTRY[s].needs[0]}]" for s in candidates)
            raise SceneError(f"{scene.source}: key '{key}' = {ref.text!r} refers to stage {named}, "
                             f"but the scene has no {sections} section")
        if len(given) > 1:
            sections = " and ".join(f"[{REGISTRY[s].needs[0]}]" for s in given)
            raise SceneError(f"{scene.source}: key '{key}' = {ref.text!r} refers to stage {named}, but the scene "
                             f"has {sections}; expected one of them (the test the values come from)")
        source = given[0]
        if source not in deps:
            deps.append(source)
    for dep, sections in entry.depends_when:
        if all(scene.section(s) is not None for s in sections):
            deps.append(dep)
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
