"""Whether the data behave as the FRF's declared kind (receptance, mobility or accelerance).

A wrong kind is not an error the fit can see: every kind gives the same poles, and the modal
constants, k, c and m come out scaled by powers of the natural frequency (an accelerance read as a
receptance gives masses ω_r² times too small). Two properties of the data tell the kinds apart:

* **The skeleton between and beyond the modes.** Away from the resonances an FRF follows the mass
  lines of the modes below and the stiffness lines of the modes above. Across several modes its
  geometric-mean level (Skudrzyk's skeleton, the mobility of the infinite structure) falls in
  receptance like ω^-2 (mass-like) to ω^-1 (plates, rods), ω^-1.5 for beams; a receptance level that
  does not fall across the modes is what an accelerance or a mobility looks like in receptance units.
  The slope is measured on the medians of log|H| between neighbouring modes and above the last one
  (each at least 10 % or five half-power widths from the resonances).
* **Dissipation at a driving point.** A passive structure absorbs the power a force puts in: the real
  part of a driving-point mobility is positive on every line. Under the declared kind the data are
  turned into a mobility; when that mobility gives power back on (nearly) every line while it absorbs
  power read as another kind, the data look like that kind (or the sign of a channel is reversed).

Calibrated on the shipped real beam (five gaps, receptance-unit skeleton slopes -2.2 to -1.1 read as
the accelerance it is), the demo and plate FRFs (-1.4, -1.2) and the synthetic cases of the tests:
a receptance-unit slope above :data:`SKELETON_LIMIT` over at least :data:`MIN_SKELETON_POINTS`
points, or a dissipating fraction under :data:`ACTIVE_FRACTION` where another kind dissipates on
more than :data:`PASSIVE_FRACTION`, is reported.
"""
from __future__ import annotations

import numpy as np

from .frf import FRF_KINDS, KIND_POWER

__all__ = ["skeleton_slope", "dissipating_fraction", "kind_contradiction", "SKELETON_LIMIT"]

#: receptance-unit skeleton slope above which the data do not fall across the modes as a receptance must
SKELETON_LIMIT = -0.25
#: receptance-unit skeleton slope below which no kind is taken for the data (a transfer FRF falls faster
#: than a mass above its modes when its modal constants cancel)
LOWEST_SKELETON = -2.75
#: the skeleton slope of a typical structure in receptance units (between beams, -1.5, and masses, -2):
#: the kind whose units bring the measured slope nearest to it is the kind the data look like
TYPICAL_SKELETON = -1.75
#: at least this many skeleton points (gaps between modes, and above the last mode)
MIN_SKELETON_POINTS = 3
#: a driving point's mobility dissipates on more than this fraction of its weight: the kind fits
PASSIVE_FRACTION = 0.9
#: ... and on less than this fraction: the kind does not
ACTIVE_FRACTION = 0.1
#: lines of a skeleton point keep at least this relative distance, and five half-power widths, from a mode
_GAP = 0.1


def skeleton_slope(frf, natural_frequency_hz, damping_ratio) -> tuple[float, int] | None:
    """Slope of log|H| over log f between the modes, in receptance units, and the number of points.

    Parameters
    ----------
    frf : FRF
    natural_frequency_hz, damping_ratio : array_like, one per mode

    Returns
    -------
    (float, int) or None
        The least-squares slope through the medians of log|H| (RMS over channels, relative to the
        largest |H|) of each gap between neighbouring modes and above the last mode, minus the kind's
        power; None with fewer than two points.
    """
    f = frf.frequency_hz
    magnitude = np.abs(frf.channels)
    magnitude = np.sqrt(np.mean((magnitude / max(np.max(magnitude), np.finfo(float).tiny)) ** 2, axis=0))
    order = np.argsort(natural_frequency_hz)
    fn = np.asarray(natural_frequency_hz, float)[order]
    zeta = np.nan_to_num(np.asarray(damping_ratio, float)[order], nan=0.0).clip(0.0, None)
    away = np.maximum(_GAP, 5 * zeta)
    lows = fn * (1 + away)
    highs = np.append(fn[1:] * (1 - away[1:]), f[-1])
    x, y = [], []
    for low, high in zip(lows, highs):
        lines = (f >= low) & (f <= high) & (f > 0) & (magnitude > 0)
        if high > low and np.count_nonzero(lines) >= 3:
            x.append(0.5 * np.log(low * high))
            y.append(np.median(np.log(magnitude[lines])))
    if len(x) < 2:
        return None
    return float(np.polyfit(x, y, 1)[0]) - KIND_POWER[frf.kind], len(x)


