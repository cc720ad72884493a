"""Errors and warnings shared by the whole toolkit (``modal`` and ``balancer``).

Every exception subclasses a built-in as well (python-control's pattern), so
callers may catch either ``ModalError`` or the familiar ``ValueError``.
Messages name the file, the field and what was expected.
"""
from __future__ import annotations

import sys
import warnings
from contextlib import contextmanager
from typing import Iterator

__all__ = [
    "ModalError",
    "FRFValidationError",
    "FormatError",
    "IdentificationError",
    "ParameterError",
    "ArchiveError",
    "SceneError",
    "PlotError",
    "ModalWarning",
    "ResolutionWarning",
    "QualityWarning",
    "warn",
    "warn_caller",
    "kept_warnings",
]


class ModalError(Exception):
    """Base class of every error raised by this toolkit."""


class FRFValidationError(ModalError, ValueError):
    """An FRF's frequency axis or response is not acceptable."""


class FormatError(ModalError, ValueError):
    """A file cannot be read: names the file, the field or line, and what was expected."""


class IdentificationError(ModalError, RuntimeError):
    """Identification cannot produce an estimate (for example: no mode in the band)."""


class ParameterError(ModalError, ValueError):
    """A physical or numerical parameter is out of its valid range."""


class ArchiveError(ModalError, ValueError):
    """An HDF5 result archive is missing, damaged or of an unknown schema version."""


class SceneError(ModalError, ValueError):
    """A scene file is invalid: names the file, the key and what was expected."""


class PlotError(ModalError, RuntimeError):
    """A figure could not be drawn or written: names the stage (or figure) and the cause."""


class ModalWarning(UserWarning):
    """Base class of the toolkit's warnings."""


class ResolutionWarning(ModalWarning):
    """The frequency resolution is too coarse for an estimate to be sound."""


class QualityWarning(ModalWarning):
    """An estimate was produced but fails a quality check (flagged in the result)."""


def warn(message: str, category: type[Warning] = ModalWarning, stacklevel: int = 3) -> None:
    """Issue a toolkit warning pointing at the caller's caller."""
    warnings.warn(message, category, stacklevel=stacklevel)


def warn_caller(message: str, category: type[Warning] = ModalWarning) -> None:
    """Issue a toolkit warning pointing at the first caller outside the ``modal`` package: the line
    that called the toolkit, however deep inside it the warning is raised."""
    frame, level = sys._getframe(1), 2
    while frame is not None and frame.f_globals.get("__name__", "").partition(".")[0] == "modal":
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)


@contextmanager
def kept_warnings() -> Iterator[list[str]]:
    """Keep the toolkit's warnings given inside the block: the list yielded holds their texts (each once, in
    order) when the block ends, whatever the filters in force show.

    The warnings are then shown as those filters say (an "error" filter raises, at the end of the block); other
    warnings pass through as they would without it. For results that must carry what their data was warned of
    (archives, JSON documents) as well as show it.
    """
    kept: list[str] = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ModalWarning)
            yield kept
    finally:  # shown even when the block fails: they may say why
        kept.extend(dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, ModalWarning)))
        shown = set()
        for w in caught:
            if (w.category, str(w.message)) not in shown:
                shown.add((w.category, str(w.message)))
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
