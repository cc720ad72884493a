"""The papers' slider-cranks as fixtures for the compressor tests."""
import pytest
from support.crank import seed000_mechanism, seed004_mechanism

from balancer.compressor.crank import SliderCrank


@pytest.fixture
def seed000() -> SliderCrank:
    return seed000_mechanism()


@pytest.fixture
def seed004() -> SliderCrank:
    return seed004_mechanism()
