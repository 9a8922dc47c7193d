"""The bundled sample lap is what its documented generator produces, and is physical."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _csvtext import csv_text_mismatch
from _tools import load_tool

ROOT = Path(__file__).resolve().parents[1]
G = 9.80665


def _generator():  # type: ignore[no-untyped-def]
    return load_tool("make_sample_lap")


def _bundled() -> np.ndarray:
    return np.genfromtxt(ROOT / "configs/recordings/lap.csv", delimiter=",", names=True)


def test_bundled_lap_is_reproducible() -> None:
    # as numbers, to the written precision: another machine's floats may round the other way
    # in the last decimal (tests/_csvtext.py)
    bundled = (ROOT / "configs/recordings/lap.csv").read_text()
    assert csv_text_mismatch(_generator().lap_csv_text(), bundled) is None


def test_lap_is_a_closed_circuit_at_the_limit() -> None:
    d = _bundled()
    dt = np.diff(d["t"])
    np.testing.assert_allclose(dt, 0.01, atol=1e-9)
    # Heading: one full clockwise turn of the circuit (right-hand corners dominate).
    heading = np.sum(d["wz"][:-1] * dt)
    assert abs(heading + 2 * np.pi) < 0.05 * 2 * np.pi
    # A flying lap: the speed at the line closes on itself.
    assert abs(d["speed"][0] - d["speed"][-1]) < 0.5
    # Vertical specific force averages to gravity; grip envelope about 1.35 g laterally.
    assert abs(np.mean(d["fz"]) - G) < 0.02 * G
    assert 1.2 * G < np.max(np.abs(d["fy"])) < 1.5 * G


def test_lateral_force_sign_matches_turn_direction() -> None:
    d = _bundled()
    # In a right-hand turn (yaw rate < 0) the centripetal acceleration points right (-y).
    turning = np.abs(d["wz"]) > 0.2
    assert np.all(np.sign(d["fy"][turning]) == np.sign(d["wz"][turning]))
