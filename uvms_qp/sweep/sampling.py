"""Seeds and draws: every run of a sweep is decided by one integer, its seed.

Run ``i`` of a sweep with master seed ``s`` has the seed :func:`run_seed` ``(s, i)``, the first
64-bit word (less its top bit) of ``numpy.random.SeedSequence(s, spawn_key=(i,))``, the same
sequence as child ``i`` of ``SeedSequence(s).spawn(n)`` for any ``n > i``: adding runs to a
sweep leaves the earlier runs as they were.

From a run's seed, each variable draws from its own generator, seeded by the run's seed and the
variable's name (:func:`draw`): the value a run draws for ``current.speed`` does not change when
the file varies one more quantity. So a run is replayed from its seed and the sweep file alone.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from typing import Any

import numpy as np

from .spec import Variable

#: Seed of the sensors' noise generator of a run, drawn like a variable under this name.
SENSOR_SEED = "sensors.seed"


def run_seed(master: int, index: int) -> int:
    """The seed of run ``index`` of a sweep whose master seed is ``master`` (< 2**63)."""
    words = np.random.SeedSequence(master, spawn_key=(index,)).generate_state(1, np.uint64)
    return int(words[0]) >> 1


def generator(seed: int, name: str) -> np.random.Generator:
    """The generator of the variable ``name`` in the run of seed ``seed``."""
    return np.random.default_rng([seed, zlib.crc32(name.encode())])


def draw(variables: Sequence[Variable], seed: int) -> dict[str, Any]:
    """Every variable's value in the run of seed ``seed``: a number, a string or a list.

    A variable of ``count`` > 1 (a vector perturbation) draws a list of ``count`` values.
    """
    values: dict[str, Any] = {}
    for variable in variables:
        rng = generator(seed, variable.name)
        if variable.count == 1:
            values[variable.name] = variable.dist.sample(rng)
        else:
            values[variable.name] = [variable.dist.sample(rng) for _ in range(variable.count)]
    return values


def sensor_seed(seed: int) -> int:
    """The seed of the run's measurement noise (< 2**32)."""
    return int(generator(seed, SENSOR_SEED).integers(2**32))
