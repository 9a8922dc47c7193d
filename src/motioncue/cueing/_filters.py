"""Filter building blocks shared by the washout and the vestibular models.

* :func:`tustin_section` discretises a continuous transfer function of order <= 2 by the
  bilinear (Tustin) transform with frequency prewarping, giving one second-order section
  ``(b0, b1, b2, 1, a1, a2)`` in the layout of :func:`scipy.signal.sosfilt`.
* :func:`soft_limit` / :func:`soft_limit_array`: the smooth limiter (identity up to a knee,
  then a tanh bend towards the limit, continuous in value and slope).
* :func:`compress` / :func:`compress_array`: the compressive scaling curve
  ``y = k x / (1 + |k x / L|^p)^(1/p)`` (gain ``k`` near zero, limit ``L``, one limit per
  sign), smooth, odd when both limits agree, strictly monotone.
* :func:`rate_limit_array`: the rate limiter ``y[n] = y[n-1] + clip(x[n] - y[n-1], -r, r)``
  over a whole signal, vectorised by segments, giving the same numbers as the sample loop.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from .._errors import ConfigError

__all__ = [
    "compress",
    "compress_array",
    "compress_inverse",
    "rate_limit_array",
    "rate_limit_step",
    "soft_limit",
    "soft_limit_array",
    "tustin_section",
]

Section = tuple[float, float, float, float, float, float]


def tustin_section(
    num: Sequence[float], den: Sequence[float], fs_hz: float, warp_rad_s: float | None
) -> Section:
    """Bilinear transform of ``num(s)/den(s)`` (order <= 2) into one second-order section.

    The substitution is ``s = K (1 - z^-1) / (1 + z^-1)`` with ``K = w / tan(w T / 2)``
    (prewarped so that the discrete response equals the continuous one exactly at
    ``w = warp_rad_s``), or ``K = 2 fs`` when ``warp_rad_s`` is ``None``.

    Parameters
    ----------
    num, den
        Polynomial coefficients in ``s``, highest power first; ``len(den) <= 3``,
        ``len(num) <= len(den)`` (proper).
    fs_hz
        Sample rate.
    warp_rad_s
        Prewarp frequency, below Nyquist (``pi fs``).

    Returns
    -------
    tuple of 6 floats
        ``(b0, b1, b2, 1.0, a1, a2)``, normalised so that ``a0 = 1``.
    """
    den_a = np.trim_zeros(np.asarray(den, dtype=float), "f")
    num_a = np.trim_zeros(np.asarray(num, dtype=float), "f")
    order = len(den_a) - 1
    if order < 1 or order > 2 or len(num_a) - 1 > order:
        raise ValueError(f"need a proper transfer function of order 1 or 2, got {num}/{den}")
    nyquist = math.pi * fs_hz
    if warp_rad_s is None:
        k = 2.0 * fs_hz
    else:
        if not 0.0 < warp_rad_s < nyquist:
            raise ConfigError(
                f"filter frequency {warp_rad_s:g} rad/s is not below Nyquist "
                f"({nyquist:g} rad/s at fs = {fs_hz:g} Hz); raise the sample rate"
            )
        k = warp_rad_s / math.tan(warp_rad_s / (2.0 * fs_hz))
    b, a = _bilinear(num_a, order, k), _bilinear(den_a, order, k)
    b = np.concatenate([b, np.zeros(3 - len(b))]) / a[0]
    a = np.concatenate([a, np.zeros(3 - len(a))]) / a[0]
    return (float(b[0]), float(b[1]), float(b[2]), 1.0, float(a[1]), float(a[2]))


def _bilinear(poly: NDArray[np.float64], order: int, k: float) -> NDArray[np.float64]:
    """``p(K (z - 1) / (z + 1)) (z + 1)^order`` for ``p`` of degree <= ``order`` (coefficients
    highest power first, in ``s`` and in ``z``): the substitution of
    :func:`scipy.signal.bilinear` (with ``fs = K / 2``), written out because importing
    :mod:`scipy.signal` costs about 0.9 s of CPU (it imports :mod:`scipy.stats`), which every
    ``bridge`` start paid to build its washout. tests/test_cueing_filters.py checks it against
    scipy's."""
    P = np.polynomial.polynomial  # coefficients lowest power first
    out = np.zeros(order + 1)
    for power, coef in enumerate(poly[::-1]):  # coef of s**power
        term = P.polymul(P.polypow([-1.0, 1.0], power), P.polypow([1.0, 1.0], order - power))
        out += coef * k**power * term
    return out[::-1]


