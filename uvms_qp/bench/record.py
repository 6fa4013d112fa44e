"""One benchmark row: a solver (or scheme) on one problem of one set.

Rows are what the JSON and CSV files store, one per ``(set, problem, solver)`` key; a resumed run
skips the keys already present. Every trial is counted: ``trials = successes + sum(failures)``,
and each failure carries its reason.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

#: Hard-row tolerance a result must meet to count as a success (whatever the back-end says).
HARD_TOL = 1e-7

#: Note of a row whose answer was clipped into the hard box (a closed form: then not the
#: lexicographic reference, and a level it misses cannot be proven optimal).
SATURATED = "saturated into the hard box"
#: Note of a row that solved its own problem, smaller than the one the other rows of its set
#: solve (Pink on a scenario: the tracked frame and a posture cost as one weighted level): its
#: times are not compared with theirs.
OWN_PROBLEM = "own problem: the tracked frame and a posture cost as one weighted level"

#: Columns of the CSV file, in order.
CSV_COLUMNS: tuple[str, ...] = (
    "set", "problem", "solver", "trials", "successes", "failures", "n_times", "median_us",
    "p95_us", "max_us", "hard_violation", "claimed_violation", "nan_count", "levels",
    "backend_us", "note", "times_us",
)


@dataclass
class Record:
    """Outcome of one solver on one problem.

    Attributes:
        set: Test set name.
        problem: Problem name (unique within the set).
        solver: Solver or scheme name.
        trials: Trials attempted (control steps, or repeated solves of one problem).
        successes: Verified successes: finite, status optimal, every hard row
            within :data:`HARD_TOL`.
        failures: Failure reason -> count (e.g. ``{"hard_violation": 2, "backend_error": 1}``).
        times_us: Time of every timed trial [us] (failed ones too).
        hard_violation: Largest hard-row violation over every trial.
        claimed_violation: Largest hard-row violation over the trials the back-end called a
            success (> HARD_TOL means it claimed a success it did not deliver).
        nan_count: Trials with a non-finite answer.
        levels: Weighted violation norm of every level at the last answer (problems with a
            common reference only), else None.
        backend_us: Median time the back-end reports for itself [us] (DAQP's C solve time), or
            NaN.
        note: Skipped/not-applicable reason or other detail.
        info: Problem description (model, n, tags...).
    """

    set: str
    problem: str
    solver: str
    trials: int = 0
    successes: int = 0
    failures: dict[str, int] = field(default_factory=dict)
    times_us: list[float] = field(default_factory=list)
    hard_violation: float = 0.0
    claimed_violation: float = 0.0
    nan_count: int = 0
    levels: list[float] | None = None
    backend_us: float = math.nan
    note: str = ""
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def key(self) -> tuple[str, str, str]:
        """The resumable key ``(set, problem, solver)``."""
        return (self.set, self.problem, self.solver)

    @property
    def applicable(self) -> bool:
        """False for a row that records a solver not applicable to the problem (no trial)."""
        return self.trials > 0

    @property
    def failed(self) -> int:
        """Number of failed trials."""
        return sum(self.failures.values())

    def fail(self, reason: str, count: int = 1) -> None:
        """Count ``count`` failures for ``reason``."""
        if count:
            self.failures[reason] = self.failures.get(reason, 0) + int(count)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dictionary (NaN written as None)."""
        data = asdict(self)
        if math.isnan(self.backend_us):
            data["backend_us"] = None
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Record:
        """Inverse of :meth:`to_dict`."""
        kwargs = dict(data)
        if kwargs.get("backend_us") is None:
            kwargs["backend_us"] = math.nan
        known = set(cls.__dataclass_fields__)
        return cls(**{k: v for k, v in kwargs.items() if k in known})

    def to_row(self) -> dict[str, str]:
        """One CSV row (see :data:`CSV_COLUMNS`); lists are space-separated."""
        t = self.times_us
        return {
            "set": self.set, "problem": self.problem, "solver": self.solver,
            "trials": str(self.trials), "successes": str(self.successes),
            "failures": ";".join(f"{k}:{v}" for k, v in sorted(self.failures.items())),
            "n_times": str(len(t)),
            "median_us": f"{percentile(t, 50):.3f}", "p95_us": f"{tail_percentile(t, 95):.3f}",
            "max_us": f"{max(t):.3f}" if t else "nan",
            "hard_violation": f"{self.hard_violation:.3e}",
            "claimed_violation": f"{self.claimed_violation:.3e}",
            "nan_count": str(self.nan_count),
            "levels": "" if self.levels is None else " ".join(f"{v:.12e}" for v in self.levels),
            "backend_us": f"{self.backend_us:.3f}",
            "note": self.note,
            "times_us": " ".join(f"{v:.2f}" for v in t),
        }

    @classmethod
    def from_row(cls, row: dict[str, str]) -> Record:
        """Inverse of :meth:`to_row` (problem info is not stored in the CSV)."""
        failures: dict[str, int] = {}
        for part in filter(None, (row.get("failures") or "").split(";")):
            reason, _, count = part.rpartition(":")
            failures[reason] = int(count)
        levels_text = row.get("levels") or ""
        return cls(
            set=row["set"], problem=row["problem"], solver=row["solver"],
            trials=int(row["trials"]), successes=int(row["successes"]), failures=failures,
            times_us=[float(v) for v in (row.get("times_us") or "").split()],
            hard_violation=float(row["hard_violation"]),
            claimed_violation=float(row["claimed_violation"]),
            nan_count=int(row["nan_count"]),
            levels=[float(v) for v in levels_text.split()] if levels_text else None,
            backend_us=float(row.get("backend_us") or "nan"),
            note=row.get("note") or "",
        )


def percentile(values: Sequence[float], q: float) -> float:
    """The ``q``-th percentile of ``values`` (NaN when empty)."""
    return float(np.percentile(values, q)) if len(values) else math.nan


def tail_samples(q: float) -> int:
    """Fewest samples a ``q``-th percentile (q > 50) needs: ``ceil(100 / (100 - q))``.

    With fewer, not one sample is expected above it: the "percentile" is the maximum, or an
    interpolation toward it (20 samples for p95, 100 for p99).
    """
    return math.ceil(100.0 / (100.0 - q) - 1e-9)


def tail_percentile(values: Sequence[float], q: float) -> float:
    """The ``q``-th percentile of ``values``, NaN from fewer than :func:`tail_samples` samples."""
    return percentile(values, q) if len(values) >= tail_samples(q) else math.nan
