"""The shared check of the bad-input tables: a typed error whose message names the culprit."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import pytest

from uvms_qp import UvmsQpError


def bad_cases(table: Sequence[tuple[Any, ...]]) -> list[Any]:
    """``pytest.param`` per row ``(id, *values)`` of a bad-input table."""
    return [pytest.param(*row[1:], id=row[0]) for row in table]


def assert_names_culprit(build: Callable[..., Any], error: type[Exception], fragment: str,
                         *args: Any) -> None:
    """``build(*args)`` raises ``error``, a library error, whose message contains ``fragment``."""
    with pytest.raises(error) as info:
        build(*args)
    assert isinstance(info.value, UvmsQpError)
    assert fragment in str(info.value)
