"""The shape of a refusal of bad input: one line naming the file, the fragments asked for and what was
expected, with no warning on the way."""
from __future__ import annotations

import warnings

import pytest

from modal.errors import FormatError


def assert_refused(path, read, *fragments) -> str:
    """``read(path)`` refuses ``path`` with one :class:`FormatError` line naming the file, each fragment and what
    was expected; no warning is raised on the way (a NumPy RuntimeWarning is a failure too). Returns the
    message."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(FormatError) as info:
            read(path)
    msg = str(info.value)
    assert "\n" not in msg and str(path) in msg and "expected" in msg, msg
    for fragment in fragments:
        assert fragment in msg, f"{fragment!r} not in {msg!r}"
    return msg
