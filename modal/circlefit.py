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

from .model import cramer_rao_sdof

__all__ = ["CircleEstimate", "fit_circle", "circle_fit_curve"]


def fit_circle(x: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
    """Hyper algebraic circle fit; returns (xc, yc, radius).

    Points are centred and scaled first (the normal matrix is then well
    conditioned at any physical scale). Falls back to Kasa's fit when the Hyper
    generalised eigenproblem has no admissible solution.
    """
    mx, my = x.mean(), y.mean()
    scale = np.sqrt(np.mean((x - mx) ** 2 + (y - my) ** 2)) or 1.0
    u, v = (x - mx) / scale, (y - my) / scale
    z = u**2 + v**2
    Z = np.column_stack([z, u, v, np.ones_like(u)])
    M = Z.T @ Z / u.size
    zbar = z.mean()
    N = np.array([[8 * zbar, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [2, 0, 0, 0]], dtype=float)
    best = None
    try:  # N is invertible for Hyper: M a = η N a  ⇔  N⁻¹M a = η a
        vals, vecs = np.linalg.eig(np.linalg.solve(N, M))
        for k in range(4):
            if not np.isfinite(vals[k]) or abs(vals[k].imag) > 1e-9 * (1 + abs(vals[k].real)):
                continue
            a = np.real(vecs[:, k])
            norm = a @ N @ a
            if norm <= 0 or abs(a[0]) < 1e-14 * np.linalg.norm(a):
                continue
            eta = (a @ M @ a) / norm
            if best is None or eta < best[0]:
                best = (eta, a)
    except (np.linalg.LinAlgError, ValueError):
        best = None
    if best is None:  # Kasa: z + B u + C v + D = 0, linear
        sol, *_ = np.linalg.lstsq(np.column_stack([u, v, np.ones_like(u)]), -z, rcond=None)
        a = np.array([1.0, *sol])
    else:
        a = best[1]
    A, B, C, D = a
    uc, vc = -B / (2 * A), -C / (2 * A)
    radius = np.sqrt(max(B**2 + C**2 - 4 * A * D, 0.0)) / (2 * abs(A))
    return mx + scale * uc, my + scale * vc, scale * radius


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


def _circle_bound(omega, omega_n, zeta, modal_constant, noise_std):
    """Cramér–Rao standard deviations of (ωn, ζ) for a mobility circle with offset."""
    try:
        with np.errstate(all="ignore"):
            return cramer_rao_sdof(omega, omega_n, zeta, modal_constant, 1, noise_std, offset=True)[:2]
    except (np.linalg.LinAlgError, ValueError, FloatingPointError):
        return np.array([np.nan, np.nan])


def circle_fit_curve(omega: np.ndarray, mobility: np.ndarray, noise_std: float) -> CircleEstimate:
    """Circle fit of the strongest mode in a band, on one channel of mobility.

    Parameters
    ----------
    omega : ndarray
        Lines of the band, rad/s.
    mobility : ndarray of complex
        Mobility on those lines (convert other kinds exactly first).
    noise_std : float
        σ of the complex noise on the mobility (for the Cramér–Rao floor of the
        standard errors).
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
    dof = xs.size - 3
    if dof > 0 and ok:
        s2 = float(np.sum(residual**2) / dof)
        try:
            cov = s2 * np.linalg.inv(jac.T @ jac)
            std_x, std_z = np.sqrt(max(cov[0, 0], 0)), np.sqrt(max(cov[1, 1], 0))
        except np.linalg.LinAlgError:
            pass
    if ok and np.isfinite(noise_std) and noise_std > 0:
        # the angle residuals ignore the error of the fitted centre, which moves every
        # angle together (observed scatter ≈ 1.5× that error): the Cramér–Rao bound of
        # the circle (mode + offset) on the same lines is the floor
        bound = _circle_bound(w, x_n * w_ref, zeta, 2 * zeta * x_n * w_ref * 2 * rho * np.exp(1j * psi), noise_std)
        if np.all(np.isfinite(bound)):
            std_x = max(std_x, bound[0] / w_ref) if np.isfinite(std_x) else bound[0] / w_ref
            std_z = max(std_z, bound[1]) if np.isfinite(std_z) else bound[1]
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
                          float(std_x * w_ref), float(std_z), spread, int(xs.size), tuple(flags))
