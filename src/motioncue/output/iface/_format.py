"""The interface-string format of SimTools and FlyPT Mover: a template turned into bytes.

A template is text with tokens in angle brackets:

- ``<Axis1a>`` ... ``<Axis9c>``: an axis value (the ``a``, ``b`` and ``c`` sets of the
  tools' axis assignments); which motor axis each token carries is the controller's
  ``axes`` list;
- ``<255>``: one literal byte given in decimal (0-255), for bytes that are not text;
- any other character: itself, one byte (Latin-1).

An axis value is an unsigned integer of the output's bit range (8-16 bits,
``0 .. 2**bits - 1``), written as

- ``binary``: one byte for 8 bits, else two bytes, most significant first (big-endian);
- ``hex``: upper-case hexadecimal text, zero-padded to ``ceil(bits / 4)`` digits;
- ``decimal``: decimal text without padding.

Start and stop strings use the same syntax without axis tokens. Nothing here reads bytes
back: the emulators parse the stream as each board's firmware does (``_boards``).
"""

from __future__ import annotations

import math
import re
import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from ..._errors import ConfigError, ProtocolError
from ..._frozen import set_fields

__all__ = ["ENCODINGS", "FrameFormatter", "InterfaceFormat", "literal_bytes", "parse_template"]

ENCODINGS = ("binary", "hex", "decimal")
_TOKEN = re.compile(r"<([^<>]*)>")
_AXIS = re.compile(r"Axis[1-9][abc]")


def parse_template(template: str, what: str = "template") -> list[bytes | str]:
    """Split a template into literal bytes and axis token names, in order.

    Raises
    ------
    ConfigError
        An unknown token, an unclosed ``<``, a byte above 255 or a non-Latin-1 character.
    """
    parts: list[bytes | str] = []
    pos = 0
    for m in _TOKEN.finditer(template):
        parts.append(_text(template[pos : m.start()], what))
        body = m.group(1)
        if _AXIS.fullmatch(body):
            parts.append(body)
        elif body.isdigit() and int(body) <= 255:
            parts.append(bytes((int(body),)))
        else:
            raise ConfigError(
                f"{what} {template!r}: token <{body}> is invalid; allowed: <Axis1a> .. "
                "<Axis9c> or a byte <0> .. <255>"
            )
        pos = m.end()
    parts.append(_text(template[pos:], what))
    merged: list[bytes | str] = []
    for p in parts:
        if isinstance(p, bytes) and merged and isinstance(merged[-1], bytes):
            merged[-1] = merged[-1] + p
        elif p != b"":
            merged.append(p)
    return merged


def _text(s: str, what: str) -> bytes:
    if "<" in s or ">" in s:
        raise ConfigError(f"{what}: unmatched '<' or '>' in {s!r}; allowed: <token>")
    try:
        return s.encode("latin-1")
    except UnicodeEncodeError:
        raise ConfigError(
            f"{what}: {s!r} has a character outside Latin-1 (one byte each)"
        ) from None


def literal_bytes(template: str, what: str) -> bytes:
    """A start or stop string's bytes (no axis tokens allowed)."""
    parts = parse_template(template, what)
    if any(isinstance(p, str) for p in parts):
        raise ConfigError(f"{what} {template!r}: axis tokens are not allowed here")
    return b"".join(p for p in parts if isinstance(p, bytes))


