"""The [oma] stage: a scene takes k, c, M from an operational test scaled by mass change, as from an impact test."""
from __future__ import annotations

import warnings
from types import SimpleNamespace

import h5py
import numpy as np
import pytest
from scipy.linalg import eigh

from balancer import run_scene
from modal.errors import SceneError
from modal.synthetic import ambient_response, chain_matrices

from support.scenes import ADB, scene

MASSES, SPRINGS = np.array([2.0, 1.5, 1.0, 1.2]), np.array([8e3, 6e3, 5e3, 4e3])
ADDED = [0.2, 0.15, 0.1, 0.12]


def _write(path, rec):
    with h5py.File(path, "w") as fh:
        ds = fh.create_dataset("signals", data=rec.signals)
        ds.attrs["sample_rate_hz"] = rec.sample_rate_hz
        ds.attrs["quantities"] = ["acceleration"] * rec.signals.shape[0]
        ds.attrs["units"] = ["m/s^2"] * rec.signals.shape[0]
    return path.name


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    folder = tmp_path_factory.mktemp("oma_scene")
    M, C, K = chain_matrices(MASSES, SPRINGS, 0.01)
    before = _write(folder / "before.h5", ambient_response(M, C, K, 200.0, 300_000, noise=0.1, seed=1))
    after = _write(folder / "after.h5", ambient_response(M + np.diag(ADDED), C, K, 200.0, 300_000, noise=0.1, seed=2))
    return folder, before, after, M, K


def _scene_file(folder, name, oma, rotor=None, **extra):
    import json

    rotor = rotor or {"M": "identified:mode1.mass", "k": "identified:mode1.stiffness",
                      "c": "identified:mode1.damping", "e": 0.0005, "mass_includes_balls": False}
    config = scene(oma=oma, rotor=rotor, adb=ADB, outputs={"tables": ["rotor"]}, **extra)
    lines = []
    for section, table in config.items():  # a small TOML writer: tables of scalars, lists and inline tables
        plain = {k: v for k, v in table.items() if not isinstance(v, dict)}
        lines.append(f"[{section}]")
        lines += [f"{k} = {json.dumps(v)}" for k, v in plain.items()]
        for key, sub in table.items():
            if isinstance(sub, dict) and key == "added_mass_kg":
                lines.append(f"{key} = {{ {', '.join(f'{json.dumps(c)} = {kg}' for c, kg in sub.items())} }}")
        for key, sub in table.items():
            if isinstance(sub, dict) and key != "added_mass_kg":
                lines.append(f"[{section}.{key}]")
                lines += [f"{k} = {json.dumps(v)}" for k, v in sub.items()]
    path = folder / name
    path.write_text("\n".join(lines) + "\n")
    return path


def test_rotor_takes_k_c_m_from_a_mass_change_test(records):
    folder, before, after, M, K = records
    oma = {"file": before, "band_hz": [1.0, 60.0], "mass_change": after,
           "added_mass_kg": {str(k + 1): kg for k, kg in enumerate(ADDED)}, "channel": 2, "accept_flagged": True}
    run = run_scene(_scene_file(folder, "scaled.toml", oma))
    assert run.stages["oma"] == "ran" and run.stages["rotor"] == "ran"
    w2, phi = eigh(K, M)  # mass-normalised: phi' M phi = 1
    rotor = run.results["rotor"]
    # channel 2 (numbered from 1) is a driving point of mode 1's mass-normalised shape: m = 1/phi^2, k = m wn^2;
    # within 20 %: the scaled shape is within 10 % (operational/test_scaling.py), m goes with its square
    m_true = 1 / phi[1, 0] ** 2
    assert abs(rotor.params.M / m_true - 1) < 0.2
    assert abs(rotor.params.k / (m_true * w2[0]) - 1) < 0.2
    assert rotor.std.M > 0 and rotor.std.k > 0  # the operational test's errors are carried
    assert "channel 2" in rotor.sources[0]  # numbered from 1 in the sources, as in the scene and for [identify]


def test_an_operational_test_without_mass_change_gives_no_k_c_m(records):
    folder, before, _, _, _ = records
    with pytest.raises(SceneError, match="an operational test alone gives no k, c, m; expected oma.mass_change"):
        run_scene(_scene_file(folder, "unscaled.toml", {"file": before, "band_hz": [1.0, 60.0],
                                                        "accept_flagged": True}))


