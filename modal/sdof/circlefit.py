"""Circle fit (Kennedy–Pancu) on the mobility circle.

For one viscous mode the mobility ``Y = iωA/(ωr² − ω² + 2iζωrω)`` traces an
exact circle; the angle of each point about the centre is
``θ = ψ0 + 2 atan((ωr² − ω²)/(2ζωrω))``. The circle comes from the algebraic
Hyper fit (Al-Sharadqah & Chernov 2009) on centred, scaled points; ωr and ζ
come from a least-squares fit of that angle model, started from the classical
maximum-sweep-rate frequency and Ewins' damping pairs, whose spread is kept as
a quality measure. ``|A| = 2ζωr · diameter`` and its phase is the direction of
the diameter through the resonance point; the opposite end is the residual.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


__all__ = ["CircleEstimate", "fit_circle", "fit_circles", "circle_fit_curve"]


def fit_circle(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Hyper algebraic circle fit; returns (xc, yc, radius).

    Points are centred and scaled first (the normal matrix is then well
    conditioned at any physical scale). Falls back to Kasa's fit when the Hyper
    generalised eigenproblem has no admissible solution.
    """
    xc, yc, r = fit_circles(np.asarray(x, float)[None, :], np.asarray(y, float)[None, :])
    return float(xc[0]), float(yc[0]), float(r[0])


def fit_circles(x: np.ndarray, y: np.ndarray):
    """:func:`fit_circle` of a batch of point sets ``x``, ``y`` (B, n); returns three arrays (B,)."""
    mx, my = x.mean(axis=1, keepdims=True), y.mean(axis=1, keepdims=True)
    scale = np.sqrt(np.mean((x - mx) ** 2 + (y - my) ** 2, axis=1, keepdims=True))
    scale = np.where(scale > 0, scale, 1.0)
    u, v = (x - mx) / scale, (y - my) / scale
    z = u**2 + v**2
    Z = np.stack([z, u, v, np.ones_like(u)], axis=2)  # (B, n, 4)
    M = np.einsum("bni,bnj->bij", Z, Z) / u.shape[1]
    zbar = z.mean(axis=1)
    N = np.zeros_like(M)
    N[:, 0, 0] = 8 * zbar
    N[:, 0, 3] = N[:, 3, 0] = 2
    N[:, 1, 1] = N[:, 2, 2] = 1
    a = np.full((x.shape[0], 4), np.nan)
    try:  # N is invertible for Hyper: M a = η N a  ⇔  N⁻¹M a = η a
        vals, vecs = np.linalg.eig(np.linalg.solve(N, M))
        vecs = np.real(vecs)  # (B, 4, 4): columns are the eigenvectors
        norm = np.einsum("bik,bij,bjk->bk", vecs, N, vecs)
        eta = np.einsum("bik,bij,bjk->bk", vecs, M, vecs) / np.where(norm != 0, norm, np.nan)
        admissible = (np.isfinite(vals) & (np.abs(vals.imag) <= 1e-9 * (1 + np.abs(vals.real))) & (norm > 0)
                      & (np.abs(vecs[:, 0, :]) >= 1e-14 * np.linalg.norm(vecs, axis=1)))
        eta = np.where(admissible, eta, np.inf)
        best = np.argmin(eta, axis=1)
        found = np.isfinite(eta[np.arange(x.shape[0]), best])
        a[found] = vecs[found, :, best[found]]
    except (np.linalg.LinAlgError, ValueError):
        found = np.zeros(x.shape[0], bool)
    for k in np.flatnonzero(~found):  # Kasa: z + B u + C v + D = 0, linear
        sol, *_ = np.linalg.lstsq(np.column_stack([u[k], v[k], np.ones_like(u[k])]), -z[k], rcond=None)
        a[k] = [1.0, *sol]
    A, B, C, D = a.T
    uc, vc = -B / (2 * A), -C / (2 * A)
    radius = np.sqrt(np.maximum(B**2 + C**2 - 4 * A * D, 0.0)) / (2 * np.abs(A))
    return mx[:, 0] + scale[:, 0] * uc, my[:, 0] + scale[:, 0] * vc, scale[:, 0] * radius


