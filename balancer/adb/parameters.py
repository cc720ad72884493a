"""Physical parameters of a planar Jeffcott rotor carrying an automatic ball balancer.

Conventions (SI inside): masses in kg, lengths in m, stiffness in N/m, support damping
in N s/m, ball drag in N m s (torque per unit relative angular speed of a ball).

Nondimensional groups follow the research note (``adb.md`` section 1d): time scaled by
``omega_n = sqrt(k / (M + n m))`` and lengths by the race radius ``R``.  Rodrigues et al.
scale by ``sqrt(k / M)`` instead; this library does not.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, Sequence

import numpy as np

from modal.errors import ParameterError

from .._checks import count, parameter

__all__ = [
    "ADBParameters",
    "ParameterStd",
    "ParameterBatch",
    "identified_std",
    "identified_correlation",
    "STD_ORDER",
]

_FIELD_NAMES = ("M", "m", "n", "R", "e", "k", "c", "D")
_FIELD_UNITS = {"M": "kg", "m": "kg", "n": "", "R": "m", "e": "m", "k": "N/m", "c": "N s/m", "D": "N m s"}
_FIELD_MEANING = {
    "M": "rotor mass",
    "m": "mass of one ball",
    "n": "ball count",
    "R": "race radius",
    "e": "eccentricity of the rotor mass centre",
    "k": "support stiffness",
    "c": "support damping",
    "D": "ball drag coefficient",
}


#: how an error names each field: ``"k (support stiffness)"``
_LABELS = {name: f"{name} ({meaning})" for name, meaning in _FIELD_MEANING.items()}


@dataclass(frozen=True, slots=True)
class ADBParameters:
    """Jeffcott rotor with an automatic ball balancer (Chung & Ro model), SI units.

    Parameters
    ----------
    M : float
        Rotor (disk) mass without the balls, kg (> 0).
    m : float
        Mass of one ball, kg (> 0).
    n : int
        Number of balls (>= 1).
    R : float
        Race radius (distance from the race centre to a ball centre), m (> 0).
    e : float
        Distance of the rotor mass centre from the race centre, m (>= 0).
    k : float
        Isotropic support stiffness, N/m (> 0).
    c : float
        Viscous support damping, N s/m (>= 0).
    D : float
        Viscous drag on a ball's motion relative to the race, as a torque per unit
        relative angular speed, N m s (>= 0).

    Raises
    ------
    modal.errors.ParameterError
        If a value is not finite, a mass, radius or stiffness is not positive, a damping or
        the eccentricity is negative, or ``n`` is not an integer >= 1.
    """

    M: float
    m: float
    n: int
    R: float
    e: float
    k: float
    c: float
    D: float

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        return {"M": "kg", "m": "kg", "n": "1", "R": "m", "e": "m", "k": "N/m", "c": "N s/m", "D": "N m s"}

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for name in ("M", "m", "R", "k"):
            set_(self, name, parameter(_LABELS[name], getattr(self, name), _FIELD_UNITS[name], positive=True))
        for name in ("e", "c", "D"):
            set_(self, name, parameter(_LABELS[name], getattr(self, name), _FIELD_UNITS[name], positive=False))
        set_(self, "n", count(_LABELS["n"], self.n))

    # ----------------------------------------------------------------- derived
    @property
    def total_mass_kg(self) -> float:
        """Rotor plus balls, ``M + n m`` (kg)."""
        return self.M + self.n * self.m

    @property
    def natural_frequency_rad_s(self) -> float:
        """Natural frequency of the rotor with balls, ``sqrt(k / (M + n m))`` (rad/s)."""
        return math.sqrt(self.k / self.total_mass_kg)

    @property
    def mass_ratio(self) -> float:
        """Ball mass ratio ``mu = m / (M + n m)`` (-)."""
        return self.m / self.total_mass_kg

    @property
    def eccentricity_ratio(self) -> float:
        """Nondimensional unbalance ``M e / ((M + n m) R)`` (-)."""
        return self.M * self.e / (self.total_mass_kg * self.R)

    @property
    def damping_ratio(self) -> float:
        """Support damping ratio ``zeta = c / (2 sqrt(k (M + n m)))`` (-)."""
        return self.c / (2.0 * math.sqrt(self.k * self.total_mass_kg))

    @property
    def drag_ratio(self) -> float:
        """Ball drag ratio ``beta = D / (m R^2 omega_n)`` (-)."""
        return self.D / (self.m * self.R**2 * self.natural_frequency_rad_s)

    @property
    def unbalance_ratio(self) -> float:
        """``a = M e / (m R)``: the unbalance in units of one ball's; balancing needs ``a <= n`` (-)."""
        return self.M * self.e / (self.m * self.R)

    @property
    def unbalance_kg_m(self) -> float:
        """Rotor unbalance ``M e`` (kg m)."""
        return self.M * self.e

    @property
    def ball_time_constant_s(self) -> float:
        """Relaxation time of a ball's slip against the drag alone, ``m R^2 / D`` (s); inf if D = 0."""
        return math.inf if self.D == 0.0 else self.m * self.R**2 / self.D

    @property
    def can_balance(self) -> bool:
        """Whether the balls can cancel the unbalance at all: ``n m R >= M e``."""
        return self.n * self.m * self.R >= self.M * self.e

    def require_balancing(self) -> None:
        """Raise :class:`~modal.errors.ParameterError` unless ``n m R >= M e``.

        For one ball the balanced state exists only if ``m R == M e`` exactly; that case is
        rejected here as well unless it holds to rounding.
        """
        capacity = self.n * self.m * self.R
        if capacity < self.M * self.e:
            raise ParameterError(
                f"n*m*R = {capacity:.6g} kg m is less than M*e = {self.M * self.e:.6g} kg m: "
                f"the balls cannot cancel the unbalance; expected n*m*R >= M*e "
                f"(more balls, heavier balls or a larger race radius)"
            )
        if self.n == 1 and not math.isclose(capacity, self.M * self.e, rel_tol=1e-12):
            raise ParameterError(
                f"n = 1: one ball balances only if m*R == M*e, got m*R = {capacity:.6g} kg m "
                f"and M*e = {self.M * self.e:.6g} kg m; expected n >= 2"
            )

    def replace(self, **changes: Any) -> "ADBParameters":
        """Return a copy with some fields changed (validated again)."""
        values = {name: getattr(self, name) for name in _FIELD_NAMES}
        unknown = set(changes) - set(values)
        if unknown:
            raise ParameterError(f"unknown ADBParameters field(s) {sorted(unknown)}; expected one of {_FIELD_NAMES}")
        values.update(changes)
        return ADBParameters(**values)

    # ------------------------------------------------------------ constructors
    @classmethod
    def from_nondimensional(
        cls,
        *,
        n: int,
        mass_ratio: float,
        unbalance_ratio: float,
        damping_ratio: float,
        drag_ratio: float,
        M: float = 1.0,
        R: float = 0.05,
        k: float = 1.0e4,
    ) -> "ADBParameters":
        """Build SI parameters from the nondimensional groups (``mu, a, zeta, beta``).

        Parameters
        ----------
        n : int
            Ball count.
        mass_ratio : float
            ``mu = m / (M + n m)``, must satisfy ``0 < n mu < 1``.
        unbalance_ratio : float
            ``a = M e / (m R)``.
        damping_ratio : float
            ``zeta``.
        drag_ratio : float
            ``beta``.
        M, R, k : float
            Scales: rotor mass (kg), race radius (m), stiffness (N/m); the dynamics in
            nondimensional form do not depend on them.
        """
        n = count(_LABELS["n"], n)
        mu = parameter(_LABELS["m"], mass_ratio, _FIELD_UNITS["m"], positive=True)
        if not n * mu < 1.0:
            raise ParameterError(f"mass_ratio = {mu!r} with n = {n}: expected n * mass_ratio < 1")
        m = mu * M / (1.0 - n * mu)
        total = M + n * m
        omega_n = math.sqrt(k / total)
        return cls(
            M=M,
            m=m,
            n=n,
            R=R,
            e=unbalance_ratio * m * R / M,
            k=k,
            c=2.0 * damping_ratio * math.sqrt(k * total),
            D=drag_ratio * m * R**2 * omega_n,
        )

    @classmethod
    def from_identified(
        cls,
        mode: Any,
        *,
        m: float,
        n: int,
        R: float,
        e: float,
        D: float,
        channel: int | None = 0,
        mass_includes_balls: bool = False,
    ) -> "ADBParameters":
        """Build parameters from an identified mode (stiffness, damping and mass).

        Duck-typed on the identification result's attribute names ``stiffness_n_per_m``,
        ``damping_n_s_per_m`` and ``mass_kg`` (floats or arrays over channels).

        Parameters
        ----------
        mode : object
            Identified mode with ``stiffness_n_per_m`` (N/m), ``damping_n_s_per_m`` (N s/m)
            and ``mass_kg`` (kg).
        m, n, R, e, D : float, int, float, float, float
            Ball mass (kg), ball count, race radius (m), eccentricity (m), ball drag (N m s).
        channel : int or None
            Which channel to use when the fields are arrays; ignored for scalars.
        mass_includes_balls : bool
            True if the modal test was made with the balls in the race, so that the
            identified mass is ``M + n m``; the rotor mass is then ``mass_kg - n m``.

        Raises
        ------
        modal.errors.ParameterError
            If a field is missing, not finite or out of range.
        """
        k = _pick(mode, "stiffness_n_per_m", channel)
        c = _pick(mode, "damping_n_s_per_m", channel)
        mass = _pick(mode, "mass_kg", channel)
        n = count(_LABELS["n"], n)
        rotor_mass = mass - n * float(m) if mass_includes_balls else mass
        if mass_includes_balls and not rotor_mass > 0.0:
            raise ParameterError(
                f"mass_kg = {mass!r} with mass_includes_balls=True leaves a rotor mass M = {rotor_mass!r} kg "
                f"after removing n*m = {n * float(m)!r} kg; expected M > 0"
            )
        return cls(M=rotor_mass, m=m, n=n, R=R, e=e, k=k, c=c, D=D)


