"""modal.errors.kept_warnings: the toolkit's warnings kept for the results that must carry them, and shown too."""
import warnings

import pytest

from modal.errors import ModalWarning, QualityWarning, kept_warnings


def _warn_twice_and_once_more():
    warnings.warn("hits disagree", QualityWarning)
    warnings.warn("hits disagree", QualityWarning)
    warnings.warn("a library's own", DeprecationWarning)
    warnings.warn("rotor frequency", ModalWarning)


def test_kept_whatever_is_shown_and_shown_as_the_filters_say():
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        with kept_warnings() as kept:
            _warn_twice_and_once_more()
    # kept: the toolkit's, each once, in order; shown: each distinct warning once, the others' too
    assert kept == ["hits disagree", "rotor frequency"]
    assert [(w.category, str(w.message)) for w in shown] == [
        (QualityWarning, "hits disagree"), (DeprecationWarning, "a library's own"), (ModalWarning, "rotor frequency")]
    # a caller that silences warnings still gets them kept
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("ignore")
        with kept_warnings() as kept:
            _warn_twice_and_once_more()
    assert kept == ["hits disagree", "rotor frequency"] and shown == []


def test_an_error_filter_still_raises_and_a_failing_block_still_shows_its_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error", QualityWarning)
        with pytest.raises(QualityWarning, match="hits disagree"):
            with kept_warnings():
                warnings.warn("hits disagree", QualityWarning)
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        with pytest.raises(ValueError), kept_warnings() as kept:
            warnings.warn("rotor frequency", ModalWarning)
            raise ValueError("the stage failed")
    assert kept == ["rotor frequency"] and [str(w.message) for w in shown] == ["rotor frequency"]