def dissipating_fraction(frf, driving, power: int) -> float | None:
    """Share of a driving point's mobility, read as kind ``power``, whose real part is positive.

    ``sum |H| max(cos φ, 0) / sum |H| |cos φ|`` over the lines above 0 Hz of the driving-point channels,
    φ the phase of the mobility: the weight |H| is the same whatever the kind, and lines whose mobility is
    nearly imaginary (far from the resonances, where noise decides the sign of its real part) count
    little. None without a driving point.
    """
    driving = np.asarray(driving, bool)
    if not driving.any():
        return None
    f = frf.frequency_hz
    lines = f > 0
    response = frf.channels[driving][:, lines]
    cosine = np.cos(np.angle(response) - (power - 1) * np.pi / 2)  # the phase of H / (i omega)**(p - 1)
    weight = np.abs(response)
    weight = weight / max(np.max(weight), np.finfo(float).tiny)  # sums of values near overflow stay finite
    total = np.sum(weight * np.abs(cosine))
    return float(np.sum(weight * np.maximum(cosine, 0.0)) / total) if total > 0 else None


def kind_contradiction(frf, modes, driving=None) -> str | None:
    """Why the data contradict the FRF's declared kind, naming the kind they look like; None when they don't.

    Parameters
    ----------
    frf : FRF
    modes : sequence of ModeResult
        The identified modes (their natural frequencies and damping place the skeleton points).
    driving : array_like of bool, optional
        Driving-point channels (known or declared); their dissipation is checked too, and names the kind
        among those the skeleton allows.
    """
    declared = KIND_POWER[frf.kind]
    name = {power: kind for kind, power in KIND_POWER.items() if kind in FRF_KINDS}
    share = {p: dissipating_fraction(frf, driving, p) for p in name} if driving is not None else {}
    passive = [p for p, value in share.items() if value is not None and value > PASSIVE_FRACTION]
    reasons, looks = [], None
    skeleton = skeleton_slope(frf, [m.natural_frequency_hz for m in modes],
                              [m.damping_ratio for m in modes]) if len(modes) else None
    if skeleton is not None and skeleton[1] >= MIN_SKELETON_POINTS and skeleton[0] > SKELETON_LIMIT:
        slope = skeleton[0] + declared  # in the data's own units
        plausible = [p for p in name if slope - p <= SKELETON_LIMIT]
        dissipating = [p for p in plausible if p in passive]
        looks = dissipating[0] if dissipating else int(np.clip(round(slope - TYPICAL_SKELETON), 0, 2))
        if looks == declared:
            looks = None
        else:
            reasons.append(f"between the modes its level goes as f^{slope:+.2f}, where a {frf.kind}'s goes as "
                           f"f^{declared - 2} to f^{declared - 1}")
    if share and share[declared] is not None and share[declared] < ACTIVE_FRACTION and passive:
        best = max(passive, key=lambda p: share[p])
        # a reversed sign turns a receptance's dissipation into an accelerance's and back: where the skeleton
        # says the data cannot be that other kind, the sign is wrong, not the kind (non_positive_constant)
        measured = skeleton is not None and skeleton[1] >= MIN_SKELETON_POINTS
        sign_only = measured and not LOWEST_SKELETON <= skeleton[0] + declared - best <= SKELETON_LIMIT
        if looks in (None, best) and not sign_only:
            looks = best
            reasons.append(f"read as {frf.kind} its driving point would give power back on "
                           f"{100 * (1 - share[declared]):.0f} % of its weight, read as {name[best]} it absorbs "
                           f"power on {100 * share[best]:.0f} %" + (" (or the sign of the force or the response is "
                                                                  "reversed)" if abs(best - declared) == 2 else ""))
    elif looks is not None and looks in passive:
        reasons.append(f"its driving point absorbs power on {100 * share[looks]:.0f} % of its weight read as "
                       f"{name[looks]}, on {100 * share[declared]:.0f} % as {frf.kind}")
    if looks is None or not reasons:
        return None
    return (f"the data look like {name[looks]}, not {frf.kind} as declared: " + "; ".join(reasons)
            + f". Masses and stiffnesses would be off by powers of the natural frequency: declare the kind "
              f"(--kind {name[looks]}, kind = \"{name[looks]}\" under [frf], FRF(..., kind=\"{name[looks]}\")) if "
              "that is what was measured")
