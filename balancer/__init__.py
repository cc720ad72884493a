"""Balancing studies fed by modal identification: automatic ball balancer,
slider-crank / compressor counterweight, and machine drive (belt and shaft),
wired together by scenes.

``balancer`` imports ``modal``; never the reverse.
"""
from modal.archive import read_archive

__all__ = ["run_scene", "read_archive"]


def run_scene(*args, **kwargs):
    """Run a scene end to end; see :func:`balancer.scene.run_scene`."""
    from .scene import run_scene as _run

    return _run(*args, **kwargs)