@pytest.mark.parametrize("oma, extra, message", [
    ({"mass_change": "after.h5"}, {}, "key 'oma.added_mass_kg' is missing; oma.mass_change needs it"),
    ({"method": "magic"}, {}, "key 'oma.method' = 'magic'"),
    ({"channel": 0}, {}, "key 'oma.channel' = 0: expected a channel number counted from 1"),
    ({"band_hz": [30.0, 10.0]}, {}, "key 'oma': .*0 <= FMIN < FMAX"),
    ({}, {"frf": {"file": "x.csv"}}, r"has \[frf\] and \[oma\]; expected one of them"),
])
def test_bad_oma_sections_are_one_error(records, oma, extra, message):
    folder, before, _, _, _ = records
    with pytest.raises(SceneError, match=message) as info:
        run_scene(_scene_file(folder, "bad.toml", {"file": before, **oma}, **extra))
    assert "\n" not in str(info.value)


def test_k_c_m_at_a_channel_that_does_not_move_are_refused(tmp_path):
    # a fifth sensor, disconnected (amplifier noise alone), named as the rotor's channel: its mass-normalised
    # shape entry is 0 within its errors and m = 1/psi^2 came out as 1e11 kg (± 3e11), handed to the study
    M, C, K = chain_matrices(MASSES, SPRINGS, 0.01)
    rng = np.random.default_rng(5)
    for name, added, seed in (("before.h5", [0.0] * 4, 1), ("after.h5", ADDED, 2)):
        rec = ambient_response(M + np.diag(added), C, K, 200.0, 150_000, noise=0.1, seed=seed)
        dead = 1e-3 * rec.signals[3].std() * rng.standard_normal(rec.signals.shape[1])
        _write(tmp_path / name, SimpleNamespace(signals=np.vstack([rec.signals, dead]), sample_rate_hz=200.0))
    oma = {"file": "before.h5", "band_hz": [1.0, 60.0], "mass_change": "after.h5",
           "added_mass_kg": {str(k + 1): kg for k, kg in enumerate(ADDED)}, "channel": 5, "accept_flagged": True}
    with pytest.raises(SceneError, match=r"key 'rotor\.M' = 'identified:mode1\.mass': mode 1's shape at channel 5 "
                                         r"\(.*\) is within 3 standard errors of zero: its k, c, m there rest on "
                                         r"noise") as info:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            run_scene(_scene_file(tmp_path, "dead.toml", oma))
    assert "\n" not in str(info.value)
    # modal oma says so too, of both records
    assert sum("channel 5 moves in none of the 4 modes" in str(w.message) for w in caught) == 2


def test_a_record_of_bursts_does_not_feed_the_study(tmp_path):
    # the 'before' record holds the machine's response in bursts (running 2 s of every 10, idle between): not
    # stationary, its modes flagged non_stationary, which the scene refuses as it refuses any flagged mode
    M, C, K = chain_matrices(MASSES, SPRINGS, 0.01)
    rec = ambient_response(M, C, K, 200.0, 40_000, noise=0.1, seed=1)
    running = (np.arange(rec.signals.shape[1]) / 200.0) % 10.0 < 2.0
    _write(tmp_path / "before.h5", SimpleNamespace(signals=rec.signals * np.where(running, 1.0, 0.02),
                                                   sample_rate_hz=200.0))
    _write(tmp_path / "after.h5", ambient_response(M + np.diag(ADDED), C, K, 200.0, 40_000, noise=0.1, seed=2))
    oma = {"file": "before.h5", "band_hz": [1.0, 60.0], "mass_change": "after.h5",
           "added_mass_kg": {str(k + 1): kg for k, kg in enumerate(ADDED)}, "channel": 2}
    with pytest.raises(SceneError, match=r"key 'rotor\.M' = 'identified:mode1\.mass': mode 1 .* is flagged "
                                         r"\(.*non_stationary.*\)") as info:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            run_scene(_scene_file(tmp_path, "bursts.toml", oma))
    assert "\n" not in str(info.value)
