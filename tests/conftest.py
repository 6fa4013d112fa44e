"""Shared pytest configuration and fixtures: hypothesis profiles, headless plotting, models.

Test modules build no model at import time: they take the ``models`` fixture (every bundled
model by name, loaded on first use) or ``rov`` (the BlueROV2 Heavy with the Alpha 5 arm). A
:class:`~uvms_qp.model.Model` is read-only after construction (its arrays are not writeable, each
state has its own Pinocchio data), so one instance per name serves the whole session.
"""

import os

import matplotlib
import pytest
from hypothesis import HealthCheck, settings

from uvms_qp.model import Model, load_model

matplotlib.use("Agg")

settings.register_profile(
    "ci",
    derandomize=True,
    deadline=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("dev", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


class BundledModels(dict[str, Model]):
    """Bundled models by name, each loaded on first use."""

    def __missing__(self, name: str) -> Model:
        model = self[name] = load_model(name)
        return model


@pytest.fixture(scope="session")
def models() -> BundledModels:
    """Every bundled model by name (``models["wang_9dof"]``), shared by the session."""
    return BundledModels()


@pytest.fixture(scope="session")
def rov(models: BundledModels) -> Model:
    """The BlueROV2 Heavy with the Reach Alpha 5 arm (``bluerov2_heavy_alpha5``)."""
    return models["bluerov2_heavy_alpha5"]
