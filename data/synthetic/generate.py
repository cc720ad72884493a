"""Make the small synthetic files the demo and the tests use (reproducible from the seed).

Run ``python data/synthetic/generate.py``; the files are committed, and a test
checks that running this again gives the same bytes.

demo_frf.csv
    Driving-point accelerance of a rotor rig hit with an impact hammer: the
    rotor's bending mode (M = 1.04 kg rotor with balls, k = 1e4 N/m,
    c = 20 N s/m: 15.61 Hz, ζ = 9.8 %) and two housing modes (120 Hz, 2 %;
    310 Hz, 1.5 %), 0.25 Hz lines up to 400 Hz, noise 0.5 % of max |H|.

hammer.csv
    The rig's hammer test as recorded: force and driving-point acceleration (both at point
    1+Z) sampled at 1024 Hz for 10 s, eight hits 1.25 s apart (2 ms half-sine pulses of
    about 50 N, 10 % scatter in peak and width; each response dies out before the next hit), white measurement noise of 0.2 % (force) and
    0.5 % (acceleration) of each channel's peak. Exact discrete time (modal.synthetic's
    impact_record): the rotor's mode (the demo's M, k, c) and the two housing modes;
    hammer_scene.toml runs it from the record to the balancing studies.

plate_geometry.uff, plate_frf.uff
    A simply supported steel plate (0.6 m x 0.4 m x 3 mm) measured on a 6 x 5 grid: the
    geometry (UFF 15 nodes, UFF 82 trace lines along the grid) and roving-accelerometer
    accelerances (UFF 58, one dataset per point with its node and +Z direction) at the 12
    interior nodes, hammer at node 8 (a driving point). Five modes, (1,1) at 40 Hz up to
    (2,2) at 160 Hz, from the plate's analytical mass-normalised shapes
    (2/sqrt(rho h a b)) sin(m pi x/a) sin(n pi y/b); 0.5 Hz lines 1-200 Hz, noise 0.2 %
    of max |H|. The edge nodes are not measured: they stand still, as the supports hold them.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SEED = 20261122

#: truth of the demo rig (SI)
RIG_MASS_KG = 1.04
RIG_STIFFNESS_N_PER_M = 1.0e4
RIG_DAMPING_N_S_PER_M = 20.0
HOUSING_FREQUENCY_HZ = (120.0, 310.0)
HOUSING_DAMPING_RATIO = (0.02, 0.015)
HOUSING_MODAL_CONSTANT = (0.35, 0.6)  # 1/kg
NOISE_LEVEL = 0.005


def demo_frf():
    """The demo FRF object (accelerance, one driving-point channel)."""
    from modal.synthetic import add_noise, modal_frf

    f = np.arange(1, 1601) * 0.25
    frf = modal_frf(
        f,
        *rig_modes(),
        kind="accelerance",
        response_points=["1+X"],
        reference_points=["1+X"],
    )
    return add_noise(frf, NOISE_LEVEL, seed=SEED)


#: the rig's hammer test (SI): sample rate, record length, hits, pulse and noise
HAMMER_SAMPLE_RATE_HZ = 1024.0
HAMMER_DURATION_S = 10.0
HAMMER_HIT_TIMES_S = tuple(0.2 + 1.25 * i for i in range(8))
HAMMER_PULSE_WIDTH_S = 0.002
HAMMER_PEAK_N = 50.0
HAMMER_SCATTER = 0.1
HAMMER_FORCE_NOISE = 0.002
HAMMER_RESPONSE_NOISE = 0.005


def rig_modes():
    """The rig's modes: (natural frequencies, Hz; damping ratios; driving-point modal constants, 1/kg)."""
    wn = np.sqrt(RIG_STIFFNESS_N_PER_M / RIG_MASS_KG)
    zeta = RIG_DAMPING_N_S_PER_M / (2 * np.sqrt(RIG_STIFFNESS_N_PER_M * RIG_MASS_KG))
    return ([wn / (2 * np.pi), *HOUSING_FREQUENCY_HZ], [zeta, *HOUSING_DAMPING_RATIO],
            [1 / RIG_MASS_KG, *HOUSING_MODAL_CONSTANT])


def hammer_record():
    """The rig's hammer test (a SyntheticRecord: the record and the digital system it came from)."""
    from modal.synthetic import DigitalModes, impact_record

    frequency_hz, damping_ratio, modal_constant = rig_modes()
    system = DigitalModes(frequency_hz, damping_ratio, [modal_constant], HAMMER_SAMPLE_RATE_HZ)
    return impact_record(system, HAMMER_HIT_TIMES_S, HAMMER_DURATION_S, pulse_width_s=HAMMER_PULSE_WIDTH_S,
                         amplitude_n=HAMMER_PEAK_N, amplitude_variation=HAMMER_SCATTER,
                         width_variation=HAMMER_SCATTER, force_noise=HAMMER_FORCE_NOISE,
                         response_noise=HAMMER_RESPONSE_NOISE, response_quantity="acceleration",
                         names=["1+Z", "1+Z"], seed=SEED + 2, source="hammer.csv")