def directional_unwrap(angles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Unwrap angles assuming they move one way (the sweep direction of the points).

    ``np.unwrap`` fails when a line step is larger than π (fewer than ~1.3 lines
    per half-power width); here steps are mapped into (−3π/2, π/2] for a
    clockwise sweep (and mirrored otherwise).
    """
    direction = np.sign(np.sum(np.imag(np.conj(points[:-1]) * points[1:]))) or -1.0
    steps = np.diff(angles) * direction  # now a mostly positive sweep
    steps = np.mod(steps + np.pi / 2, 2 * np.pi) - np.pi / 2  # into [−π/2, 3π/2)
    return np.concatenate([[angles[0]], angles[0] + direction * np.cumsum(steps)])


@dataclass(frozen=True)
class CircleEstimate:
    """Circle-fit result on one channel (ω in rad/s, modal constant in 1/kg)."""

    omega_n: float
    damping_ratio: float
    modal_constant: complex
    residual_offset: complex
    std_omega_n: float
    std_damping_ratio: float
    damping_pair_spread: float
    n_points: int
    flags: tuple[str, ...]
    #: covariance of (ωn, ζ, Re A, Im A) propagated from the noise through this estimator
    #: (NaN without a noise level); the errors above are its diagonal (plus quantisation
    #: where the peak is unresolved)
    cov: np.ndarray | None = None
    #: ∂(ωn, ζ, Re A, Im A)/∂(Re Y, Im Y) on every line of the band, shape (4, 2, n)
    jacobian: np.ndarray | None = None


def _angle_model(params, w):
    wr, zeta, psi = params
    return psi + 2 * np.arctan((wr**2 - w**2) / (2 * zeta * wr * w))


def _angle_jac(params, w):
    wr, zeta, psi = params
    t = (wr**2 - w**2) / (2 * zeta * wr * w)
    common = 2 / (1 + t**2)
    dt_dwr = (wr**2 + w**2) / (2 * zeta * wr**2 * w)
    dt_dzeta = -t / zeta
    return np.column_stack([common * dt_dwr, common * dt_dzeta, np.ones_like(w)])


def _levenberg_marquardt(p0, xs, theta, max_iter=100):
    """Least squares of the angle model (3 parameters), Marquardt-scaled LM."""
    p = p0.astype(float).copy()
    r = _angle_model(p, xs) - theta
    cost = r @ r
    lam = 1e-3
    for _ in range(max_iter):
        J = _angle_jac(p, xs)
        JtJ, g = J.T @ J, J.T @ r
        d = np.diag(JtJ).copy()
        d[d <= 0] = 1e-300
        improved = False
        for _ in range(30):
            try:
                step = np.linalg.solve(JtJ + lam * np.diag(d), -g)
            except np.linalg.LinAlgError:
                lam *= 10
                continue
            trial = p + step
            if trial[0] > 0 and trial[1] > 0:
                r_new = _angle_model(trial, xs) - theta
                c_new = r_new @ r_new
                if np.isfinite(c_new) and c_new <= cost:
                    improved = True
                    break
            lam *= 4
        if not improved:
            break
        rel = np.max(np.abs(step) / np.maximum(np.abs(trial), 1e-300))
        p, r, cost = trial, r_new, c_new
        lam = max(lam / 3, 1e-12)
        if rel < 1e-14:
            break
    ok = bool(np.all(np.isfinite(p)) and p[0] > 0 and p[1] > 0)
    return p, r, _angle_jac(p, xs), ok


def _centre_jacobian(x, y):
    """∂(xc, yc, ρ)/∂(x_j, y_j) of :func:`fit_circle`, shape (3, 2, n), by central differences
    (one batch of 4n perturbed point sets)."""
    n = x.size
    scale = float(np.sqrt(np.mean((x - x.mean()) ** 2 + (y - y.mean()) ** 2))) or 1.0
    step = 1e-6 * scale
    xs = np.repeat(x[None, :], 4 * n, axis=0)
    ys = np.repeat(y[None, :], 4 * n, axis=0)
    j = np.arange(n)
    xs[4 * j, j] += step
    xs[4 * j + 1, j] -= step
    ys[4 * j + 2, j] += step
    ys[4 * j + 3, j] -= step
    out = np.array(fit_circles(xs, ys))  # (3, 4n)
    jac = np.empty((3, 2, n))
    jac[:, 0] = (out[:, 0::4] - out[:, 1::4]) / (2 * step)
    jac[:, 1] = (out[:, 2::4] - out[:, 3::4]) / (2 * step)
    return jac


def _linearisation(z, centre, rho, xs, params, w_ref):
    """∂(ωn, ζ, Re A, Im A)/∂(Re z_j, Im z_j) of the circle fit, shape (4, 2, n).

    First order through every step the estimate takes: the Hyper circle
    (numerically, :func:`_centre_jacobian`), the angles about its centre
    (dθ_j = Im((dz_j − dc)/(z_j − c))), the Gauss–Newton solution of the angle
    least squares (dp = (JᵀJ)⁻¹Jᵀ dθ) and A = 2ζωn·2ρ·e^{iψ}.
    """
    n = z.size
    x_n, zeta, psi = params
    d_circle = _centre_jacobian(z.real, z.imag)  # (3, 2, n)
    w = z - centre
    a2 = np.abs(w) ** 2
    # direct part of dθ_j (z_j moves) per (Re, Im)
    d_theta = np.zeros((n, 2, n))
    idx = np.arange(n)
    d_theta[idx, 0, idx] = -w.imag / a2
    d_theta[idx, 1, idx] = w.real / a2
    # through the centre: dθ_j = −(−w_i dxc + w_r dyc)/|w|²
    d_theta -= (-w.imag / a2)[:, None, None] * d_circle[0][None] + (w.real / a2)[:, None, None] * d_circle[1][None]
    J = _angle_jac(params, xs)
    solve = np.linalg.solve(J.T @ J, J.T)  # (3, n)
    d_params = np.einsum("pj,jkn->pkn", solve, d_theta)  # (3, 2, n): x_n, ζ, ψ
    d_wn = w_ref * d_params[0]
    d_zeta = d_params[1]
    d_rho = d_circle[2]
    wn = x_n * w_ref
    A = 2 * zeta * wn * 2 * rho * np.exp(1j * psi)
    dA = A * (d_zeta / zeta + d_wn / wn + d_rho / rho + 1j * d_params[2])
    return np.stack([d_wn, d_zeta, dA.real, dA.imag])


def circle_fit_curve(omega: np.ndarray, mobility: np.ndarray, noise_std, errors: bool = True) -> CircleEstimate:
    """Circle fit of the strongest mode in a band, on one channel of mobility.

    Parameters
    ----------
    omega : ndarray
        Lines of the band, rad/s.
    mobility : ndarray of complex
        Mobility on those lines (convert other kinds exactly first).
    noise_std : float or ndarray
        σ of the complex noise on the mobility, one value or one per line (for the
        standard errors, propagated through the estimator's linearisation).
    errors : bool
        False: the estimate only (standard errors NaN, no covariance), for start values.
    """
    mag = np.abs(mobility)
    n = mag.size
    i = int(np.argmax(mag))
    flags: list[str] = []
    if i == 0 or i == n - 1:
        flags.append("band_edge_peak")
    n_above = int(np.sum(mag >= mag[i] / np.sqrt(2)))
    if n_above < 3:
        flags.append("resolution_limited")
    sel = np.flatnonzero(mag >= 0.5 * mag[i])
    if sel.size < 7:  # take the 7 lines nearest to the peak
        lo = max(0, min(i - 3, n - 7))
        sel = np.arange(lo, min(n, lo + 7))
    if sel.size < 5:
        raise ValueError(f"circle fit needs at least 5 lines near resonance, the band holds {n}")
    w, z = omega[sel], mobility[sel]
    # fit in scaled units so that any physical scale is fine
    w_ref = omega[i]
    xs = w / w_ref
    xc, yc, rho = fit_circle(z.real, z.imag)
    centre = complex(xc, yc)
    theta = directional_unwrap(np.angle(z - centre), z - centre)
    # classical start: maximum sweep rate and damping pairs
    rate = np.abs(np.diff(theta) / np.diff(xs))
    k = int(np.argmax(rate))
    x_r = 0.5 * (xs[k] + xs[k + 1])
    theta_r = 0.5 * (theta[k] + theta[k + 1])
    below = xs < x_r
    above = xs > x_r
    alpha_a = np.abs(theta[below] - theta_r)[:, None]
    alpha_b = np.abs(theta_r - theta[above])[None, :]
    xa, xb = xs[below][:, None], xs[above][None, :]
    valid = (alpha_a > 0.05) & (alpha_a < 3.0) & (alpha_b > 0.05) & (alpha_b < 3.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        pairs = (xb**2 - xa**2) / (2 * x_r * (xa * np.tan(alpha_a / 2) + xb * np.tan(alpha_b / 2)))
    zetas = pairs[valid]
    zetas = zetas[np.isfinite(zetas) & (zetas > 0)]
    if zetas.size:
        zeta0 = float(np.median(zetas))
        spread = float(np.std(zetas) / np.mean(zetas)) if zetas.size > 1 else 0.0
    else:
        zeta0 = max((xs[-1] - xs[0]) / 4, 1e-6)
        spread = np.nan
    x_r = x_r / (1 - zeta0**2 / 2)  # max sweep rate lies at ωr(1 − ζ²/2)
    p0 = np.array([x_r, zeta0, theta_r])
    params, residual, jac, ok = _levenberg_marquardt(p0, xs, theta)
    x_n, zeta, psi = params
    # a pole outside the fitted lines or a damping ratio above 1 is no estimate (too few
    # points on the arc): keep the classical values, flagged
    if ok and not (xs[0] <= x_n <= xs[-1] and zeta < 1.0):
        ok = False
    if not ok:
        x_n, zeta, psi = p0
        if not (xs[0] <= x_n <= xs[-1]):
            x_n = xs[int(np.argmin(np.abs(sel - i)))]  # the selected line nearest the peak
        zeta = min(zeta, 1.0)
        flags.append("did_not_converge")
    std_x = std_z = np.nan
    cov = jacobian = None
    if ok and errors:
        # the estimator's own errors, to first order: its linearisation in the data times the
        # noise of each line (σ/√2 on the real and on the imaginary part, independently)
        with np.errstate(all="ignore"):
            local = _linearisation(z, centre, rho, xs, params, w_ref)  # (4, 2, n_sel)
        jacobian = np.zeros((4, 2, n))
        jacobian[:, :, sel] = local
        line_var = np.broadcast_to(np.asarray(noise_std, float) ** 2 / 2, (n,))
        if np.all(np.isfinite(line_var)) and np.all(np.isfinite(jacobian)):
            cov = np.einsum("pkn,n,qkn->pq", jacobian, line_var, jacobian)
            std_x, std_z = np.sqrt(cov[0, 0]) / w_ref, np.sqrt(cov[1, 1])
    if "resolution_limited" in flags or not ok:
        # unresolved peak: the line spacing bounds what the data can say (quantisation)
        spacing = float(np.min(np.diff(xs)))
        std_x = float(np.hypot(std_x if np.isfinite(std_x) else 0.0, spacing / np.sqrt(12)))
        std_z = float(np.hypot(std_z if np.isfinite(std_z) else 0.0, spacing / (2 * x_n)))
    omega_n = x_n * w_ref
    modal_constant = 2 * zeta * omega_n * 2 * rho * np.exp(1j * psi)
    residual = centre - rho * np.exp(1j * psi)
    if np.isfinite(spread) and spread > 0.2:
        flags.append("damping_pair_spread")
    return CircleEstimate(float(omega_n), float(zeta), complex(modal_constant), complex(residual),
                          float(std_x * w_ref), float(std_z), spread, int(xs.size), tuple(flags), cov, jacobian)
