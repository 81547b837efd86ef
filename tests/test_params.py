"""pftrack.params: the typed parameter dataclasses every tracker, detector and cue takes; values from the command line
(strings) coerced to the declared type, and every wrong value refused with a ParameterError naming the parameter."""

from __future__ import annotations

import dataclasses
import doctest
from typing import Literal

import pytest

import pftrack.params
from pftrack.errors import ParameterError
from pftrack.params import Params, param, parse_param_assignments


@dataclasses.dataclass(frozen=True, kw_only=True)
class Demo(Params):
    n: int = param(100, ge=1, doc="a count")
    rate: float = param(0.5, gt=0, lt=1, doc="a share")
    flag: bool = param(False, doc="a switch")
    name: str = param("a", doc="a name")
    mode: Literal["fast", "exact"] = param("fast", doc="a choice")
    level: str = param("low", choices=("low", "high"), doc="declared choices")
    sizes: tuple[int, ...] = param((1, 2), ge=0, doc="several counts")
    cap: float | None = param(None, le=10, doc="optional")


def test_the_module_example_runs():
    assert doctest.testmod(pftrack.params).failed == 0


@pytest.mark.parametrize("given, field, expected", [
    ({"n": "7"}, "n", 7), ({"n": 7.0}, "n", 7), ({"n": " 12 "}, "n", 12),
    ({"rate": "0.25"}, "rate", 0.25), ({"rate": 1 / 3}, "rate", 1 / 3),
    ({"flag": "true"}, "flag", True), ({"flag": " No "}, "flag", False), ({"flag": 1}, "flag", True),
    ({"flag": 0}, "flag", False), ({"mode": "exact"}, "mode", "exact"), ({"level": "high"}, "level", "high"),
    ({"sizes": "3/4;5"}, "sizes", (3, 4, 5)), ({"sizes": "6,7"}, "sizes", (6, 7)), ({"sizes": [8]}, "sizes", (8,)),
    ({"cap": "2.5"}, "cap", 2.5), ({"cap": None}, "cap", None),
])
def test_values_are_coerced_to_the_declared_type(given, field, expected):
    value = getattr(Demo.from_mapping(given), field)
    assert value == expected and type(value) is type(expected)


@pytest.mark.parametrize("given, message", [
    ({"n": "seven"}, "'n' must be an integer, got 'seven'"), ({"n": 2.5}, "'n' must be an integer"),
    ({"n": True}, "'n' must be an integer, got True"), ({"n": None}, "'n' must be a int, got None"),
    ({"n": 0}, "'n' must be >= 1, got 0"),
    ({"rate": "x"}, "'rate' must be a number"), ({"rate": False}, "'rate' must be a number, got False"),
    ({"rate": "nan"}, "'rate' must be finite"), ({"rate": 0}, "'rate' must be > 0"), ({"rate": 1.0}, "must be < 1"),
    ({"flag": "maybe"}, "'flag' must be true or false"), ({"flag": 2}, "'flag' must be true or false"),
    ({"name": 3}, "'name' must be a string, got 3"), ({"mode": "slow"}, "'mode' must be one of 'fast', 'exact'"),
    ({"level": "mid"}, "'level' must be one of 'low', 'high', got 'mid'"),
    ({"sizes": {"a": 1}}, "'sizes' must be a"), ({"sizes": "1,x"}, "'sizes' must be an integer, got 'x'"),
    ({"sizes": "1,-2"}, "'sizes' must be >= 0, got -2"), ({"cap": 11}, "'cap' must be <= 10"),
    ({"particles": 5}, "unknown parameter 'particles' for Demo; valid: cap, flag, level"),
    ({"rates": 0.2}, "unknown parameter 'rates' for Demo; did you mean rate"),
])
def test_wrong_values_name_the_parameter(given, message):
    with pytest.raises(ParameterError, match=message.replace("(", r"\(").replace(")", r"\)")):
        Demo.from_mapping(given)


def test_replace_validates_again_and_describe_lists_every_field():
    p = Demo(n=3)
    assert p.replace(rate="0.75").rate == 0.75 and p.replace(rate="0.75").n == 3 and p.rate == 0.5
    with pytest.raises(ParameterError, match="'n' must be >= 1"):
        p.replace(n=0)
    rows = {name: (kind, default, doc) for name, kind, default, doc in Demo.describe()}
    assert rows["n"] == ("int", 100, "a count") and set(rows) == set(Demo.field_names())


def test_a_mutable_default_is_refused_when_the_class_is_written():
    with pytest.raises(TypeError, match="mutable parameter defaults"):
        param([1, 2], doc="a list")


def test_command_line_assignments():
    assert parse_param_assignments(["n=3", " max-rate = 0.5 ", "name=a=b"]) == {"n": "3", "max_rate": "0.5",
                                                                                 "name": "a=b"}
    assert parse_param_assignments(None) == {}
    for bad in ("n", "=3"):
        with pytest.raises(ParameterError, match="--param expects KEY=VALUE"):
            parse_param_assignments([bad])
