"""A roving-hammer test made in exact discrete time: three masses in a chain, the accelerometer at point 1,
the hammer moved over points 1, 2 and 3, one time file per hit point."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from modal.io.timewrite import write_time
from modal.synthetic_time import DigitalModes, impact_record

__all__ = ["FS", "MASS", "STIFFNESS", "DAMPING", "HITS_S", "plant", "hits", "write", "roving_files"]

FS = 1024.0
# three masses in a chain (kg, N/m) with Rayleigh damping: modes at 31.7, 65.5 and 85.8 Hz, ζ 1.5-2.9 %
MASS = np.diag([1.0, 1.5, 1.2])
STIFFNESS = np.array([[2e5, -1e5, 0], [-1e5, 2.5e5, -1.2e5], [0, -1.2e5, 1.6e5]])
DAMPING = 1e-4 * STIFFNESS + 2.0 * MASS
HITS_S = [0.5, 6.5, 12.5]


def plant(point: int, rate: float = FS) -> DigitalModes:
    """Force at ``point`` (0-based), the accelerometer at point 0."""
    return DigitalModes.from_matrices(MASS, DAMPING, STIFFNESS, rate, response_dofs=[0], reference_dof=point)


def hits(point, seed, hits=HITS_S, duration=18.0, rate=FS, response="1+Z", **options):
    """The time record of hammer hits at ``point`` (force channel ``{point + 1}+Z``, response ``response``)."""
    return impact_record(plant(point, rate), hits, duration, seed=seed, names=[f"{point + 1}+Z", response],
                         response_noise=3e-3, force_noise=1e-3, **options).record


def write(path, record):
    """``record`` written to ``path`` as a time file, its source the file's name."""
    write_time(replace(record, source=path.name), path)
    return path


def roving_files(folder, first_seed: int = 10):
    """The three files ``p1.csv``, ``p2.csv``, ``p3.csv`` of the hammer at points 1, 2, 3 in ``folder``."""
    return [write(folder / f"p{j + 1}.csv", hits(j, seed=first_seed + j)) for j in range(3)]
