"""What every telemetry decoder produces: a body-frame motion sample, and a counted outcome.

Frames and units follow ``docs/conventions.md``: ISO 8855 body axes (x forward, y left,
z up), specific force ``f = a - g`` in m/s^2 (at rest, level: ``f = [0, 0, +9.80665]``),
angular velocity ``w`` in the body frame in rad/s.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Literal, TypedDict

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

__all__ = [
    "G0_M_S2",
    "MAX_ABS_F_M_S2",
    "MAX_ABS_W_RAD_S",
    "DecodeResult",
    "Decoder",
    "SampleArrays",
    "TelemetrySample",
    "samples_to_arrays",
    "up_in_body_from_angles",
    "wrong_size",
]

G0_M_S2 = 9.80665
"""Standard gravity (m/s^2); also the unit the F1 games use for their g-forces."""

MAX_ABS_F_M_S2 = 1000.0
"""Largest specific-force component a decoder passes on (about 100 g).

Real crashes in the games reach tens of g; values beyond this are garbage (a foreign packet
whose bytes happened to pass the checks), not physics. Spikes below it are the washout and
limits stages' business.
"""

MAX_ABS_W_RAD_S = 100.0
"""Largest angular-velocity component a decoder passes on (about 16 turns per second)."""

Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class TelemetrySample:
    """One vehicle-motion sample in the ISO 8855 body frame.

    Attributes
    ----------
    t_s : float
        Time of the sample (s). Live sources stamp ``time.perf_counter()`` at the arrival of
        the datagram that completed the sample; replays of files stamp the recorded time.
    f : tuple of 3 float
        Specific force ``a - g`` in the body frame (m/s^2); ``(0, 0, +9.80665)`` at rest, level.
    w : tuple of 3 float
        Angular velocity in the body frame (rad/s): roll rate, pitch rate, yaw rate.
    paused : bool
        True when the game says it is paused, in a menu or not driving (the pipeline parks).
    game : str
        Registered name of the game that produced it (``"f1"``, ``"forza"``, ``"beamng"``).
    rpm : float
        Engine speed (rev/min); nan when the game does not report it. Optional channel for
        the effect layer (a game profile's ``[effects]``: engine, road, shift), like the
        three below.
    rpm_max : float
        The engine's maximum (rev/min), nan when unknown.
    gear : int or None
        Gear engaged: 0 neutral, -1 reverse, 1.. forward; None when unknown.
    suspension_velocity_m_s : tuple of 4 float or None
        Suspension velocity of the wheels front-left, front-right, rear-left, rear-right
        (m/s, positive compressing); None when unknown.
    """

    t_s: float
    f: Vec3
    w: Vec3
    paused: bool
    game: str
    rpm: float = math.nan
    rpm_max: float = math.nan
    gear: int | None = None
    suspension_velocity_m_s: tuple[float, float, float, float] | None = None


DecodeStatus = Literal["sample", "partial", "state", "ignored", "skipped"]


@dataclass(frozen=True, slots=True)
class DecodeResult:
    """Outcome of decoding one datagram.

    Attributes
    ----------
    status : {"sample", "partial", "state", "ignored", "skipped"}
        ``sample``: a new sample is in ``sample``. ``partial``: the datagram was valid but a
        sample needs another one too (F1 Motion without a Motion Ex yet). ``state``: valid,
        carried game state only (F1 Session: paused flag). ``ignored``: valid, of a kind that
        carries no motion (F1 lap data...). ``skipped``: rejected, see reason.
    reason : str
        The counter key this outcome was counted under in ``Decoder.stats``.
    sample : TelemetrySample or None
        The sample when ``status == "sample"``, else None.
    """

    status: DecodeStatus
    reason: str
    sample: TelemetrySample | None = None


def wrong_size(n: int, size: int) -> DecodeResult:
    """The outcome of a datagram of ``n`` bytes where a format has ``size``: ``skipped:
    truncated`` when it is shorter, ``skipped: wrong size`` when longer (every decoder's two
    reasons for a length it does not know)."""
    return DecodeResult("skipped", "skipped: truncated" if n < size else "skipped: wrong size")


class Decoder(ABC):
    """Base class of the per-game decoders: ``feed`` never raises, every outcome is counted.

    Subclasses implement :meth:`_decode`, which returns a :class:`DecodeResult` for anything
    it recognises or rejects; an exception escaping it is a bug in the decoder, which
    :meth:`decode` still catches and counts (as ``"skipped: decoder error <Type>"``) so that
    a live loop never dies on a datagram.

    Attributes
    ----------
    game : str
        Registered name of the game.
    default_port : int
        UDP port the game sends to by default (class attribute; with :attr:`game` and
        :attr:`title`, what ``GameInfo.of`` registers).
    title : str
        Human-readable list of the games and formats covered (class attribute).
    stats : dict of str to int
        Count of outcomes by reason, e.g. ``{"sample": 812, "skipped: truncated": 3}``.
    """

    game: str = ""
    default_port: ClassVar[int] = 0
    title: ClassVar[str] = ""

    def __init__(self) -> None:
        self.stats: dict[str, int] = {}

    def _count(self, reason: str) -> None:
        self.stats[reason] = self.stats.get(reason, 0) + 1

    def decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        """Decode one datagram received at ``t_s``; never raises, counts the outcome."""
        try:
            result = self._decode(datagram, t_s)
        except Exception as exc:  # a decoder bug must not kill the live loop
            result = DecodeResult("skipped", f"skipped: decoder error {type(exc).__name__}")
        self._count(result.reason)
        return result

    def feed(self, datagram: bytes, t_s: float) -> TelemetrySample | None:
        """Decode one datagram; return the new sample, or None if it yields none. Never raises."""
        return self.decode(datagram, t_s).sample

    def reset(self) -> None:  # noqa: B027 - stateless decoders have nothing to forget
        """Forget game state carried between datagrams (counters are kept)."""

    @abstractmethod
    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        """Decode one datagram (may assume nothing about its content)."""

    # -- helpers for subclasses ------------------------------------------------------------
    def _make(
        self, t_s: float, f: Vec3, w: Vec3, paused: bool, extras: Extras | None = None
    ) -> DecodeResult:
        """Check a converted sample for non-finite or absurd values and wrap it.

        ``extras`` are the optional channels (``rpm``, ``rpm_max``, ``gear``,
        ``suspension_velocity_m_s``); a non-finite or absurd one is dropped (set to unknown)
        rather than costing the motion sample.
        """
        # one chained comparison per value (False for nan, and for inf); the reason only
        # when one fails (this runs for every datagram of every game)
        fx, fy, fz = f
        wx, wy, wz = w
        mf, mw = MAX_ABS_F_M_S2, MAX_ABS_W_RAD_S
        if not (
            -mf <= fx <= mf and -mf <= fy <= mf and -mf <= fz <= mf
            and -mw <= wx <= mw and -mw <= wy <= mw and -mw <= wz <= mw
        ):  # fmt: skip
            for v, m in ((fx, mf), (fy, mf), (fz, mf), (wx, mw), (wy, mw), (wz, mw)):
                if not math.isfinite(v):
                    return DecodeResult("skipped", "skipped: non-finite")
                if abs(v) > m:
                    return DecodeResult("skipped", "skipped: out of range")
        if extras is None:
            return DecodeResult("sample", "sample", TelemetrySample(t_s, f, w, paused, self.game))
        return DecodeResult(
            "sample", "sample", TelemetrySample(t_s, f, w, paused, self.game, **_clean(extras))
        )


Extras = dict[str, object]

MAX_RPM = 100_000.0
"""Largest engine speed passed on (rev/min); anything above is garbage."""

MAX_SUSPENSION_VELOCITY_M_S = 100.0
"""Largest suspension velocity passed on (m/s)."""


class _Channels(TypedDict, total=False):
    rpm: float
    rpm_max: float
    gear: int | None
    suspension_velocity_m_s: tuple[float, float, float, float] | None


def _clean(extras: Extras) -> _Channels:
    """Optional channels with non-finite or absurd values replaced by 'unknown'.

    (Chained comparisons are False for nan and reject inf: one test per value, on the path of
    every datagram.)
    """
    out: _Channels = {}
    if "rpm" in extras:
        v = extras["rpm"]
        ok = isinstance(v, _REAL) and 0.0 <= v <= MAX_RPM
        out["rpm"] = float(v) if ok else math.nan  # type: ignore[arg-type]
    if "rpm_max" in extras:
        v = extras["rpm_max"]
        ok = isinstance(v, _REAL) and 0.0 <= v <= MAX_RPM
        out["rpm_max"] = float(v) if ok else math.nan  # type: ignore[arg-type]
    if "gear" in extras:
        g = extras["gear"]
        out["gear"] = g if isinstance(g, int) and -1 <= g <= 20 else None
    if "suspension_velocity_m_s" in extras:
        sv = extras["suspension_velocity_m_s"]
        clean: tuple[float, float, float, float] | None = None
        if isinstance(sv, tuple) and len(sv) == 4:
            a, b, c, d = (float(x) for x in sv)
            m = MAX_SUSPENSION_VELOCITY_M_S
            if -m <= a <= m and -m <= b <= m and -m <= c <= m and -m <= d <= m:
                clean = (a, b, c, d)
        out["suspension_velocity_m_s"] = clean
    if len(out) != len(extras):  # out has only keys of extras: the others are unknown
        raise TypeError(f"unknown sample channels {sorted(set(extras) - set(out))}")
    return out


_REAL = (float, int)  # a tuple: isinstance with it is faster than with float | int


def up_in_body_from_angles(pitch_rad: float, roll_rad: float) -> Vec3:
    """World "up" unit vector in ISO 8855 body axes, from ISO pitch and roll.

    With ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (conventions.md), the body components of the world
    up axis are the last row of ``R``: ``(-sin(pitch), sin(roll) cos(pitch),
    cos(roll) cos(pitch))``. Since ``-g = G0 * up``, a decoder whose game reports kinematic
    acceleration ``a`` (gravity excluded) builds the specific force as ``a + G0 * up``.

    Parameters
    ----------
    pitch_rad : float
        ISO pitch (rad), positive nose down.
    roll_rad : float
        ISO roll (rad), positive right side down.
    """
    cp = math.cos(pitch_rad)
    return (-math.sin(pitch_rad), math.sin(roll_rad) * cp, math.cos(roll_rad) * cp)


def samples_to_arrays(samples: Sequence[TelemetrySample]) -> SampleArrays:
    """Stack samples into arrays for offline work (ride files, plots, washout in batch).

    Returns
    -------
    SampleArrays
        ``t_s`` (N,) s, ``f`` (N, 3) m/s^2, ``w`` (N, 3) rad/s, ``paused`` (N,) bool; N may
        be 0 (shapes (0,), (0, 3)).
    """
    import numpy as np

    n = len(samples)
    t_s = np.fromiter((s.t_s for s in samples), dtype=float, count=n)
    f = np.array([s.f for s in samples], dtype=float).reshape(n, 3)
    w = np.array([s.w for s in samples], dtype=float).reshape(n, 3)
    paused = np.fromiter((s.paused for s in samples), dtype=bool, count=n)
    return SampleArrays(t_s, f, w, paused)


@dataclass(frozen=True)
class SampleArrays:
    """Samples as arrays: ``t_s`` (N,), ``f`` (N, 3), ``w`` (N, 3), ``paused`` (N,)."""

    t_s: NDArray[np.float64]
    f: NDArray[np.float64]
    w: NDArray[np.float64]
    paused: NDArray[np.bool_]
