"""A telemetry record declared once: its dataclass fields, in wire order, are the layout.

A game's record (``ForzaMotion``, ``BeamNGMotion``, ...) is a frozen dataclass whose fields
stand in the order of its ``struct.Struct``; a field annotated ``tuple[float, float, float]``
takes three consecutive values, any other one value. :func:`flat_values` and
:func:`from_flat` turn a record into the struct's values and back, so a record's ``pack``
and ``unpack`` are one line each instead of a second and third list of its fields.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import fields
from typing import TypeVar, get_args, get_origin, get_type_hints

__all__ = ["flat_values", "from_flat"]

T = TypeVar("T")


_WIDTHS: dict[type, tuple[tuple[str, int], ...]] = {}


def _widths(cls: type) -> tuple[tuple[str, int], ...]:
    """``(name, width)`` of each field of the dataclass ``cls``: a fixed-length tuple's
    length, 0 for a single value (worked out once per class)."""
    known = _WIDTHS.get(cls)
    if known is not None:
        return known
    hints = get_type_hints(cls)
    out = []
    for f in fields(cls):
        t = hints[f.name]
        args = get_args(t)
        fixed = get_origin(t) is tuple and Ellipsis not in args
        out.append((f.name, len(args) if fixed else 0))
    _WIDTHS[cls] = tuple(out)
    return _WIDTHS[cls]


def flat_values(record: object) -> list[object]:
    """The fields of the dataclass ``record`` in declaration order, tuples spread out."""
    out: list[object] = []
    for name, width in _widths(type(record)):
        value = getattr(record, name)
        if width:
            out.extend(value)
        else:
            out.append(value)
    return out


def from_flat(cls: type[T], values: Sequence[object]) -> T:
    """The record ``cls`` whose :func:`flat_values` are ``values``."""
    widths = _widths(cls)
    n_wire = sum(width or 1 for _, width in widths)
    if len(values) != n_wire:
        raise ValueError(f"{cls.__name__}: {len(values)} values for {n_wire} wire fields")
    kwargs: dict[str, object] = {}
    i = 0
    for name, width in widths:
        if width:
            kwargs[name] = tuple(values[i : i + width])
            i += width
        else:
            kwargs[name] = values[i]
            i += 1
    return cls(**kwargs)
