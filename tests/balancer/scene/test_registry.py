"""The stage registry: every stage declared once, and everything about a scene read from it."""
from __future__ import annotations

import json
import os
import subprocess
import sys

from support.paths import ROOT

from balancer.scene.registry import REGISTRY, STAGES, load
from balancer.scene.rules import REFERENCE_STAGES
from balancer.scene.schema import REQUIRED, SCHEMA


def _schema_node(dotted: str):
    node = SCHEMA
    for part in dotted.split("."):
        node = node[0] if isinstance(node, list) else node
        node = node[part]
    return node


def test_every_entry_names_stages_that_run_before_it_and_functions_that_exist():
    for position, (name, stage) in enumerate(REGISTRY.items()):
        assert stage.name == name
        earlier = set(STAGES[:position])
        upstream = set(stage.depends) | {dep for dep, _ in stage.depends_when}
        assert upstream <= earlier, name  # the run order is an order of the dependencies
        assert set(stage.plot_inputs) <= earlier | {name}, name
        for target in (stage.run, stage.prepare, stage.figures, stage.digest, stage.rows):
            if target is not None:
                assert callable(load(target)), target
    assert {s for stages in REFERENCE_STAGES.values() for s in stages} <= set(STAGES)


def test_the_schema_is_the_stages_own_configuration():
    # each key a stage owns is in the scene's schema with the stage's rule, and nothing else is but [scene]
    # and [outputs]
    owned = set()
    for stage in REGISTRY.values():
        for dotted, rule in stage.config.items():
            assert _schema_node(dotted) is rule, dotted
            owned.add(dotted.split(".")[0])
        for path, keys in stage.required.items():
            assert REQUIRED[path] == keys and set(keys) <= set(_schema_node(path)[0] if isinstance(
                _schema_node(path), list) else _schema_node(path)), path
    assert set(SCHEMA) == owned | {"scene", "outputs"}


_NEW_STAGE = """
import json, sys
sys.path.insert(0, {root!r})
from dataclasses import dataclass
from balancer.scene import registry
from balancer.scene.rules import POS, ref_or


@dataclass(frozen=True)
class Doubled:
    value: float


def run(scene, drive=None):
    return Doubled(2 * scene.section("double.x"))


def digest(result):
    return {{"value": result.value}}


def rows(result, d):
    return [f"  doubled: {{d['value']:g}}"]


registry.REGISTRY["double"] = registry.Stage("double", run="__main__:run", needs=("double",),
                                             config={{"double.x": ref_or(POS, ("drive",))}}, required={{"double": ("x",)}},
                                             digest="__main__:digest", rows="__main__:rows")
registry.STAGES = tuple(registry.REGISTRY)
from balancer.scene import parse_scene, run_scene
from modal.errors import SceneError

errors = []
for bad in ({{"double": {{"x": -1.0}}}}, {{"double": {{}}}}, {{"double": {{"x": "drive:speed"}}}}, {{}}):
    try:
        parse_scene({{**bad, "outputs": {{"tables": ["double"]}}}}, source="s.toml")
    except SceneError as exc:
        errors.append(str(exc))
run = run_scene({{"double": {{"x": 1.5}}, "outputs": {{"tables": ["double"], "archive": True}}}}, out="d.h5")
import h5py
with h5py.File("d.h5", "r") as f:  # under its name (the archive rebuilds only the toolkit's own classes)
    archived, hashed = float(f["double/value"][()]), f["double"].attrs["inputs_hash"] == run.inputs_hash["double"]
print(json.dumps({{"errors": errors, "stages": run.stages, "value": run.results["double"].value,
                  "summary": run.summary.splitlines()[-4:], "archived": archived, "hashed": bool(hashed)}}))
"""


def test_a_stage_declared_in_the_registry_alone_is_checked_planned_run_archived_and_summarised(tmp_path):
    # the stage is declared by one entry (in a fresh interpreter: the schema is built from the registry when
    # it is first imported); nothing else in balancer.scene names it
    proc = subprocess.run([sys.executable, "-c", _NEW_STAGE.format(root=str(ROOT))], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120, env={**os.environ, "MPLBACKEND": "Agg"})
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["errors"] == [
        "s.toml: key 'double.x' = -1.0: expected a number > 0",
        "s.toml: key 'double.x' is missing; [double] needs x",
        "s.toml: key 'double.x' = 'drive:speed' refers to stage 'drive', but the scene has no [drive] section",
        "s.toml: output 'double' needs section [double], which the scene does not have",
    ]
    assert out["stages"] == {**{stage: "skipped" for stage in STAGES}, "double": "ran"}
    assert out["value"] == out["archived"] == 3.0 and out["hashed"]
    assert out["summary"][:3] == ["[double]", "  doubled: 3", ""] and out["summary"][3].startswith("archive: ")
