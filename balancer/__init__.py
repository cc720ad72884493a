"""Balancing studies fed by modal identification: automatic ball balancer,
slider-crank / compressor counterweight, and machine drive (belt and shaft),
wired together by scenes.

``balancer`` imports ``modal``; never the reverse.
"""
__all__ = ["run_scene", "read_archive"]


def read_archive(path):
    """Read an archive written by a scene run; see :func:`modal.archive.read_archive`.

    (Imported when called: ``python -m balancer run`` starts its plotting process early, and
    h5py is not needed before that.)
    """
    from modal.archive import read_archive as _read

    return _read(path)


def run_scene(*args, **kwargs):
    """Run a scene end to end; see :func:`balancer.scene.run_scene`."""
    from .scene import run_scene as _run

    return _run(*args, **kwargs)
