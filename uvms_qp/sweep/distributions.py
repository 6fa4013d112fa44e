"""The distributions a sweep file draws its varied values from, read strictly from TOML.

A value of a sweep file is either fixed or drawn anew for every run:

- a number (or a string where the key takes one): fixed, the same in every run;
- ``{ uniform = [low, high] }``: uniform on ``[low, high]``;
- ``{ normal = [mean, std] }``: Gaussian; add ``within = [low, high]`` to truncate it to an
  interval (drawn from the truncated law, not clipped);
- ``{ choice = [a, b, ...] }``: one of the listed values (numbers or strings), equally likely.

Each distribution knows its support (:attr:`Distribution.support`), so a sweep file is checked
against the range of the quantity it varies before any run starts: a spread that could make a
mass negative is refused even if no run would happen to draw it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.stats import truncnorm

from ..errors import ConfigError
from ..sim.config import Table, check_number, describe, join

#: Keys of a distribution table.
DISTRIBUTION_KEYS = ("uniform", "normal", "within", "choice")


@dataclass(frozen=True, kw_only=True)
class Distribution:
    """A law of one scalar value (base class; :meth:`sample` draws one value).

    Attributes:
        kind: ``"fixed"``, ``"uniform"``, ``"normal"`` or ``"choice"``.
    """

    kind: str = "fixed"

    @property
    def varies(self) -> bool:
        """Whether two runs may draw different values."""
        return False

    @property
    def support(self) -> tuple[float, float]:
        """Smallest and largest value a draw can take (``-inf``/``inf`` when unbounded)."""
        raise NotImplementedError

    def sample(self, rng: np.random.Generator) -> Any:
        """One value drawn with ``rng``."""
        raise NotImplementedError

    def describe(self) -> str:
        """The law in a few characters, for reports (``U(-0.5, 0.5)``)."""
        raise NotImplementedError


@dataclass(frozen=True, kw_only=True)
class Fixed(Distribution):
    """The same value in every run."""

    value: Any = 0.0
    kind: str = "fixed"

    @property
    def support(self) -> tuple[float, float]:
        """The value itself (numbers only)."""
        return (float(self.value), float(self.value))

    def sample(self, rng: np.random.Generator) -> Any:
        """The value (no random number is drawn)."""
        return self.value

    def describe(self) -> str:
        """The value."""
        return f"{self.value:g}" if isinstance(self.value, float | int) else str(self.value)


@dataclass(frozen=True, kw_only=True)
class Uniform(Distribution):
    """Uniform on ``[low, high]``."""

    low: float = 0.0
    high: float = 0.0
    kind: str = "uniform"

    @property
    def varies(self) -> bool:
        """True unless ``low == high``."""
        return self.high > self.low

    @property
    def support(self) -> tuple[float, float]:
        """``(low, high)``."""
        return (self.low, self.high)

    def sample(self, rng: np.random.Generator) -> float:
        """``rng.uniform(low, high)``."""
        return float(rng.uniform(self.low, self.high))

    def describe(self) -> str:
        """``U(low, high)``."""
        return f"U({self.low:g}, {self.high:g})"


@dataclass(frozen=True, kw_only=True)
class Normal(Distribution):
    """Gaussian of ``mean`` and ``std``, optionally truncated to ``[low, high]``."""

    mean: float = 0.0
    std: float = 0.0
    low: float = -math.inf
    high: float = math.inf
    kind: str = "normal"

    @property
    def varies(self) -> bool:
        """True when ``std > 0``."""
        return self.std > 0.0

    @property
    def support(self) -> tuple[float, float]:
        """``(low, high)`` of the truncation, unbounded without one."""
        if self.std == 0.0:
            return (self.mean, self.mean)
        return (self.low, self.high)

    def sample(self, rng: np.random.Generator) -> float:
        """A Gaussian draw (from the truncated law when ``within`` is set)."""
        if self.std == 0.0:
            return self.mean
        if math.isinf(self.low) and math.isinf(self.high):
            return float(rng.normal(self.mean, self.std))
        a, b = (self.low - self.mean) / self.std, (self.high - self.mean) / self.std
        return float(truncnorm.rvs(a, b, loc=self.mean, scale=self.std, random_state=rng))

    def describe(self) -> str:
        """``N(mean, std)``, with its truncation."""
        text = f"N({self.mean:g}, {self.std:g})"
        if math.isfinite(self.low) or math.isfinite(self.high):
            text += f" in [{self.low:g}, {self.high:g}]"
        return text


@dataclass(frozen=True, kw_only=True)
class Choice(Distribution):
    """One of ``options``, equally likely."""

    options: tuple[Any, ...] = ()
    kind: str = "choice"

    @property
    def varies(self) -> bool:
        """True with two options or more."""
        return len(set(self.options)) > 1

    @property
    def support(self) -> tuple[float, float]:
        """Smallest and largest option (numbers only)."""
        return (float(min(self.options)), float(max(self.options)))

    def sample(self, rng: np.random.Generator) -> Any:
        """One option."""
        return self.options[int(rng.integers(len(self.options)))]

    def describe(self) -> str:
        """``one of a, b, c``."""
        return "one of " + ", ".join(str(o) for o in self.options)


def _pair(value: Any, path: str, what: str) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise ConfigError(f"expected [{what}], two numbers, got {describe(value)}"
                          + (f" of {len(value)}" if isinstance(value, list) else ""), path)
    return check_number(value[0], join(path, 0)), check_number(value[1], join(path, 1))


def read_distribution(value: Any, path: str, *, strings: bool = False) -> Distribution:
    """Read a fixed value or a distribution table (see the module docstring).

    Args:
        value: The raw TOML value.
        path: Its field path, for messages.
        strings: Whether the key takes strings (a fixed string or a choice of strings).

    Raises:
        ConfigError: not a number (or string), an unknown or misspelt law, several laws in one
            table, ``low > high``, a negative ``std``, a truncation that excludes the whole law,
            or an empty choice; at the path of the culprit.
    """
    if strings and isinstance(value, str):
        return Fixed(value=value)
    if not isinstance(value, dict):
        check_number(value, path)
        return Fixed(value=float(value))
    table = Table(value, path, DISTRIBUTION_KEYS)
    laws = [key for key in ("uniform", "normal", "choice") if key in value]
    if len(laws) != 1:
        table.raw("uniform")
        table.raw("normal")
        table.raw("choice")
        table.raw("within")
        table.finish()  # an unknown key first
        found = ", ".join(laws) if laws else "none"
        raise ConfigError(f"expected exactly one of uniform, normal, choice; got {found}", path)
    law = laws[0]
    if law == "uniform":
        low, high = _pair(table.raw("uniform"), table.at("uniform"), "low, high")
        table.finish()
        if low > high:
            raise ConfigError(f"expected low <= high, got [{low:g}, {high:g}]",
                              table.at("uniform"))
        return Uniform(low=low, high=high)
    if law == "normal":
        mean, std = _pair(table.raw("normal"), table.at("normal"), "mean, std")
        if std < 0.0:
            raise ConfigError(f"expected a standard deviation >= 0, got {std:g}",
                              join(table.at("normal"), 1))
        within = table.raw("within")
        table.finish()
        if within is None:
            return Normal(mean=mean, std=std)
        low, high = _pair(within, table.at("within"), "low, high")
        if not low < high or not low <= mean <= high:
            raise ConfigError(f"expected low < high around the mean {mean:g}, got "
                              f"[{low:g}, {high:g}]", table.at("within"))
        return Normal(mean=mean, std=std, low=low, high=high)
    options = table.raw("choice")
    table.finish()
    where = table.at("choice")
    if not isinstance(options, list) or not options:
        raise ConfigError(f"expected a non-empty array, got {describe(options)}", where)
    checked: list[Any] = []
    for i, option in enumerate(options):
        if strings and isinstance(option, str):
            checked.append(option)
        else:
            checked.append(check_number(option, join(where, i)))
    if len({type(o) for o in checked}) > 1:
        raise ConfigError("expected options of one type (all numbers or all strings)", where)
    return Choice(options=tuple(checked))


def check_support(dist: Distribution, path: str, *, low: float | None = None,
                  high: float | None = None, what: str = "the value",
                  strict_low: bool = False) -> None:
    """Refuse a distribution whose support leaves ``[low, high]``.

    Args:
        dist: The distribution (numbers).
        path: Field path for the message.
        low: Smallest allowed value (None: unbounded).
        high: Largest allowed value (None: unbounded).
        what: The quantity, for the message (``"a delay [s]"``).
        strict_low: ``low`` itself is not allowed (a value must be ``> low``).

    Raises:
        ConfigError: the support reaches outside the range (an unbounded normal always does
            when a bound is set: give it ``within``).
    """
    lo, hi = dist.support
    too_low = low is not None and (lo < low or (strict_low and lo <= low))
    too_high = high is not None and hi > high
    if not (too_low or too_high):
        return
    sign = ">" if strict_low else ">="
    allowed = " and ".join(
        part for part in (f"{sign} {low:g}" if low is not None else "",
                          f"<= {high:g}" if high is not None else "") if part)
    reach = lo if too_low else hi
    reach_text = ("is unbounded (add within = [low, high])" if math.isinf(reach)
                  else f"reaches {reach:g}")
    raise ConfigError(f"{what} must be {allowed}, but the spread {dist.describe()} "
                      f"{reach_text}", path)