def _pick(obj: Any, name: str, channel: int | None) -> float:
    if not hasattr(obj, name):
        raise ParameterError(f"identified mode has no attribute {name!r}; expected an identification result")
    value = np.asarray(getattr(obj, name), dtype=float)
    if value.ndim > 0:
        if channel is None:
            if value.size != 1:
                raise ParameterError(
                    f"{name} has {value.size} channels; pass channel=<index> to choose one"
                )
            value = value.reshape(())
        else:
            try:
                value = value.reshape(-1)[channel]
            except IndexError as exc:
                raise ParameterError(
                    f"channel = {channel} is out of range for {name} with {value.size} channels"
                ) from exc
    number = float(value)
    if not math.isfinite(number):
        raise ParameterError(f"identified {name} = {number!r}: expected a finite number")
    return number


#: order of the rows and columns of :attr:`ParameterStd.correlation`
STD_ORDER = ("k", "c", "M")


@dataclass(frozen=True, slots=True)
class ParameterStd:
    """Standard errors of the identified rotor parameters (0 where unknown), and their correlation.

    Attributes
    ----------
    k : float
        Standard error of the support stiffness, N/m.
    c : float
        Standard error of the support damping, N s/m.
    M : float
        Standard error of the rotor mass, kg.
    correlation : ndarray, shape (3, 3), or None
        Correlation of the errors of (k, c, M) (:data:`STD_ORDER`); None: independent.
        k, c and M identified from one mode share ωn, ζ and the modal constant and are
        strongly correlated (k and M through 1/|A|: nearly +1).
    """

    k: float = 0.0
    c: float = 0.0
    M: float = 0.0
    correlation: np.ndarray | None = None

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        return {"k": "N/m", "c": "N s/m", "M": "kg", "correlation": "1"}

    def __post_init__(self) -> None:
        for name in STD_ORDER:
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value >= 0.0):
                raise ParameterError(f"standard error of {name} = {value!r}: expected a finite number >= 0")
            object.__setattr__(self, name, value)
        if self.correlation is not None:
            r = np.array(self.correlation, dtype=float)
            ok = (r.shape == (3, 3) and np.all(np.isfinite(r)) and np.allclose(r, r.T, atol=1e-9)
                  and np.allclose(np.diag(r), 1.0, atol=1e-9) and np.all(np.abs(r) <= 1.0 + 1e-9))
            if not ok:
                raise ParameterError(f"correlation of (k, c, M) = {self.correlation!r}: expected a symmetric "
                                     "3 x 3 matrix with unit diagonal and entries in [-1, 1]")
            r.flags.writeable = False
            object.__setattr__(self, "correlation", r)

    @property
    def covariance(self) -> np.ndarray:
        """Covariance of (k, c, M), shape (3, 3): N/m, N s/m, kg (independent without a correlation)."""
        sd = np.array([self.k, self.c, self.M])
        r = np.eye(3) if self.correlation is None else self.correlation
        return sd[:, None] * r * sd[None, :]


