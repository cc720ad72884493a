"""Scenes: one TOML file describing an identify-then-balance case, run end to end.

``run_scene(path_or_dict)`` does only the stages the ``[outputs]`` need, reuses
unchanged stages from an earlier archive, and writes an HDF5 archive and plots.

The names below are loaded on first use: the plotting process of ``python -m balancer run``
imports ``balancer.scene.plots`` without the runner and its stages (:mod:`.plotter`).
"""
from __future__ import annotations

import importlib

__all__ = ["run_scene", "SceneRun", "plan", "stage_hashes", "load_scene", "parse_scene", "Scene", "STAGES"]

_HOME = {"run_scene": "runner", "SceneRun": "runner", "plan": "runner", "stage_hashes": "runner",
         "load_scene": "schema", "parse_scene": "schema", "Scene": "schema", "STAGES": "registry"}


def __getattr__(name: str):
    if name in _HOME:
        value = getattr(importlib.import_module(f".{_HOME[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
