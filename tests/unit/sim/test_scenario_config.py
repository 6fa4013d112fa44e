"""The generic TOML-to-object machinery, on small stand-in classes (the introspection contract
that any new task, constraint or trajectory class relies on)."""

from __future__ import annotations

from typing import Literal

import pytest

from uvms_qp.errors import ConfigError, InputError, UnknownFrameError
from uvms_qp.sim.config import Table, construct, convert


class Widget:
    def __init__(
        self,
        size: float,
        *,
        mode: Literal["a", "b"] = "a",
        count: int = 1,
        flag: bool = False,
        gains: float | list[float] = 1.0,
        names: list[str] | None = None,
        matrix: list[list[float]] | None = None,
        label: str = "w",
        blob=None,
    ) -> None:
        if size <= 0:
            raise InputError(f"{label}.size: expected a positive number, got {size}")
        if names and "bad" in names:
            raise UnknownFrameError("bad", ["tool", "vehicle"])
        self.size, self.mode, self.count, self.flag = size, mode, count, flag
        self.gains, self.names, self.matrix, self.blob = gains, names, matrix, blob


def build(data):
    return construct(Widget, Table(data, "things[2]"), skip=(), kind="")


def test_values_are_converted_by_their_hints():
    w = build({"size": 2, "mode": "b", "count": 3, "flag": True, "gains": [1, 2],
               "names": ["x"], "matrix": [[1, 2], [3, 4]], "blob": {"any": "thing"}})
    assert w.size == 2.0 and isinstance(w.size, float)
    assert (w.mode, w.count, w.flag, w.gains) == ("b", 3, True, [1.0, 2.0])
    assert w.matrix == [[1.0, 2.0], [3.0, 4.0]]
    assert w.blob == {"any": "thing"}  # no hint: passed through for the constructor to check


@pytest.mark.parametrize(
    ("data", "path", "fragment"),
    [
        ({}, "things[2]", "missing required field 'size'"),
        ({"size": 1, "colour": 2}, "things[2].colour", "unknown key 'colour'"),
        ({"size": "big"}, "things[2].size", "expected a number, got a string"),
        ({"size": True}, "things[2].size", "expected a number, got a boolean"),
        ({"size": 1, "mode": "c"}, "things[2].mode", "expected one of 'a', 'b', got 'c'"),
        ({"size": 1, "count": 2.5}, "things[2].count", "expected an integer, got a float"),
        ({"size": 1, "flag": 1}, "things[2].flag", "expected a boolean, got an integer"),
        ({"size": 1, "gains": "x"}, "things[2].gains", "expected a number, got a string"),
        ({"size": 1, "names": "x"}, "things[2].names", "expected an array of strings"),
        ({"size": 1, "matrix": [[1, "x"]]}, "things[2].matrix[0][1]", "expected a number"),
        ({"size": float("nan")}, "things[2].size", "expected a finite number"),
        # the constructor's own validation, moved into the path
        ({"size": -1}, "things[2].size", "expected a positive number, got -1"),
        ({"size": 1, "names": ["ok", "bad"]}, "things[2].names[1]", "unknown frame 'bad'"),
    ],
)
def test_errors_carry_the_field_path(data, path, fragment):
    with pytest.raises(ConfigError) as info:
        build(data)
    assert info.value.path == path, str(info.value)
    assert fragment in str(info.value)


def test_table_reports_unknown_keys_after_reading():
    table = Table({"a": 1, "b": 2}, "top")
    assert table.take_number("a") == 1.0
    with pytest.raises(ConfigError, match=r"^top\.b: unknown key 'b'; known keys: a"):
        table.finish()
    with pytest.raises(ConfigError, match=r"^x: expected a table, got an array"):
        Table([1], "x")


def test_convert_leaves_unknown_hints_alone():
    marker = object()
    assert convert(marker, object, "p") is marker
