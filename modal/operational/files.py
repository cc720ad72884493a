"""Time files → operational results with the options of ``modal oma``, in one place.

:class:`OMAOptions` is the one vocabulary of the operational options: ``python -m modal oma``
(:mod:`modal.cli_oma`), a scene's ``[oma]`` section (:mod:`balancer.scene`) and ``modal batch --oma``
take the same names (the command line's ``--band`` sets ``band_hz``). Channels are named as on the
command line: a number counted from 1 in the file's order, or the channel's name; the Python
functions underneath (:func:`modal.oma`, :func:`modal.scale_by_mass_change`,
:func:`modal.merge_setups`) take 0-based indices.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

from ..errors import ParameterError
from ..results import IdentificationResult
from ..validate import one_of, positive

__all__ = ["OMAOptions", "oma_file", "oma_files", "scale_files", "channel_indices"]


@dataclass(frozen=True)
class OMAOptions:
    """What ``modal oma`` does with a record, as plain values (picklable, hashable into a settings key).

    Attributes
    ----------
    band_hz : (float, float), optional
        Band of interest, Hz (``--band FMIN FMAX``).
    method : str
        ``"ssi"`` (default), ``"plscf"``, ``"fdd"`` or ``"efdd"``.
    reference_channels : tuple of str, optional
        Reference (projection) channels: numbers counted from 1 or channel names; with several setups,
        the references every setup shares, in the same order.
    rotor_speed_hz : float, optional
        The machine's running speed, Hz.
    max_order : int, optional
        Highest model order of the sweep.
    """

    band_hz: tuple[float, float] | None = None
    method: str = "ssi"
    reference_channels: tuple[str, ...] | None = None
    rotor_speed_hz: float | None = None
    max_order: int | None = None

    def __post_init__(self) -> None:
        from .methods import OMA_METHODS

        one_of("method", self.method, OMA_METHODS)
        if self.band_hz is not None:
            try:
                low, high = (float(v) for v in self.band_hz)
            except (TypeError, ValueError):
                raise ParameterError(f"'band_hz' is {self.band_hz!r}; expected two frequencies (FMIN, FMAX) in Hz") \
                    from None
            if not (0 <= low < high < float("inf")):
                raise ParameterError(f"'band_hz' is ({low:g}, {high:g}); expected 0 <= FMIN < FMAX in Hz")
            object.__setattr__(self, "band_hz", (low, high))
        if self.reference_channels is not None:
            refs = self.reference_channels
            refs = (refs,) if isinstance(refs, (str, int)) else refs
            object.__setattr__(self, "reference_channels", tuple(str(r) for r in refs))

    @classmethod
    def from_args(cls, args: Any) -> "OMAOptions":
        """From an ``argparse`` namespace of ``modal oma`` / ``modal batch --oma`` (``--band`` → ``band_hz``)."""
        values = {f.name: getattr(args, f.name, None) for f in dataclasses.fields(cls) if f.name != "band_hz"}
        values["band_hz"] = getattr(args, "band", None)
        values["method"] = values["method"] or "ssi"
        return cls(**values)

    def settings(self) -> dict[str, Any]:
        """The options that were given (not None), JSON-ready."""
        return {f.name: list(v) if isinstance(v, tuple) else v
                for f in dataclasses.fields(self) if (v := getattr(self, f.name)) is not None}

    def settings_json(self) -> str:
        """Canonical JSON of :meth:`settings` with the toolkit version (what a result depends on)."""
        from .._version import __version__

        return json.dumps({"oma": self.settings(), "modalbal": __version__}, sort_keys=True)

    def settings_hash(self) -> str:
        """SHA-256 (hex) of :meth:`settings_json`."""
        return hashlib.sha256(self.settings_json().encode()).hexdigest()


def channel_indices(record, channels: Sequence[str | int], what: str) -> list[int]:
    """0-based indices of channels named as on the command line (numbers from 1, or names) in ``record``."""
    from ..errors import FormatError

    try:
        return [record.channel_index(c) for c in channels]
    except FormatError as exc:
        raise ParameterError(f"{what}: {exc}") from None


def _read(path):
    from ..io.timedata import read_time

    return read_time(path)


def _run(record, options: OMAOptions) -> IdentificationResult:
    from .identify import oma

    refs = None
    if options.reference_channels is not None:
        refs = channel_indices(record, options.reference_channels, "reference_channels")
    return oma(record, band_hz=options.band_hz, method=options.method, reference_channels=refs,
               rotor_speed_hz=options.rotor_speed_hz, max_order=options.max_order)


def oma_file(path: str | os.PathLike, options: OMAOptions = OMAOptions()) -> IdentificationResult:
    """Read a time file and identify its modes from the responses, as ``modal oma FILE`` does.

    Raises
    ------
    ModalError
        An unreadable file, bad options or a failed identification (the message names the file).
    """
    return _run(_read(path), options)


def oma_files(paths: Sequence[str | os.PathLike], options: OMAOptions = OMAOptions()):
    """Several setups (roving sensors with shared references), each identified, then merged.

    Returns
    -------
    (IdentificationResult, list of IdentificationResult)
        The merged result over all channels (the first setup's, then each further setup's non-reference
        channels) and each setup's own.
    """
    from .setups import merge_setups

    if len(paths) < 2:
        raise ParameterError(f"{len(paths)} file: setups to merge are 2 files or more")
    if not options.reference_channels:
        raise ParameterError(f"{len(paths)} files are setups to merge; give the references they share "
                             "(reference_channels, --reference-channels CH ...)")
    records = [_read(p) for p in paths]
    results = [_run(r, options) for r in records]
    refs = [channel_indices(r, options.reference_channels, f"{r.source}: reference_channels") for r in records]
    return merge_setups(results, refs), results


def scale_files(before: str | os.PathLike, after: str | os.PathLike, added_mass_kg: Mapping[str | int, float],
                options: OMAOptions = OMAOptions()):
    """Mass-normalised modes from a record and one with known masses added, as ``modal oma BEFORE
    --mass-change AFTER --added-mass-kg CH KG`` does.

    Parameters
    ----------
    before, after : path-like
        Time files of the same channels without and with the added masses.
    added_mass_kg : mapping
        ``{channel: kg}``, channels as on the command line (numbers from 1 or names).

    Returns
    -------
    (IdentificationResult, IdentificationResult)
        The scaled modes of ``before`` (k, c, m per channel) and the result of ``after``.
    """
    from .scaling import scale_by_mass_change

    first, second = _read(before), _read(after)
    if not added_mass_kg:
        raise ParameterError(f"{first.source}: no added mass given; expected added_mass_kg {{channel: kg}} "
                             "(--added-mass-kg CH KG)")
    where = channel_indices(first, list(added_mass_kg), "added_mass_kg")
    masses = {}
    for index, (key, kg) in zip(where, added_mass_kg.items()):
        masses[index] = masses.get(index, 0.0) + float(positive(f"added_mass_kg at channel {key}", kg)[0])
    result_before, result_after = _run(first, options), _run(second, options)
    return scale_by_mass_change(result_before, result_after, masses), result_after
