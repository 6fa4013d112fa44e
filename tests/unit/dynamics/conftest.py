"""Fixtures of the floating plant's tests: the bundled parameter sets."""

import pytest

from uvms_qp.dynamics import PlantParameters, plant_parameters


@pytest.fixture(scope="session")
def heavy() -> PlantParameters:
    """BlueROV2 Heavy (von Benzon et al. 2022) with the Alpha-5-like arm."""
    return plant_parameters("bluerov2_heavy_von_benzon_2022")


@pytest.fixture(scope="session")
def wu() -> PlantParameters:
    """Standard BlueROV2 (Wu 2018) with the Alpha-5-like arm."""
    return plant_parameters("bluerov2_wu_2018")