@dataclass(frozen=True)
class InterfaceFormat:
    """One output string: template, axes, bit range and encoding (module docstring).

    Parameters
    ----------
    template : str
    axes : sequence of str
        Token name carried by each motor axis, in motor-axis order (``("Axis1a", ...)``);
        every token of the template must be one of them and every axis must appear.
    bits : int
        Bit range, 8 .. 16.
    encoding : str
        ``binary``, ``hex`` or ``decimal``.
    """

    template: str
    axes: tuple[str, ...]
    bits: int
    encoding: str
    _parts: tuple[bytes | str, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if (
            isinstance(self.bits, bool)
            or not isinstance(self.bits, int)
            or not 8 <= self.bits <= 16
        ):
            raise ConfigError(f"bits = {self.bits!r} is invalid; allowed: an integer in [8, 16]")
        if self.encoding not in ENCODINGS:
            raise ConfigError(
                f"encoding = {self.encoding!r} is invalid; allowed: {' | '.join(ENCODINGS)}"
            )
        axes = tuple(self.axes)
        if not axes or len(set(axes)) != len(axes) or not all(_AXIS.fullmatch(a) for a in axes):
            raise ConfigError(
                f"axes = {list(axes)!r} is invalid; allowed: distinct tokens Axis1a .. Axis9c"
            )
        parts = tuple(parse_template(self.template))
        used = {p for p in parts if isinstance(p, str)}
        unknown = used - set(axes)
        if unknown:
            raise ConfigError(
                f"template {self.template!r}: tokens {sorted(unknown)} are not among "
                f"axes {list(axes)}"
            )
        missing = [a for a in axes if a not in used]
        if missing:
            raise ConfigError(f"template {self.template!r}: axes {missing} never sent")
        set_fields(self, axes=axes, _parts=parts)

    @property
    def full_scale(self) -> int:
        """Largest axis value, ``2**bits - 1``."""
        return (1 << self.bits) - 1

    @property
    def n_axes(self) -> int:
        return len(self.axes)

    def value_bytes(self) -> int:
        """Most bytes one axis value takes."""
        if self.encoding == "binary":
            return 1 if self.bits <= 8 else 2
        if self.encoding == "hex":
            return math.ceil(self.bits / 4)
        return len(str(self.full_scale))

    def max_frame_bytes(self) -> int:
        """Most bytes one frame takes on the wire."""
        return sum(len(p) if isinstance(p, bytes) else self.value_bytes() for p in self._parts)

    def encoder(self) -> FrameFormatter:
        """A fast formatter of this string (values in motor-axis order -> bytes)."""
        return FrameFormatter(self)


class FrameFormatter:
    """Formats frames of one :class:`InterfaceFormat` (precompiled: ``struct`` for binary,
    ``%`` formatting for text).

    :meth:`format` checks its values; :meth:`format_unchecked` is for callers that have
    checked them already (the run encoder does, once per frame).
    """

    __slots__ = ("_full", "_n", "_plan", "_struct_pack", "_text", "_text_order")

    def __init__(self, f: InterfaceFormat) -> None:
        index = {a: i for i, a in enumerate(f.axes)}
        self._n = f.n_axes
        self._full = f.full_scale
        order = tuple(index[p] for p in f._parts if isinstance(p, str))
        self._text_order = None if order == tuple(range(self._n)) else order
        # (literal, -1) or (None, motor axis): the struct arguments in order
        self._plan = tuple((p, -1) if isinstance(p, bytes) else (b"", index[p]) for p in f._parts)
        if f.encoding == "binary":
            code = "B" if f.bits <= 8 else "H"
            fmt = ">" + "".join(f"{len(p)}s" if isinstance(p, bytes) else code for p in f._parts)
            self._struct_pack: Callable[..., bytes] | None = struct.Struct(fmt).pack
            self._text = b""
        else:
            spec = f"%0{math.ceil(f.bits / 4)}X" if f.encoding == "hex" else "%d"
            self._text = b"".join(
                p.replace(b"%", b"%%") if isinstance(p, bytes) else spec.encode() for p in f._parts
            )
            self._struct_pack = None

    def format(self, values: Sequence[int]) -> bytes:
        """The bytes of one frame carrying ``values`` (one per motor axis, ints in range).

        Raises
        ------
        ProtocolError
            Wrong count or a value outside ``0 .. 2**bits - 1`` (nothing is written).
        """
        if len(values) != self._n:
            raise ProtocolError(f"{len(values)} values for a {self._n}-axis interface string")
        if min(values) < 0 or max(values) > self._full:
            bad = next(v for v in values if not 0 <= v <= self._full)
            raise ProtocolError(f"axis value {bad} outside the bit range [0, {self._full}]")
        return self.format_unchecked([int(v) for v in values])

    def format_unchecked(self, values: Sequence[int]) -> bytes:
        """:meth:`format` without the checks (``values``: ints, count and range checked)."""
        pack = self._struct_pack
        if pack is not None:  # binary
            return pack(*[v if i < 0 else values[i] for v, i in self._plan])
        order = self._text_order
        args = values if order is None else tuple([values[i] for i in order])
        if type(args) is not tuple:
            args = tuple(args)
        return self._text % args