def identified_std(mode: Any, channel: int | None = 0) -> ParameterStd:
    """Standard errors of k, c, M from an identification result's ``std`` attribute, with their
    correlation from its ``kcm_correlation`` (when it has one).

    Parameters
    ----------
    mode : object
        Identified mode; its ``std`` holds ``stiffness_n_per_m``, ``damping_n_s_per_m`` and
        ``mass_kg`` standard errors.  Missing fields count as 0.
    channel : int or None
        Channel index for array-valued fields.

    Returns
    -------
    ParameterStd
        Standard errors in N/m, N s/m and kg, and the correlation of (k, c, M).
    """
    std = getattr(mode, "std", None)
    if std is None:
        return ParameterStd()
    values = {}
    for key, attr in (("k", "stiffness_n_per_m"), ("c", "damping_n_s_per_m"), ("M", "mass_kg")):
        values[key] = _pick(std, attr, channel) if hasattr(std, attr) else 0.0
    return ParameterStd(**values, correlation=identified_correlation(mode, channel))


def identified_correlation(mode: Any, channel: int | None = 0) -> np.ndarray | None:
    """Correlation (3, 3) of the errors of (k, c, M) of an identified mode's channel, or None.

    Read from the mode's ``kcm_correlation`` (rows k, c, m; shape (3, 3) or one per
    channel); None when it has none or it is not finite (a transfer channel).

    Parameters
    ----------
    mode : ModeResult
        An identified mode (``modal.identify(...).modes[i]``).
    channel : int or None
        Channel (0-based) of a multi-channel result; None for a single-channel one.
    """
    r = getattr(mode, "kcm_correlation", None)
    if r is None:
        return None
    r = np.asarray(r, dtype=float)
    if r.ndim == 3:
        if channel is None:
            if r.shape[0] != 1:
                raise ParameterError(f"kcm_correlation has {r.shape[0]} channels; pass channel=<index> to choose one")
            channel = 0
        r = r[channel]
    return r if r.shape == (3, 3) and np.all(np.isfinite(r)) else None