#: the plate (SI): size, areal mass, the five modes (m, n) and their damping ratios
PLATE_SIZE_M = (0.6, 0.4)
PLATE_AREAL_MASS_KG_M2 = 7850.0 * 0.003
PLATE_GRID = (6, 5)
PLATE_MODES = ((1, 1), (2, 1), (1, 2), (3, 1), (2, 2))
PLATE_FIRST_HZ = 40.0
PLATE_DAMPING_RATIO = (0.015, 0.012, 0.01, 0.01, 0.008)
PLATE_DRIVING_NODE = 8
PLATE_NOISE_LEVEL = 0.002
#: the date written into the UFF 58 headers, fixed so the files are reproducible
FIXED_DATE = b"01-Jan-26 00:00:00"


def plate_nodes():
    """Node ids (1 + i + 6 j) and x, y, z (m) of the measurement grid, i along x, j along y."""
    a, b = PLATE_SIZE_M
    nx, ny = PLATE_GRID
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="xy")
    ids = (1 + i + nx * j).ravel()
    xyz = np.column_stack([(i * a / (nx - 1)).ravel(), (j * b / (ny - 1)).ravel(), np.zeros(i.size)])
    return ids, xyz


def plate_geometry():
    """The plate's Geometry: the grid nodes and its lines along x and y."""
    from modal.geometry import Geometry

    ids, xyz = plate_nodes()
    nx, ny = PLATE_GRID
    grid = ids.reshape(ny, nx)
    lines = [(grid[j, i], grid[j, i + 1]) for j in range(ny) for i in range(nx - 1)]
    lines += [(grid[j, i], grid[j + 1, i]) for i in range(nx) for j in range(ny - 1)]
    return Geometry(ids, xyz, np.array(lines), source="plate")


def plate_frequencies_hz() -> np.ndarray:
    a, b = PLATE_SIZE_M
    wave = np.array([(m / a) ** 2 + (n / b) ** 2 for m, n in PLATE_MODES])
    return PLATE_FIRST_HZ * wave / wave[0]


def plate_shapes(xyz: np.ndarray) -> np.ndarray:
    """Mass-normalised shapes (1/sqrt(kg)) at the points ``xyz``, shape (n_modes, n_points)."""
    a, b = PLATE_SIZE_M
    scale = 2.0 / np.sqrt(PLATE_AREAL_MASS_KG_M2 * a * b)
    return np.array([scale * np.sin(m * np.pi * xyz[:, 0] / a) * np.sin(n * np.pi * xyz[:, 1] / b)
                     for m, n in PLATE_MODES])


def plate_frf():
    """The plate's accelerances: hammer at node 8, accelerometer roving over the 12 interior nodes."""
    from modal.synthetic import add_noise, modal_frf

    ids, xyz = plate_nodes()
    nx, ny = PLATE_GRID
    interior = np.array([(1 + i + nx * j) for j in range(1, ny - 1) for i in range(1, nx - 1)])
    rows = np.searchsorted(ids, interior)
    phi = plate_shapes(xyz[rows])
    drive = phi[:, list(interior).index(PLATE_DRIVING_NODE)]
    const = (phi * drive[:, None]).T  # A_jk = phi_j phi_k, (channels, modes)
    f = np.arange(2, 401) * 0.5
    frf = modal_frf(f, plate_frequencies_hz(), PLATE_DAMPING_RATIO, const, kind="accelerance",
                    response_points=[f"{n}+Z" for n in interior],
                    reference_points=[f"{PLATE_DRIVING_NODE}+Z"] * interior.size)
    return add_noise(frf, PLATE_NOISE_LEVEL, seed=SEED + 1)


def _fixed_date(path: Path) -> None:
    """The UFF 58 writer stamps the time of writing (id3): a fixed date keeps the bytes reproducible."""
    import re

    data = path.read_bytes()
    path.write_bytes(re.sub(rb"\d\d-[A-Z][a-z]{2}-\d\d \d\d:\d\d:\d\d", FIXED_DATE, data))


def main(out_dir: Path = HERE) -> list[Path]:
    from modal.io import write_frf
    from modal.io.geometry import write_geometry_uff
    from modal.io.timewrite import write_time

    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "demo_frf.csv"
    write_frf(demo_frf(), path)
    hammer = out_dir / "hammer.csv"
    write_time(hammer_record().record, hammer)
    geometry = out_dir / "plate_geometry.uff"
    write_geometry_uff(plate_geometry(), geometry)
    frf = out_dir / "plate_frf.uff"
    write_frf(plate_frf(), frf)
    _fixed_date(frf)
    return [path, hammer, geometry, frf]


if __name__ == "__main__":
    for written in main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE):
        print(written)
