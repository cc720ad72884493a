"""Seed 002's belt stages as fixtures for the drive tests."""
import pytest
from support.drive import seed002_stage_a, seed002_stage_b


@pytest.fixture
def stage_a():
    return seed002_stage_a()


@pytest.fixture
def stage_b():
    return seed002_stage_b()
