"""Global identification (identify(frf, method="global")): pLSCF, stabilisation, joint refinement."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import modal
from support.paths import REAL
from modal.global_ import channel_grid, mpc, plscf_poles

#: the real beam's modes by an independent LSCF + LSFD fit (sdypy-EMA, data/real/README.md)
BEAM_HZ = np.array([51.5, 142.2, 278.7, 460.4, 687.2])


def _fit(frf, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)  # flags are checked explicitly
        return modal.identify(frf, "global", **kwargs)


def structure():
    """14 modes in 20-600 Hz (a close pair at 200/202 Hz within their 4 Hz half-power bandwidths, with
    orthogonal participation; a mode at 340 Hz driven at a fifth of the others), two modes above the band,
    12 response points x 2 references (24 channels), real normal modes of unit modal mass."""
    rng = np.random.default_rng(100)
    fn = np.array([32., 55., 81., 110., 146., 200., 202., 251., 297., 340., 395., 452., 505., 560., 700., 850.])
    zeta = np.array([0.02, 0.015, 0.012, 0.01, 0.01, 0.01, 0.01, 0.008, 0.008, 0.008, 0.006, 0.006, 0.005, 0.005,
                     0.005, 0.005])
    n_out, refs = 12, [0, 5]
    phi = rng.normal(size=(n_out, fn.size))
    phi[refs, :] = rng.choice([-1, 1], size=(2, fn.size)) * rng.uniform(0.6, 1.2, size=(2, fn.size))
    phi[:, 6] = phi[:, 5][::-1] * np.sign(rng.normal(size=n_out))
    phi[refs, 5], phi[refs, 6] = [1.0, 1.0], [1.0, -1.0]
    phi[refs, 9] *= 0.2
    const = np.array([[phi[o, r] * phi[q, r] for r in range(fn.size)] for o in range(n_out) for q in refs])
    resp = [str(o) for o in range(n_out) for q in refs]
    ref = [str(q) for o in range(n_out) for q in refs]
    return fn, zeta, const, resp, ref


@pytest.fixture(scope="module")
def multi_reference():
    fn, zeta, const, resp, ref = structure()
    f = np.arange(20, 600.001, 0.25)
    clean = modal.modal_frf(f, fn, zeta, const, kind="accelerance", response_points=resp, reference_points=ref)
    noisy = modal.add_noise(clean, 0.002, seed=1)  # 0.2 % of each channel's peak
    return fn, zeta, const, clean, noisy, _fit(noisy)


def test_channel_grid_finds_outputs_and_references(multi_reference):
    *_, noisy, _ = multi_reference
    index, refs, transposed = channel_grid(noisy)
    assert index.shape == (12, 2) and refs == ["0", "5"] and not transposed
    assert sorted(index.ravel()) == list(range(24))


def test_every_mode_in_band_found_with_calibrated_errors(multi_reference):
    fn, zeta, const, clean, noisy, result = multi_reference
    found = np.array([m.natural_frequency_hz for m in result])
    in_band = np.flatnonzero(fn < 600)
    matched = []
    for k in in_band:
        j = int(np.argmin(np.abs(found - fn[k])))
        assert abs(found[j] / fn[k] - 1) < 3e-3, (fn[k], found)  # the 0.3 % asked
        matched.append(j)
    assert len(set(matched)) == in_band.size  # the close pair at 200/202 Hz is two modes
    modes = [result[j] for j in matched]
    z_f = np.array([(m.natural_frequency_hz - fn[k]) / m.std.natural_frequency_hz for m, k in zip(modes, in_band)])
    z_z = np.array([(m.damping_ratio - zeta[k]) / m.std.damping_ratio for m, k in zip(modes, in_band)])
    # "inside 4 standard errors for nearly all modes": the two modes above the band are modelled by the
    # residual terms only, which may bias the top mode beyond its white-noise error
    assert np.sum(np.abs(z_f) < 4) >= in_band.size - 1 and np.sum(np.abs(z_z) < 4) >= in_band.size - 1
    for m, k in zip(modes, in_band):
        a = np.asarray(m.modal_constant)
        mac = abs(np.vdot(a, const[:, k])) ** 2 / (np.vdot(a, a).real * np.vdot(const[:, k], const[:, k]).real)
        assert mac >= 0.98, (fn[k], mac)
        assert m.mpc > 0.9  # real normal modes
    for j, m in enumerate(result):
        if j not in matched:  # a pole that matches no mode of the structure must not pass as one
            assert not m.ok, (m.natural_frequency_hz, m.flags)
    assert "close_modes" in result[matched[5]].flags and "close_modes" in result[matched[6]].flags


def test_synthesis_reproduces_the_noise_free_frf(multi_reference):
    *_, clean, noisy, result = multi_reference
    synth = result.synthesize(clean.frequency_hz)
    assert synth.kind == "accelerance" and synth.channels.shape == clean.channels.shape
    error = np.abs(synth.channels - clean.channels) / np.abs(clean.channels)
    assert np.median(error) < 0.01  # the 1 % asked
    # the synthesis is the model identify fitted: its residual on the noisy data is the noise (0.2 % of peak)
    residual = noisy.channels - synth.channels
    noise = 0.002 * np.abs(clean.channels).max(axis=1)
    assert np.mean(np.abs(residual) ** 2 / noise[:, None] ** 2) == pytest.approx(1.0, abs=0.1)


def test_mac_matrix_is_diagonal_for_distinct_shapes(multi_reference):
    *_, result = multi_reference
    mac = result.mac()
    assert mac.shape == (len(result), len(result))
    np.testing.assert_allclose(np.diag(mac), 1.0, rtol=1e-12)
    assert np.all(mac <= 1 + 1e-12)


def test_stabilisation_diagram_and_settings_are_kept(multi_reference):
    *_, result = multi_reference
    diagram = result.stabilisation
    assert diagram.order.size == diagram.frequency_hz.size == diagram.stable.size > 0
    lo, hi = result.settings["orders"]
    assert set(np.unique(diagram.order)) <= set(range(lo, hi + 1))
    assert result.settings["references"] == ["0", "5"]


def test_plscf_converges_on_noise_free_data():
    # the z-domain basis only approximates a continuous-time FRF: on noise-free data the poles converge
    # geometrically with the order (relative frequency error 4e-4 at order 4, 1e-6 at 8, 1e-9 at 12, 4e-11 at 20)
    fn, zeta = np.array([50.0, 80.0]), np.array([0.02, 0.01])
    f = np.linspace(10, 150, 701)
    frf = modal.modal_frf(f, fn, zeta, np.array([[1.0, 0.5], [0.4, -0.8], [0.7, 0.2]]))
    low, high = plscf_poles(frf.omega_rad_s, frf.channels[:, None, :], [4, 20])
    for pack, tol_f, tol_z in ((low, 2e-3, 0.05), (high, 1e-9, 1e-7)):
        got = pack.omega_n / (2 * np.pi)
        nearest = [int(np.argmin(np.abs(got - x))) for x in fn]
        np.testing.assert_allclose(got[nearest], fn, rtol=tol_f)
        np.testing.assert_allclose(pack.damping_ratio[nearest], zeta, rtol=tol_z)


def test_mpc_of_real_and_complex_vectors():
    assert mpc(np.array([1.0, -2.0, 0.5]) * np.exp(0.7j)) == pytest.approx(1.0, abs=1e-12)
    assert mpc(np.array([1.0, 1j])) == pytest.approx(0.0, abs=1e-12)


def test_errors_are_calibrated_over_noise_seeds():
    """2σ intervals hold the truth about 95 % of the time (as asked), over 120 noise seeds × 3 modes."""
    fn, zeta = np.array([40.0, 65.0, 90.0]), np.array([0.02, 0.015, 0.01])
    const = np.array([[1.0, 0.6, 0.5], [0.6, -0.9, 0.4], [0.5, 0.4, -0.8], [0.3, 0.8, 0.7]])
    f = np.arange(20, 120.001, 0.2)
    clean = modal.modal_frf(f, fn, zeta, const, kind="accelerance")
    z = []
    for seed in range(120):
        result = _fit(modal.add_noise(clean, 0.01, seed=seed), max_order=12)
        found = np.array([m.natural_frequency_hz for m in result])
        for k in range(3):
            m = result[int(np.argmin(np.abs(found - fn[k])))]
            z.append([(m.natural_frequency_hz - fn[k]) / m.std.natural_frequency_hz,
                      (m.damping_ratio - zeta[k]) / m.std.damping_ratio])
    z = np.array(z)
    # 360 z-scores per quantity: the standard deviation of a standard normal sample of 360 is 1 ± 0.037;
    # ±15 % (the bound asked for calibration) is four of those
    assert np.all(np.abs(z.std(axis=0) - 1) < 0.15), z.std(axis=0)
    coverage = np.mean(np.abs(z) < 2, axis=0)
    # 95.4 % expected, binomial SE 1.1 %: 4 of them either side
    assert np.all(np.abs(coverage - 0.954) < 0.045), coverage


def _beam(relative_perturbation=0.0, seed=0):
    """The real beam as one response and three hammer points, each value optionally times (1 + ε·N(0, 1))."""
    paths = sorted(REAL.glob("pyuff_meas_point_*.txt"))
    channels = [modal.read_frf(p, frequency_step=1.0, kind="accelerance") for p in paths]
    H = np.array([c.response for c in channels])
    H = H * (1 + relative_perturbation * np.random.default_rng(seed).standard_normal(H.shape))
    return modal.FRF(channels[0].frequency_hz, H, kind="accelerance", response_points=["1"] * 3,
                     reference_points=["1", "2", "3"])


def test_real_beam_modes_and_synthesis():
    frf = _beam()
    result = _fit(frf)
    assert result.settings["transposed_by_reciprocity"]  # one response, three hammer points
    found = np.array([m.natural_frequency_hz for m in result])
    for f_ref in BEAM_HZ:
        nearest = found[np.argmin(np.abs(found - f_ref))]
        # the reference values are printed to 0.1 Hz: 0.05 % (as asked) is 0.03-0.3 Hz here
        assert abs(nearest / f_ref - 1) < 5e-4, (f_ref, found)
    below = [m for m in result if m.natural_frequency_hz < BEAM_HZ[0] * 0.95]
    assert all(not m.ok for m in below)  # nothing unflagged below the first flexible mode
    for m in result:
        if np.min(np.abs(m.natural_frequency_hz / BEAM_HZ - 1)) < 5e-4:
            # the five modes are explained within the data's own scatter: no model_inadequate fatigue
            assert "model_inadequate" not in m.flags, (m.natural_frequency_hz, m.flags)
    f = frf.frequency_hz
    band = (f >= 20) & (f <= 990)
    error = np.abs(result.synthesize(f[band]).channels - frf.channels[:, band]) / np.abs(frf.channels[:, band])
    assert np.median(error) < 0.06 and np.percentile(error, 90) < 0.35  # the 6 % and 35 % asked
    # and no worse than the joint refinement gave when it came (3.8 % and 8.8 %): the 4 % and 9 % asked since.
    # A pLSCF pole on the band's top edge that wanders above the lines with its damping collapsing onto its floor
    # once kept the final fit going to its iteration limit (every mode did_not_converge); kept at 1059 Hz with
    # ζ = 0, it took the 90th percentile to 9.5 %
    assert np.median(error) <= 0.04 and np.percentile(error, 90) <= 0.09
    assert not any("did_not_converge" in m.flags for m in result)


def test_real_beam_modes_do_not_turn_on_rounding():
    # a relative perturbation of 1e-12 is a few units in the last place of the data: the modes must not move
    # beyond what such a change can move a well-posed fit (1e-12 relative, 1e-8 with the refinement's own
    # tolerances: its last step stops at 1e-9 of a pole). With the stabilisation sweep reaching 1.25 times the
    # top line, the edge pole the selection kept was set by rounding: this perturbation moved the 901 Hz mode by
    # 4e-7, and with pLSCF's sums summed in another order it added a mode at 960.1 Hz
    base = _fit(_beam())
    for seed in (2, 3):
        perturbed = _fit(_beam(1e-12, seed))
        assert len(perturbed) == len(base)
        np.testing.assert_allclose([m.natural_frequency_hz for m in perturbed],
                                   [m.natural_frequency_hz for m in base], rtol=1e-8)
        np.testing.assert_allclose([m.damping_ratio for m in perturbed], [m.damping_ratio for m in base],
                                   rtol=1e-5)  # ζ 1e-4: 1e-9 of ωn is 1e-5 of ζ


def test_plscf_poles_of_the_sweep_do_not_turn_on_rounding():
    # the sweep's basis reaches BEYOND_BAND times the top line; on the real beam's 999 lines every order of
    # the default sweep (14-56) keeps its physical poles under a 1e-12 relative perturbation, to 1e-8 (measured
    # at most 1e-9; with 1.25 they moved by up to 10 % and high orders changed their count by a factor 3)
    from modal.global_.identify import BEYOND_BAND

    orders = list(range(14, 57, 2))
    packs = []
    for frf in (_beam(), _beam(1e-12, 1)):
        weight = 1 / np.sqrt(np.mean(np.abs(frf.channels[:, 1:]) ** 2, axis=1))
        matrix = (frf.channels[:, 1:] * weight[:, None])[:, None, :]
        packs.append(plscf_poles(frf.omega_rad_s[1:], matrix, orders, beyond=BEYOND_BAND))
    for a, b in zip(*packs):
        assert a.omega_n.size == b.omega_n.size, a.order
        np.testing.assert_allclose(b.omega_n, a.omega_n, rtol=1e-8, err_msg=str(a.order))


def test_cli_global_on_the_real_beam_with_a_stabilisation_plot(tmp_path):
    import json
    import os
    import subprocess
    import sys

    import modal.cli
    from support.cli import run_main
    from support.paths import ROOT

    paths = sorted(REAL.glob("pyuff_meas_point_*.txt"))
    plot = tmp_path / "stab.png"
    out = subprocess.run([sys.executable, "-m", "modal", "fit", *map(str, paths), "--frequency-step", "1", "--kind",
                          "accelerance", "--method", "global", "--json", "--stabilisation-plot", str(plot)],
                         capture_output=True, text=True, cwd=ROOT, env={**os.environ, "MPLBACKEND": "Agg"}, timeout=120)
    assert out.returncode == 0, out.stderr
    rows = json.loads(out.stdout)["modes"]
    assert {row["method"] for row in rows} == {"global"} and {row["channel"] for row in rows} == {1, 2, 3}  # counted from 1
    found = np.array(sorted({row["natural_frequency_hz"] for row in rows}))
    assert all(np.min(np.abs(found / f - 1)) < 5e-4 for f in BEAM_HZ)
    assert plot.exists()
    # the refusal is the exit code and the message: in-process
    wrong = run_main(modal.cli.main, ["fit", *paths, "--frequency-step", "1", "--kind", "accelerance", "--method", "nls",
                                      "--order", "30"], cwd=ROOT)
    assert wrong.returncode == 1 and "--order applies to --method global only" in wrong.stderr


def test_stabilisation_plot_draws_every_pole(multi_reference):
    from modal.global_.plots import plot_mac, plot_stabilisation, plot_synthesis

    *_, noisy, result = multi_reference
    fig = plot_stabilisation(noisy, result)
    ax = fig.axes[0]
    drawn = sum(line.get_xdata().size for line in ax.lines if line.get_linestyle() == "None")
    assert drawn == result.stabilisation.order.size  # every pole of every order, once
    assert len([ln for ln in ax.lines if ln.get_linestyle() == "-"]) == len(result)  # one line per chosen mode
    fig = plot_synthesis(noisy, result, channels=[0])
    np.testing.assert_allclose(fig.axes[0].lines[1].get_ydata(), np.abs(result.synthesize(noisy.frequency_hz).channels[0]))
    image = plot_mac(result).axes[0].images[0]
    np.testing.assert_allclose(image.get_array(), result.mac())


def test_uff_export_of_shapes_and_synthesis(tmp_path, multi_reference):
    import gc

    import pyuff

    from modal.global_.export import export_uff

    fn, zeta, const, clean, noisy, result = multi_reference
    path = tmp_path / "modes.uff"
    export_uff(result, noisy, path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pyuff leaves its file handles to the garbage collector
        uff = pyuff.UFF(str(path))
        types = list(uff.get_set_types())
        first = uff.read_sets(0)
        gc.collect()
    assert types == [55] * len(result) + [58] * noisy.n_channels
    # the shape of mode 1 on the first reference's channels (every other channel: references alternate),
    # on the nodes of the point ids ("0".."11" are bare nodes: z direction), to the 6 digits of ASCII UFF
    np.testing.assert_allclose(first["r3"], np.asarray(result[0].modal_constant)[0::2], rtol=2e-5, atol=1e-9)
    wn, z = result[0].omega_n_rad_s, result[0].damping_ratio
    assert first["eig"] == pytest.approx(complex(-z * wn, wn * np.sqrt(1 - z**2)), rel=1e-5)
    back = modal.read_frf(path)  # the FRF datasets: the synthesis, readable by the toolkit itself
    np.testing.assert_allclose(back.response, result.synthesize(back.frequency_hz).channels, rtol=1e-5,
                               atol=1e-5 * np.abs(back.response).max())


def test_automatic_choice_of_method(multi_reference):
    from modal.identify import choose_method

    *_, noisy, _ = multi_reference
    assert choose_method(noisy) == "global"  # a poly-reference grid
    assert _fit_auto(noisy.channel(0)).method == "global"  # one channel, 14 peaks: many modes
    few = modal.modal_frf(np.linspace(10, 200, 800), [50.0, 120.0], [0.02, 0.01], [1.0, 0.5])
    assert _fit_auto(few).method == "nls"  # two well-separated modes: the band-wise fit
    assert choose_method(noisy, bands_hz=[(190, 210)]) == "nls"  # bands given: band-wise


def _fit_auto(frf):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        return modal.identify(frf)


def test_no_phantom_mode_on_the_tail_of_a_wide_mode():
    """One channel, three modes, 0.1 % noise: a pLSCF pole on the tail of the 300 Hz mode passed the
    significance test at its pLSCF value, then shrank onto a noise spike in the joint fit (statistic 1.9 and
    9.2 against the 1e-6 quantile 13.8 for seeds 1 and 7). The refined poles are tested again; a mode that
    only fits noise passes once in 10⁶, so over 12 seeds exactly the three modes are expected."""
    f = np.linspace(10, 400, 1001)
    clean = modal.modal_frf(f, [50, 120, 300], [0.01, 0.02, 0.03], [1, 0.5, 2.0], kind="mobility")
    for seed in range(12):
        result = _fit(modal.add_noise(clean, 0.001, seed=seed))
        assert len(result) == 3, (seed, [m.natural_frequency_hz for m in result])
        assert np.allclose([m.natural_frequency_hz for m in result], [50, 120, 300], rtol=1e-3)


def test_mode_just_above_the_band_enters_the_model():
    """The benchmark case (60 outputs x 2 references, 4000 lines over 20-400 Hz, a mode at 430 Hz) at noise seed 4:
    pLSCF saw the 430 Hz mode only as a chain wandering over 405-409 Hz in 4 of 17 orders, the selection left it
    out, the residual terms absorbed it badly and the 190 Hz damping came out 10 of its errors off, unflagged.
    Chains outside the lines now enter the joint fit and its significance test keeps the real one: every
    in-band mode within 4 errors (a 4σ excursion among 24 values has probability 1.5e-3), the 430 Hz mode found
    and flagged outside_band."""
    from benchmarks.bench_global import BAND, FN, ZETA, make_case

    _, noisy = make_case(seed=4)
    result = _fit(noisy)
    found = np.array([m.natural_frequency_hz for m in result])
    above = result[int(np.argmin(np.abs(found - 430.0)))]
    assert abs(above.natural_frequency_hz / 430.0 - 1) < 3e-3 and "outside_band" in above.flags
    for f_true, z_true in zip(FN[FN < BAND[1]], ZETA[FN < BAND[1]]):
        m = result[int(np.argmin(np.abs(found - f_true)))]
        assert abs(m.natural_frequency_hz - f_true) < 4 * m.std.natural_frequency_hz, (f_true, m.natural_frequency_hz)
        assert abs(m.damping_ratio - z_true) < 4 * m.std.damping_ratio, (f_true, m.damping_ratio, m.std.damping_ratio)


def wide_band_structure(n_out: int = 12):
    """12 response points x 2 references on 4000 lines of 0.5 Hz (0.5-2000 Hz), accelerance: an under-resolved
    first mode (47.3 Hz, ζ 0.42 %: a half-power bandwidth of 0.40 Hz, under the line spacing), a close pair at
    300/302.5 Hz with orthogonal participation, a mode at 655 Hz driven at a fifth of the others, and two modes
    above the band (2150 and 2500 Hz) leaking into its top."""
    fn = np.array([47.3, 118., 205., 300., 302.5, 410., 540., 655., 790., 930., 1080., 1240., 1420., 2150., 2500.])
    zeta = np.array([0.0042, 0.012, 0.01, 0.008, 0.008, 0.008, 0.007, 0.007, 0.006, 0.006, 0.006, 0.005, 0.005,
                     0.005, 0.005])
    rng = np.random.default_rng(11)
    refs = [0, 1]
    phi = rng.normal(size=(n_out, fn.size))
    phi[refs] = rng.choice([-1, 1], size=(2, fn.size)) * rng.uniform(0.6, 1.2, size=(2, fn.size))
    phi[refs, 3], phi[refs, 4] = [1.0, 1.0], [1.0, -1.0]
    phi[refs, 7] *= 0.2
    const = np.array([[phi[o, r] * phi[q, r] for r in range(fn.size)] for o in range(n_out) for q in refs])
    f = 0.5 * np.arange(1, 4001)
    clean = modal.modal_frf(f, fn, zeta, const, kind="accelerance",
                            response_points=[str(o) for o in range(n_out) for q in refs],
                            reference_points=[str(q) for o in range(n_out) for q in refs])
    return fn, zeta, clean


@pytest.mark.parametrize("seed", [1, 2])
def test_wide_band_every_mode_found_none_invented(seed):
    """Before: pLSCF over the wide band did not show the under-resolved 47.3 Hz mode (nor, at seed 1, the close
    pair as two), and poles it had put on the tail of the modes above the band widened in the joint fit into a
    pair of wide poles (seed 2: 244.5 Hz, ζ 3.6, twice) that the significance test kept, since together they
    absorbed the leakage the residual terms leave. Now poles that widen past pLSCF's damping limit inside the
    lines are dropped, the poles outside the lines enter once the in-band modes are in place, and modes the
    residual shows (a peak where the model has none, a mode the model does not explain tried as two) enter as
    candidates: every in-band mode is found, each once, and nothing without a physical counterpart."""
    fn, zeta, clean = wide_band_structure()
    result = _fit(modal.add_noise(clean, 0.005, seed=seed))  # 0.5 % of each channel's peak
    found = np.array([m.natural_frequency_hz for m in result])
    in_band = np.flatnonzero(fn < 2000)
    matched = [int(np.argmin(np.abs(found - fn[k]))) for k in in_band]
    for k, j in zip(in_band, matched):
        assert abs(found[j] / fn[k] - 1) < 3e-3, (fn[k], found)
        m = result[j]
        # errors within 4 of the reported standard errors (27 values over the two seeds: a 4σ excursion
        # among them has probability 2e-3)
        assert abs(m.natural_frequency_hz - fn[k]) < 4 * m.std.natural_frequency_hz, (fn[k], m)
        assert abs(m.damping_ratio - zeta[k]) < 4 * m.std.damping_ratio, (fn[k], m.damping_ratio, m.std.damping_ratio)
    assert len(set(matched)) == in_band.size  # the close pair is two modes
    # a pole above the band whose damping collapsed onto its floor once kept the final fit going to its
    # iteration limit, and every mode was flagged did_not_converge
    assert not any("did_not_converge" in m.flags for m in result)
    for j, m in enumerate(result):
        if j not in matched:
            # only the modes above the band, reported as such: poles the lines barely determine (seen: 2325 ± 94 Hz
            # and 2591 ± 185 Hz for the 2500 Hz mode), within 4 of their standard errors of a mode there
            assert m.natural_frequency_hz > 2000 and "outside_band" in m.flags, (m.natural_frequency_hz, m.flags)
            assert np.min(np.abs(m.natural_frequency_hz - fn[in_band.size:])) < 4 * m.std.natural_frequency_hz, m
            assert m.damping_ratio < 0.3


def test_under_resolved_mode_is_reported_flagged_with_honest_errors():
    """The 47.3 Hz mode's half-power bandwidth (0.40 Hz) is under the 0.5 Hz line spacing: it is reported,
    flagged resolution_limited, with standard errors from the Fisher information of the fit (the peak's shape
    on the few lines around it, over every channel), which hold the truth: over 6 noise seeds the z-scores
    of its frequency and damping have an RMS of 1 within the ±0.6 that 6 standard normal values give (a
    chi-square of 6 degrees of freedom lies within its 99.9 % interval [0.4, 22.5]/6 of 1 in RMS²)."""
    fn, zeta, clean = wide_band_structure()
    z = []
    for seed in range(6):
        result = _fit(modal.add_noise(clean, 0.005, seed=seed))
        found = np.array([m.natural_frequency_hz for m in result])
        m = result[int(np.argmin(np.abs(found - fn[0])))]
        assert abs(m.natural_frequency_hz / fn[0] - 1) < 3e-3, found
        assert "resolution_limited" in m.flags and m.lines_per_bandwidth < 1
        z.append([(m.natural_frequency_hz - fn[0]) / m.std.natural_frequency_hz,
                  (m.damping_ratio - zeta[0]) / m.std.damping_ratio])
    rms2 = np.mean(np.square(z), axis=0)
    assert np.all(rms2 > 0.4 / 6) and np.all(rms2 < 22.5 / 6), z


def test_loose_stages_sample_the_lines_far_from_every_mode():
    """The loose stages of the joint refinement fit every line within two half-power bandwidths of a pole and in
    the band's top and bottom 5 %, and every 4th line elsewhere with weight 2 (its share of the cost kept in
    expectation); every line where that would keep more than 80 % of them. The sampled fit only starts the
    final one, to every line: on the wide-band structure the final fit from the sampled loose fit and from a
    loose fit to every line end within 0.1 of a standard error of each other, the distance the final stage's
    decrement test leaves (a step under 0.014 errors, ~0.1 of one for a pole converging linearly)."""
    from modal.frf import KIND_POWER
    from modal.global_.identify import LOOSE_DECREMENT, TIGHT_DECREMENT, _loose_lines
    from modal.nls import fit_modes

    fn, zeta, clean = wide_band_structure()
    noisy = modal.add_noise(clean, 0.005, seed=3)
    omega, H = noisy.omega_rad_s, noisy.channels
    wn0, zeta0 = 2 * np.pi * fn[:13] * 1.0005, zeta[:13] * 1.05
    index, weight = _loose_lines(omega, wn0, zeta0)
    near = np.zeros(omega.size, bool)
    for w, z in zip(wn0, zeta0):
        near |= np.abs(omega - w) <= max(4 * z * w, 3 * (omega[1] - omega[0]))
    near[:200] = near[-200:] = True  # 5 % of 4000 lines at either end
    assert set(np.flatnonzero(near)) <= set(index) and np.all(weight[near[index]] == 1.0)
    far = index[~near[index]]
    assert np.all(far % 4 == 0) and np.all(weight[~near[index]] == 2.0)
    assert index.size < 0.8 * omega.size
    common = dict(region=None, residual_terms=True, step_tol=1e-9, decrement_tol=LOOSE_DECREMENT)
    power = KIND_POWER[noisy.kind]
    every = fit_modes(omega, H, power, wn0, zeta0, **common)
    sampled = fit_modes(omega[index], H[:, index], power, wn0, zeta0, line_weight=weight,
                        channel_scale=np.abs(H).max(axis=1), **common)
    final = dict(common, decrement_tol=TIGHT_DECREMENT)
    after_every = fit_modes(omega, H, power, every.omega_n, every.damping_ratio, **final)
    after_sampled = fit_modes(omega, H, power, sampled.omega_n, sampled.damping_ratio, **final)
    s_wn, s_zeta = np.sqrt(after_every.mode_cov[:, 0, 0, 0]), np.sqrt(after_every.mode_cov[:, 0, 1, 1])
    assert np.all(np.abs(after_sampled.omega_n - after_every.omega_n) < 0.1 * s_wn)
    assert np.all(np.abs(after_sampled.damping_ratio - after_every.damping_ratio) < 0.1 * s_zeta)
    # a line spacing as wide as the modes: nothing far from them to sample, every line
    assert _loose_lines(omega[::100], wn0, zeta0) is None


def test_modes_above_the_band_come_from_the_low_order_sweep():
    # the benchmark's wide-band case at noise seed 1: modes at 2150 and 2500 Hz above 0.5-2000 Hz lines. The
    # stabilisation sweep's basis reaches only 1.05 times the top line; without the low-order sweep reaching 1.25
    # the 2500 Hz mode is left to the residual terms, which absorb it badly, and the 2150 Hz mode came out at
    # 2153.24 ± 0.68 Hz (4.8 of its errors off). Both above-band modes are found within 4 of their errors (a
    # 4σ excursion has probability 6e-5) and flagged outside_band
    from benchmarks.bench_global import WIDE_BAND, WIDE_FN, make_wide_case

    _, noisy = make_wide_case(seed=1)
    result = _fit(noisy)
    above = [m for m in result if m.natural_frequency_hz > WIDE_BAND[1]]
    assert len(above) == 2
    for m, f_true in zip(above, WIDE_FN[WIDE_FN > WIDE_BAND[1]]):
        assert "outside_band" in m.flags
        assert abs(m.natural_frequency_hz - f_true) < 4 * m.std.natural_frequency_hz, (f_true, m.natural_frequency_hz)


def test_a_weak_mode_misfit_by_a_strong_neighbour_splits_the_neighbour():
    from modal.global_.identify import _split_candidate

    omega = np.linspace(10.0, 100.0, 91)
    omega_n = np.array([20.0, 50.0, 57.0, 90.0])
    # mode 1 (weak, flagged) sits in the skirt of mode 2, whose misfit is larger: mode 2 is tried as two; mode 3
    # leaves more misfit still but is farther
    assert _split_candidate(omega, omega_n, np.array([1.0, 5.0, 50.0, 80.0]), 1) == 2
    # the flagged mode leaves the most misfit itself: it is the one tried as two
    assert _split_candidate(omega, omega_n, np.array([1.0, 90.0, 50.0, 80.0]), 1) == 1
    # a stronger misfit outside the lines (a mode above the band) is no candidate
    assert _split_candidate(omega, np.array([20.0, 50.0, 120.0]), np.array([1.0, 5.0, 80.0]), 1) == 1


def test_pseudo_inverse_factor_leaves_out_the_directions_zero_to_rounding():
    from modal.global_.plscf import RANK_TOL, _pseudo_inverse_factor

    basis, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(4, 4)))
    eigenvalues = np.array([2.0, 1e-3, 1e-9, 1e-15])  # the last below RANK_TOL of the largest
    G = _pseudo_inverse_factor(basis @ np.diag(eigenvalues) @ basis.T)
    assert G.shape == (3, 4)
    kept = np.where(eigenvalues > RANK_TOL * eigenvalues.max(), 1 / eigenvalues, 0.0)
    # GᵀG is that pseudo-inverse to the eigen-decomposition's rounding: ~ε·λ_max = 4e-16 absolute moves the 1e-9
    # eigenvalue by 4e-7 of itself and its inverse (1e9) by ~400, hence 1e3 absolute (1e-6 of the largest entry)
    np.testing.assert_allclose(G.T @ G, basis @ np.diag(kept) @ basis.T, rtol=1e-6, atol=1e3)
    assert _pseudo_inverse_factor(np.zeros((3, 3))) is None


def test_the_band_given_as_band_hz_as_bands_hz_extremes_and_bad_options_named():
    """identify(frf, "global", band_hz=(lo, hi)), the name modal.oma uses, raised a TypeError from deep inside
    (identify passed its own band_hz too); it is the band, as bands_hz's extremes are. Both at once, or an option
    the global method does not take, are named."""
    f = np.arange(1.0, 200.0, 0.5)
    frf = modal.add_noise(modal.modal_frf(f, [30.0, 80.0, 150.0], [0.02, 0.01, 0.01], [1.0, 0.5, 0.8],
                                          kind="accelerance"), 0.002, seed=3)
    by_name, by_extremes = _fit(frf, band_hz=(60.0, 190.0)), _fit(frf, bands_hz=[(60.0, 100.0), (120.0, 190.0)])
    assert [m.natural_frequency_hz for m in by_name] == [m.natural_frequency_hz for m in by_extremes]
    assert np.allclose([m.natural_frequency_hz for m in by_name], [80.0, 150.0], rtol=1e-3)
    with pytest.raises(modal.IdentificationError, match="band once: band_hz=.* or bands_hz"):
        _fit(frf, band_hz=(60.0, 190.0), bands_hz=[(60.0, 190.0)])
    with pytest.raises(TypeError, match=r"unexpected option\(s\) band; method='global' takes modes_hz, order"):
        _fit(frf, band=(60.0, 190.0))


def test_final_fit_of_an_estimate_weighs_and_whitens_its_lines(monkeypatch):
    # an FRF estimated from hammer hits carries its lines' noise shape and correlation (an exponential window
    # correlates the errors over tens of lines); the band-wise fits weigh and whiten by them, and the global
    # method's final fit, whose covariance gives the reported errors, must too: unweighted and unwhitened its
    # errors scattered 1.5-2.5 times as wide as they said (benchmarks/bench_chain.py, hammer-exp-*-ch3-global).
    # The loose stages, on a sample of the lines, only start it and stay unweighted
    import modal.global_.identify as global_identify
    from modal.global_.window import without_window_factor
    from modal.sdof.bands import weight_on_lines
    from modal.synthetic_time import DigitalModes, impact_record

    system = DigitalModes(np.array([40.0, 95.0]), np.array([0.02, 0.012]), np.array([[0.5, 0.8], [0.3, -0.4]]),
                          512.0)
    hits = 0.25 + 2.0 * np.arange(3)
    record = impact_record(system, hits, hits[-1] + 2.0, pulse_width_s=0.004, response_noise=0.002,
                           force_noise=0.002, seed=1).record
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", modal.ModalWarning)
        frf = modal.estimate_frf(record.signals[0], record.signals[1:], record.sample_rate_hz, impact=True,
                                 window="exponential", exponential_decay_s=0.5, kind="accelerance",
                                 excitation_points=["1"], response_points=["1", "2"])
    calls = []
    real = global_identify.fit_modes

    def spy(*args, **kwargs):
        calls.append(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(global_identify, "fit_modes", spy)
    result = _fit(frf)
    assert len(result.modes) == 2
    final = [c for c in calls if c["errors"]]
    loose = [c for c in calls if not c["errors"]]
    assert final and loose
    work, _ = without_window_factor(frf.cropped(float(frf.frequency_hz[frf.frequency_hz > 0][0]),
                                                float(frf.frequency_hz[-1])))
    expected = weight_on_lines(work, np.ones(work.n_freq, bool))
    assert expected is not None and np.ptp(expected) > 0  # the lines' noise does differ
    for c in final:
        assert np.array_equal(c["line_weight"], expected)
        assert c["whitening"] is not None and c["whitening"].bandwidth > 10  # the window's tens of lines
        assert c["correlated_lags"] >= 2  # the lag covariance may widen the errors of the two channels
    assert all(c.get("whitening") is None for c in loose)


def test_an_exponentially_windowed_accelerance_is_fitted_as_the_window_made_it():
    # an exponential window exp(−t/τ) on a force and an acceleration record gives ((iω + 1/τ)/(iω))² times the
    # accelerance at the moved poles p − 1/τ (modal.global_.window): over the global method's whole band that
    # factor is no constant the modal constants could take up (it changes by 13 % between 5 and 40 Hz at
    # τ = 0.5 s). Taken out of the data, the model is exact: nearly noise-free lines (1e-9 of the peak, which
    # moves fn by ~2e-11 relative) give the structure's poles and constants to 1e-8 relative, ten times the final
    # fit's step tolerance (1e-9); fitted with the factor in the data, fn moved by 5.5e-4 Hz (1.4e-5) and the
    # constants by 4e-4
    from dataclasses import replace

    tau = 0.5
    fn, zeta = np.array([40.0, 95.0]), np.array([0.02, 0.012])
    constants = np.array([[0.5, 0.8], [0.3, -0.4]])
    moved = -zeta * 2 * np.pi * fn + 2j * np.pi * fn * np.sqrt(1 - zeta**2) - 1 / tau
    f = np.arange(1, 2049) * 0.25
    receptance = modal.modal_frf(f, np.abs(moved) / (2 * np.pi), -moved.real / np.abs(moved), constants,
                                 kind="receptance").channels
    s = 2j * np.pi * f
    frf = modal.FRF(f, (s + 1 / tau) ** 2 * receptance, kind="accelerance", response_points=["1", "2"],
                    reference_points=["1", "1"], exponential_decay_s=tau)
    noisy = modal.add_noise(frf, 1e-9, seed=0)
    noisy = replace(noisy, noise_std=1e-9 * np.abs(noisy.channels).max(axis=1)[:, None] * np.ones(f.size))
    result = _fit(noisy)
    assert len(result.modes) == 2
    # the noise level the significance test and the flags read is the data's as fitted, divided by the factor
    factor = np.abs((s + 1 / tau) / s) ** 2
    np.testing.assert_allclose(result.noise_std, np.sqrt(np.mean((noisy.noise_std / factor) ** 2, axis=1)))
    for mode, f_true, z_true, a_true in zip(result.modes, fn, zeta, constants.T):
        assert abs(mode.natural_frequency_hz / f_true - 1) < 1e-8
        assert abs(mode.damping_ratio / z_true - 1) < 1e-8
        np.testing.assert_allclose(mode.modal_constant, a_true, rtol=1e-8, atol=1e-8)
