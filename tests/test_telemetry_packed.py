"""The record helper behind the games' pack / unpack: field order is wire order."""

from __future__ import annotations

import struct
from dataclasses import dataclass

import pytest

from motioncue.telemetry._packed import flat_values, from_flat

LAYOUT = struct.Struct("<i3fH2f")


@dataclass(frozen=True, slots=True)
class _Toy:
    a: int
    v: tuple[float, float, float]
    b: int
    w: tuple[float, float]


def test_flat_values_spread_tuples_in_field_order_and_from_flat_inverts_them() -> None:
    toy = _Toy(-7, (1.5, -2.25, 3.0), 65535, (0.5, -0.125))
    assert flat_values(toy) == [-7, 1.5, -2.25, 3.0, 65535, 0.5, -0.125]
    data = LAYOUT.pack(*flat_values(toy))
    assert data == struct.pack("<i3fH2f", -7, 1.5, -2.25, 3.0, 65535, 0.5, -0.125)
    assert from_flat(_Toy, LAYOUT.unpack(data)) == toy


@pytest.mark.parametrize("n", [0, 3, 6, 8])
def test_from_flat_refuses_a_value_count_other_than_the_fields(n: int) -> None:
    with pytest.raises(ValueError, match="wire fields"):
        from_flat(_Toy, list(range(n)))