@dataclass(frozen=True, slots=True)
class ParameterBatch:
    """A batch of parameter sets with a common ball count, as arrays of shape ``(B,)``.

    Used internally to evaluate the equations of motion for many sets at once.

    Attributes
    ----------
    M, m, R, e, k, c, D : ndarray, shape (B,)
        As in :class:`ADBParameters` (kg, kg, m, m, N/m, N s/m, N m s).
    n : int
        Common ball count.
    """

    M: np.ndarray
    m: np.ndarray
    R: np.ndarray
    e: np.ndarray
    k: np.ndarray
    c: np.ndarray
    D: np.ndarray
    n: int

    @classmethod
    def from_parameters(cls, params: "ADBParameters | Sequence[ADBParameters]") -> "ParameterBatch":
        """Stack one parameter set or a sequence of them (all with the same ``n``)."""
        members = [params] if isinstance(params, ADBParameters) else list(params)
        if not members:
            raise ParameterError("params: empty sequence; expected at least one ADBParameters")
        for item in members:
            if not isinstance(item, ADBParameters):
                raise ParameterError(f"params: got {type(item).__name__}; expected ADBParameters")
        counts = {item.n for item in members}
        if len(counts) != 1:
            raise ParameterError(
                f"ball counts {sorted(counts)} differ within the batch; expected one n per batch"
            )
        arrays = {
            name: np.array([getattr(item, name) for item in members], dtype=float)
            for name in ("M", "m", "R", "e", "k", "c", "D")
        }
        return cls(n=members[0].n, **arrays)

    @property
    def size(self) -> int:
        """Number of parameter sets."""
        return int(self.M.shape[0])

    @property
    def total_mass_kg(self) -> np.ndarray:
        """``M + n m`` per member (kg)."""
        return self.M + self.n * self.m

    @property
    def natural_frequency_rad_s(self) -> np.ndarray:
        """``sqrt(k / (M + n m))`` per member (rad/s)."""
        return np.sqrt(self.k / self.total_mass_kg)

    def member(self, index: int) -> ADBParameters:
        """The parameter set at ``index``."""
        return ADBParameters(
            M=self.M[index], m=self.m[index], n=self.n, R=self.R[index], e=self.e[index],
            k=self.k[index], c=self.c[index], D=self.D[index],
        )

    def reshaped(self, shape: tuple[int, ...]) -> "ParameterBatch":
        """Copy with every array reshaped (for broadcasting against extra state axes)."""
        return ParameterBatch(
            n=self.n, **{f.name: getattr(self, f.name).reshape(shape) for f in fields(self) if f.name != "n"}
        )
