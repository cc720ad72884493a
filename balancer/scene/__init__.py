"""Scenes: one TOML file describing an identify-then-balance case, run end to end.

``run_scene(path_or_dict)`` does only the stages the ``[outputs]`` need, reuses
unchanged stages from an earlier archive, and writes an HDF5 archive and plots.
"""
from .runner import SceneRun, plan, run_scene, stage_hashes
from .schema import STAGES, Scene, load_scene, parse_scene

__all__ = ["run_scene", "SceneRun", "plan", "stage_hashes", "load_scene", "parse_scene", "Scene", "STAGES"]