def soft_limit(x: float, limit: float, knee: float) -> float:
    """Smooth limiter on one float: ``x`` up to ``knee*limit``, then a tanh bend to ``limit``."""
    a = knee * limit
    ax = abs(x)
    if ax <= a:
        return x
    b = limit - a
    if b <= 0.0:
        return math.copysign(limit, x)
    return math.copysign(a + b * math.tanh((ax - a) / b), x)


def soft_limit_array(x: NDArray[np.float64], limit: float, knee: float) -> NDArray[np.float64]:
    """:func:`soft_limit` elementwise (same numbers); may return ``x`` itself when unchanged."""
    a = knee * limit
    ax = np.abs(x)
    if not ax.max(initial=0.0) > a:
        return x
    big = np.flatnonzero(ax > a)
    out = x.copy()
    xb = x[big]
    b = limit - a
    if b <= 0.0:
        out[big] = np.copysign(limit, xb)
    else:
        out[big] = np.copysign(a + b * np.tanh((ax[big] - a) / b), xb)
    return out


def compress(x: float, k: float, limit_pos: float, limit_neg: float, shape: float) -> float:
    """The compressive scaling curve on one float.

    ``y = k x / (1 + (|k x| / L)^p)^(1/p)`` with ``L = limit_pos`` for ``x > 0`` and
    ``limit_neg`` for ``x < 0``: slope ``k`` at zero (small cues pass scaled by ``k``), ``|y| <
    L`` always, ``y -> +-L`` for large ``|x|``. Strictly increasing for ``k > 0``; its
    derivative ``k (1 + (|k x|/L)^p)^(-1/p - 1)`` is continuous (and equals ``k`` at zero on
    both sides, whatever the two limits). ``p`` sets how sharp the bend is: ``p = 1`` the
    softest (``k x / (1 + |k x| / L)``), large ``p`` close to ``clip(k x, -L, L)``.

    Parameters
    ----------
    x : float
        Input (any unit).
    k : float
        Gain at zero, >= 0.
    limit_pos, limit_neg : float
        Limit of the output for positive and negative inputs (magnitudes, > 0; the output's
        unit).
    shape : float
        Exponent ``p`` >= 1.

    Returns
    -------
    float
    """
    y = k * x
    # ``float ** float`` is untyped (a negative base gives a complex); every base here is
    # > 1, so the power is a float
    soft: float
    if y > 0.0:
        soft = (1.0 + (y / limit_pos) ** shape) ** (1.0 / shape)
        return y / soft
    if y < 0.0:
        soft = (1.0 + (-y / limit_neg) ** shape) ** (1.0 / shape)
        return y / soft
    return y


def compress_array(
    x: NDArray[np.float64], k: float, limit_pos: float, limit_neg: float, shape: float
) -> NDArray[np.float64]:
    """:func:`compress` elementwise (the same operations, so the same numbers to rounding)."""
    y = k * np.asarray(x, dtype=float)
    lim = np.where(y > 0.0, limit_pos, limit_neg)
    return np.asarray(y / (1.0 + (np.abs(y) / lim) ** shape) ** (1.0 / shape))


def compress_inverse(y: float, k: float, limit_pos: float, limit_neg: float, shape: float) -> float:
    """The input ``x`` for which :func:`compress` gives ``y`` (``|y|`` below its limit, k > 0).

    Closed form: ``x = y / (k (1 - (|y|/L)^p)^(1/p))``.
    """
    lim = limit_pos if y > 0.0 else limit_neg
    r = abs(y) / lim
    if r >= 1.0:
        raise ValueError(f"|y| = {abs(y)!r} is not below the limit {lim!r}")
    soft: float = (1.0 - r**shape) ** (1.0 / shape)  # base in (0, 1]: a float power
    return y / (k * soft)


