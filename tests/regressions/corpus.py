"""Save and load lexicographic problems of the regression corpus (one ``.npz`` file each).

A problem that made a test fail is saved with :func:`save_problem` (from a test, a debugging
session or the soak benchmark) and is then replayed on every installed back-end by
``tests/regressions/test_corpus.py``. File layout (all float64 unless stated):

* ``n`` (int), ``lower``, ``upper``, ``W``: size, hard box, metric;
* ``hard_A``, ``hard_lo``, ``hard_hi``: hard rows;
* ``level_count`` (int) and, per level ``k``, ``A_k``, ``lo_k``, ``hi_k``, ``w_k``;
* ``note`` (str): what failed, where, with which back-end.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from uvms_qp.hqp import Problem

HERE = Path(__file__).resolve().parent


def save_problem(problem: Problem, name: str, note: str, directory: Path | None = None) -> Path:
    """Write ``problem`` to ``<directory>/<name>.npz`` (copies of every array) and return the path.

    Args:
        problem: The problem that failed.
        name: File stem, letters, digits, ``_`` and ``-`` only.
        note: What failed (test, back-end, symptom).
        directory: Target folder (default: this corpus).
    """
    if not re.fullmatch(r"[A-Za-z0-9_-]+", name):
        raise ValueError(f"name: use letters, digits, '_' and '-' only, got {name!r}")
    hard = problem.hard
    arrays: dict[str, np.ndarray] = {
        "n": np.array(problem.n), "lower": problem.lower, "upper": problem.upper,
        "W": problem.W, "hard_A": hard.A, "hard_lo": hard.lower, "hard_hi": hard.upper,
        "level_count": np.array(len(problem.sizes)), "note": np.array(note),
    }
    for k, level in enumerate(problem.levels):
        arrays[f"A_{k}"], arrays[f"lo_{k}"] = level.A, level.lower
        arrays[f"hi_{k}"], arrays[f"w_{k}"] = level.upper, level.weights
    path = (directory or HERE) / f"{name}.npz"
    np.savez_compressed(path, **{k: np.array(v, copy=True) for k, v in arrays.items()})
    return path


def load_problem(path: Path) -> tuple[Problem, str]:
    """Read a problem saved by :func:`save_problem`; returns it with its note."""
    with np.load(path, allow_pickle=False) as data:
        n = int(data["n"])
        count = int(data["level_count"])
        parts = [(data["hard_A"], data["hard_lo"], data["hard_hi"])]
        parts += [(data[f"A_{k}"], data[f"lo_{k}"], data[f"hi_{k}"]) for k in range(count)]
        problem = Problem(n, parts[0][0].shape[0], [p[0].shape[0] for p in parts[1:]],
                          data["W"])
        problem.A[n:] = np.vstack([p[0].reshape(-1, n) for p in parts])
        problem.lo[:] = np.concatenate([data["lower"], *[p[1] for p in parts]])
        problem.hi[:] = np.concatenate([data["upper"], *[p[2] for p in parts]])
        problem.set_weights(np.concatenate([data[f"w_{k}"] for k in range(count)]))
        return problem, str(data["note"])


def corpus_files(directory: Path | None = None) -> list[Path]:
    """Every saved problem, sorted by name."""
    return sorted((directory or HERE).glob("*.npz"))
