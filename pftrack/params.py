"""Typed, validated, documented parameter dataclasses.

Every tracker, detector and cue takes its options as a frozen, keyword-only
dataclass derived from :class:`Params`.  Each field is declared with
:func:`param`, which records its documentation (the paper's symbol and equation)
and its admissible range.  Construction validates every field and raises
:class:`~pftrack.errors.ParameterError` naming the parameter at fault, so a
typo or an out-of-range value fails loudly instead of silently changing the
behaviour.

Example
-------
>>> from dataclasses import dataclass
>>> @dataclass(frozen=True, kw_only=True)
... class P(Params):
...     n: int = param(100, ge=1, doc="number of particles")
>>> P(n=5).n
5
>>> P.from_mapping({"n": "7"}).n
7
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import types
import typing
from typing import Any, Iterator, Mapping

from .errors import ParameterError

_MISSING = dataclasses.MISSING


def param(
    default: Any,
    *,
    doc: str,
    ge: float | None = None,
    gt: float | None = None,
    le: float | None = None,
    lt: float | None = None,
    choices: tuple | None = None,
) -> Any:
    """Declare a parameter field with its documentation and admissible range."""
    meta = {"doc": doc, "ge": ge, "gt": gt, "le": le, "lt": lt, "choices": choices}
    if isinstance(default, (list, dict, set)):
        raise TypeError("mutable parameter defaults are not allowed; use a tuple")
    return dataclasses.field(default=default, metadata=meta)


def _unwrap_optional(tp: Any) -> tuple[Any, bool]:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1 and len(typing.get_args(tp)) == 2:
            return args[0], True
    return tp, False


def _type_name(tp: Any) -> str:
    base, optional = _unwrap_optional(tp)
    if typing.get_origin(base) is tuple:
        inner = typing.get_args(base)
        name = "tuple of " + (_type_name(inner[0]) if inner else "values")
    elif typing.get_origin(base) is typing.Literal:
        name = "one of " + ", ".join(repr(a) for a in typing.get_args(base))
    else:
        name = getattr(base, "__name__", str(base))
    return name + (" or None" if optional else "")


_TRUE = {"1", "true", "yes", "on"}
_FALSE = {"0", "false", "no", "off"}


def _coerce(name: str, value: Any, tp: Any) -> Any:
    """Convert ``value`` (possibly a string from the command line) to ``tp``."""
    base, optional = _unwrap_optional(tp)
    if value is None or (optional and isinstance(value, str) and value.lower() in ("none", "null")):
        if optional:
            return None
        raise ParameterError(f"parameter '{name}' must be a {_type_name(tp)}, got None")
    origin = typing.get_origin(base)
    if origin is typing.Literal:
        allowed = typing.get_args(base)
        if value in allowed:
            return value
        raise ParameterError(f"parameter '{name}' must be one of {', '.join(map(repr, allowed))}, got {value!r}")
    if origin is tuple:
        inner = typing.get_args(base)
        elem = inner[0] if inner else float
        if isinstance(value, str):
            # "," or ";" separate elements, and "/" too (inside a tracker spec such as
            # ``fs-meanshift[candidates=R/G/Ieq]``, where "," and ";" separate parameters)
            parts = [p for p in value.replace(";", ",").replace("/", ",").split(",") if p.strip()]
        elif isinstance(value, (list, tuple)):
            parts = list(value)
        else:
            raise ParameterError(f"parameter '{name}' must be a {_type_name(tp)}, got {value!r}")
        return tuple(_coerce(name, p, elem) for p in parts)
    if base is bool:
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.strip().lower() in _TRUE | _FALSE:
            return value.strip().lower() in _TRUE
        if isinstance(value, (int,)) and value in (0, 1):
            return bool(value)
        raise ParameterError(f"parameter '{name}' must be true or false, got {value!r}")
    if base is int:
        if isinstance(value, bool):
            raise ParameterError(f"parameter '{name}' must be an integer, got {value!r}")
        if isinstance(value, int):
            return value
        if isinstance(value, float) and value.is_integer():
            return int(value)
        if isinstance(value, str):
            try:
                return int(value.strip())
            except ValueError:
                pass
        raise ParameterError(f"parameter '{name}' must be an integer, got {value!r}")
    if base is float:
        if isinstance(value, bool):
            raise ParameterError(f"parameter '{name}' must be a number, got {value!r}")
        try:
            out = float(value)
        except (TypeError, ValueError):
            raise ParameterError(f"parameter '{name}' must be a number, got {value!r}") from None
        if not math.isfinite(out):
            raise ParameterError(f"parameter '{name}' must be finite, got {value!r}")
        return out
    if base is str:
        if isinstance(value, str):
            return value
        raise ParameterError(f"parameter '{name}' must be a string, got {value!r}")
    return value  # callables and other objects are checked by the owner


def _check_range(name: str, value: Any, meta: Mapping[str, Any]) -> None:
    if value is None:
        return
    choices = meta.get("choices")
    if choices is not None and value not in choices:
        raise ParameterError(f"parameter '{name}' must be one of {', '.join(map(repr, choices))}, got {value!r}")
    values = value if isinstance(value, tuple) else (value,)
    for v in values:
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            continue
        lo, hi = meta.get("ge"), meta.get("le")
        glo, lhi = meta.get("gt"), meta.get("lt")
        if lo is not None and v < lo:
            raise ParameterError(f"parameter '{name}' must be >= {lo}, got {v!r}")
        if glo is not None and v <= glo:
            raise ParameterError(f"parameter '{name}' must be > {glo}, got {v!r}")
        if hi is not None and v > hi:
            raise ParameterError(f"parameter '{name}' must be <= {hi}, got {v!r}")
        if lhi is not None and v >= lhi:
            raise ParameterError(f"parameter '{name}' must be < {lhi}, got {v!r}")


@dataclasses.dataclass(frozen=True, kw_only=True)
class Params:
    """Base class: validates every field on construction."""

    def __post_init__(self) -> None:
        hints = typing.get_type_hints(type(self))
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            coerced = _coerce(f.name, value, hints.get(f.name, Any))
            _check_range(f.name, coerced, f.metadata)
            if coerced is not value:
                object.__setattr__(self, f.name, coerced)
        self.validate()

    def validate(self) -> None:
        """Cross-field checks; subclasses override and raise ParameterError."""

    @classmethod
    def field_names(cls) -> list[str]:
        return [f.name for f in dataclasses.fields(cls)]

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any] | None = None, **more: Any):
        """Build from a mapping (e.g. parsed ``--param key=value`` strings).

        Unknown names raise :class:`ParameterError` with the closest valid names.
        """
        merged = dict(values or {})
        merged.update(more)
        known = set(cls.field_names())
        for key in merged:
            if key not in known:
                close = difflib.get_close_matches(key, sorted(known), n=3)
                hint = (f"; did you mean {', '.join(close)}?" if close else
                        f"; valid: {', '.join(sorted(known))}" if 0 < len(known) <= 12 else
                        f" (it has {len(known)}: 'pftrack list NAME' shows them)" if known else
                        " (it takes no parameters)")
                raise ParameterError(f"unknown parameter '{key}' for {cls.__name__}{hint}")
        return cls(**merged)

    def replace(self, **changes: Any):
        """A copy with some fields changed (validated again)."""
        return self.from_mapping({**self.as_dict(), **changes})

    def as_dict(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    @classmethod
    def describe(cls) -> Iterator[tuple[str, str, Any, str]]:
        """Yield ``(name, type, default, doc)`` for every parameter."""
        hints = typing.get_type_hints(cls)
        for f in dataclasses.fields(cls):
            default = f.default if f.default is not _MISSING else None
            yield f.name, _type_name(hints.get(f.name, Any)), default, f.metadata.get("doc", "")


def parse_param_assignments(items: list[str] | None) -> dict[str, str]:
    """Parse ``["key=value", ...]`` from the command line into a dict of strings."""
    out: dict[str, str] = {}
    for item in items or []:
        if "=" not in item:
            raise ParameterError(f"--param expects KEY=VALUE, got {item!r}")
        key, value = item.split("=", 1)
        key = key.strip().replace("-", "_")
        if not key:
            raise ParameterError(f"--param expects KEY=VALUE, got {item!r}")
        out[key] = value.strip()
    return out