_SHORT = 24  # a segment shorter than this switches to the scalar loop
_SCALAR_RUN = 512  # samples per scalar stretch
_CALM = 6  # at most this many switches in a scalar stretch switch back to segments


def rate_limit_array(x: NDArray[np.float64], step: float, y0: float) -> NDArray[np.float64]:
    """Rate limiter over a signal: the loop of :func:`rate_limit_step`, vectorised.

    The signal is processed by segments: while the limiter is inactive the output is the
    input (found with one vectorised search over ``diff(x)``); while it is active the output
    is the ramp ``y0 + s (m + 1) step`` (``s = +-1``) until the input is within reach again.
    The ramp is computed by multiplication where the loop adds ``step`` repeatedly, so the
    two differ by rounding only (the limiter is 1-Lipschitz in its input, so rounding never
    grows into a different branch of consequence). Where the limiter switches on and off
    every few samples (a noisy target near the rate limit) the per-segment overhead would
    dominate, so such stretches run the plain loop on floats instead, and the segments
    resume when the signal calms down. Cost: linear in the length.

    Parameters
    ----------
    x : (N,) array
        Target signal (finite).
    step : float
        Largest change per sample (rate limit / fs), > 0.
    y0 : float
        Output before the first sample.

    Returns
    -------
    (N,) array
    """
    n = x.shape[0]
    y = np.empty(n)
    if n == 0:
        return y
    jumps = np.flatnonzero(np.abs(np.diff(x)) > step) + 1  # |x[j] - x[j-1]| > step
    ramp = np.arange(1, n + 1) * step  # ramp[m] = (m + 1) step
    prev = y0
    i = 0
    while i < n:
        diff = x[i] - prev
        start = i
        if -step <= diff <= step:
            # tracking from i: y = x until the next jump
            k = int(np.searchsorted(jumps, i, side="right"))
            j = int(jumps[k]) if k < len(jumps) else n
            y[i:j] = x[i:j]
            prev = float(x[j - 1])
            i = j
        else:
            # ramping from i: continue at i + m while s (x[i+m] - prev) > (m + 1) step
            s = 1.0 if diff > 0.0 else -1.0
            lo = i
            window = 256
            while True:
                hi = min(n, lo + window)
                if s > 0.0:
                    reach = (x[lo:hi] - prev) - ramp[lo - i : hi - i]
                else:
                    reach = (prev - x[lo:hi]) - ramp[lo - i : hi - i]
                stops = reach <= 0.0
                k = int(np.argmax(stops))
                if stops[k] or hi == n:
                    stop = (lo - i) + (k if stops[k] else hi - lo)
                    y[i : i + stop] = prev + s * ramp[:stop]
                    prev = prev + s * float(ramp[stop - 1])
                    i += stop
                    break
                lo = hi
                window *= 4
        while i - start < _SHORT and i < n:
            # choppy: the scalar loop until the limiter stops switching so often
            start = i
            end = min(n, i + _SCALAR_RUN)
            out = []
            switches = 0
            active = False
            for v in x[i:end].tolist():
                d = v - prev
                if d > step:
                    prev = prev + step
                    switches += not active
                    active = True
                elif d < -step:
                    prev = prev - step
                    switches += not active
                    active = True
                else:
                    prev = v
                    switches += active
                    active = False
                out.append(prev)
            y[i:end] = out
            i = end
            if switches <= _CALM:
                break
    return y


def rate_limit_step(x: float, prev: float, step: float) -> float:
    """One rate-limiter sample: ``x`` if within ``step`` of ``prev``, else ``prev +- step``."""
    d = x - prev
    if d > step:
        return prev + step
    if d < -step:
        return prev - step
    return x
