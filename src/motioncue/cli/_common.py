"""Options several verbs share, defined once so that one concept has one name everywhere.

* The shared options as data (:class:`~motioncue.cli._verb.Option`), which a verb lists in
  its :class:`~motioncue.cli._verb.Verb` (or derives its variant of with ``.but``):
  :data:`PLATFORM`, :data:`CONTROLLER` (:data:`RIG`: both), :data:`LIMITS`, :data:`RATE`
  (:data:`CHECKED_RATE`), :data:`RECORDING`, :data:`PRESET`, :data:`OUT`, :data:`TARGET`,
  :data:`DURATION`, :data:`PLOT`, :data:`REPORT`, :data:`QUIET`, :data:`SPEED`;
  :func:`json_option`, :func:`set_option`.
* :func:`add_deprecated_alias`: an old spelling (``cue --fs``, ``record --seconds``) kept as a
  hidden option that still works and prints a one-line deprecation note.
* :func:`print_json`: the result of a verb's ``--json`` (:func:`json_option`).
* :func:`limits_for`: the rig's actuator limits with the overrides of :data:`LIMITS`
  (``--max-speed``, ``--max-accel``, ``--max-jerk``, ``--stroke-margin``) applied;
  :func:`load_rig`: the rig a verb drives (platform, controller, limits).
* :func:`set_option`, :func:`load_platform_arg`, :func:`load_preset_arg`:
  ``--set platform.SECTION.KEY=VALUE`` and ``--set preset.SECTION.KEY=VALUE`` overrides,
  validated exactly like the file (an unknown key is refused with its name).
* :func:`say`, :func:`status_line`: a line on stderr that a closed terminal does not turn
  into a failure.

Building a parser imports nothing heavy: the loaders are imported when a verb runs.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import tomllib
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO, TypeAlias, TypeVar

from .._errors import ConfigError
from ._verb import Allowed, Option

if TYPE_CHECKING:
    from ..cueing import CueingParams
    from ..kinematics import Platform
    from ..output import Controller
    from ..trajectory import ActuatorLimits

__all__ = [
    "CHECKED_RATE",
    "CONTROLLER",
    "DURATION",
    "LIMITS",
    "OUT",
    "PLATFORM",
    "PLOT",
    "PRESET",
    "QUIET",
    "RATE",
    "RECORDING",
    "REPORT",
    "RIG",
    "SET_TARGETS",
    "SPEED",
    "TARGET",
    "Subparsers",
    "add_deprecated_alias",
    "apply_overrides",
    "cue_rate_line",
    "json_option",
    "limits_for",
    "load_platform_arg",
    "load_preset_arg",
    "load_rig",
    "load_snapped_rig",
    "parse_set",
    "print_json",
    "say",
    "set_option",
    "status_line",
]

SET_TARGETS = ("platform", "preset")
"""The files ``--set`` can override, named by the first word of its key."""

Subparsers: TypeAlias = "argparse._SubParsersAction[argparse.ArgumentParser]"
"""What each verb module's ``register(sub)`` is given: the verbs' ``add_parser``."""

TomlValue: TypeAlias = object
"""A value parsed from TOML text (``--set``): stored, checked by the file's loader."""

_Loaded = TypeVar("_Loaded")


class _DeprecatedAlias(argparse.Action):
    """Store like the new option, after a one-line note on stderr naming the new spelling."""

    def __init__(self, option_strings: Sequence[str], dest: str, **kwargs: Any) -> None:
        self.new_name: str = kwargs.pop("new_name")
        super().__init__(option_strings, dest, **kwargs)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: object,
        option_string: str | None = None,
    ) -> None:
        print(
            f"{parser.prog}: note: {option_string} is deprecated; use {self.new_name}",
            file=sys.stderr,
        )
        setattr(namespace, self.dest, values)


def add_deprecated_alias(
    parser: argparse.ArgumentParser, old: str, new: str, *, type: Callable[[str], object] = str
) -> None:
    """Accept ``old`` as a hidden spelling of the option ``new`` (same destination).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The verb's parser; ``new`` must already be defined on it.
    old, new : str
        Option strings, e.g. ``"--fs"`` and ``"--rate"``.
    type : callable
        The conversion of the new option (argparse ``type``).
    """
    dest = new.lstrip("-").replace("-", "_")
    parser.add_argument(
        old, dest=dest, type=type, action=_DeprecatedAlias, new_name=new, help=argparse.SUPPRESS
    )


def json_option(what: str = "the result") -> Option:
    """``--json``: print ``what`` as one JSON document on stdout instead of text."""
    return Option.of(
        "--json", action="store_true", help=f"print {what} as JSON on stdout instead of text"
    )


def print_json(data: object, *, best_effort: bool = False) -> None:
    """Print ``data`` as JSON (``NaN`` refused: the output is strict JSON).

    ``best_effort=True``: a failure to print (a stdout gone with the terminal, a value JSON
    cannot hold) is ignored, for the summary printed once the platform is parked, which must
    not turn a parked exit into a traceback.
    """
    try:
        print(json.dumps(data, indent=1, allow_nan=False, default=str))
    except (OSError, ValueError):
        if not best_effort:
            raise


def say(line: str, stream: TextIO | None = None) -> None:
    """One line on ``stream`` (default stderr), flushed; a terminal that is gone (SIGHUP)
    does not stop the program."""
    try:
        print(line, file=sys.stderr if stream is None else stream, flush=True)
    except (OSError, ValueError):
        pass


def cue_rate_line(algorithm: str, cue_hz: float, rate_hz: float, what: str) -> str:
    """What ``generate`` and ``cue`` say when a plan ran below their rate (``what``: the
    frames or the poses at ``rate_hz``)."""
    return (
        f"{algorithm} plans at {cue_hz:g} Hz (its highest rate); the {rate_hz:g} Hz {what} "
        "follow a cubic spline through its poses"
    )


def status_line(line: str, tty: bool) -> None:
    """A status line on stderr: rewritten in place on a terminal (``tty``), one line each
    otherwise (a log); a terminal that is gone does not stop the program."""
    try:
        if tty:
            sys.stderr.write("\r" + line + "\x1b[K")
        else:
            sys.stderr.write(line + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass


PLATFORM = Option.of("--platform", required=True, help="bundled platform name or TOML path")
"""``--platform``: the platform a verb works on (verbs where it is optional derive theirs)."""

CONTROLLER = Option.of("--controller", required=True, help="bundled controller name or TOML path")
"""``--controller``: the controller that drives the platform."""

RIG = (PLATFORM, CONTROLLER)
"""``--platform`` and ``--controller``, both required: the rig a verb works on."""

LIMITS = (
    Option.of("--max-speed", type=float, help="speed limit, m/s (rad/s for cranks)"),
    Option.of("--max-accel", type=float, help="acceleration limit, m/s^2 (rad/s^2)"),
    Option.of("--max-jerk", type=float, help="jerk limit, m/s^3 (rad/s^3)"),
    Option.of("--stroke-margin", type=float, help="extra margin at each stroke end, m (rad)"),
)
"""The actuator-limit overrides; the smallest of these, the platform's and the controller's
value wins (see ``motioncue limits`` and :func:`limit_overrides`)."""

RATE = Option.of("--rate", type=float, default=100.0, metavar="HZ", help="frame rate")
"""``--rate HZ``: the frame rate (default 100 Hz)."""

CHECKED_RATE = RATE.but(
    help="frame rate, checked against the controller (default 100)",
    allowed=Allowed(0.0, 1000.0, unit="Hz"),
)
"""``--rate HZ`` of the analysis verbs (compare, omct), in (0, 1000] Hz."""

RECORDING = Option.of(
    "--input",
    required=True,
    metavar="REC",
    help="recording CSV (t,fx,fy,fz,wx,wy,wz) or a 'motioncue record' .mctr file",
)
"""``--input REC``: a recording of vehicle motion."""

PRESET = Option.of(
    "--preset",
    default=None,
    metavar="NAME",
    help="cueing preset name or .toml path (default: the platform's default_preset)",
)
"""``--preset NAME``: the cueing preset (default: the platform's)."""

OUT = Option.of("--out", required=True)
"""``--out``: the file a verb writes (each verb names it with its metavar and help)."""

TARGET = Option.of(
    "--target",
    default=None,
    metavar="URL",
    help="udp://HOST:PORT, serial://..., pcap:PATH or file:PATH (default: the controller's "
    "default target)",
)
"""``--target URL``: where a controller's bytes go."""

DURATION = Option.of(
    "--duration",
    type=float,
    default=None,
    metavar="S",
    help="stop after S seconds (default: until Ctrl-C)",
)
"""``--duration S``: how long a verb that runs until stopped runs."""

PLOT = Option.of("--plot", metavar="FILE.png")
"""``--plot FILE.png``: a plot of the result (each verb says which)."""

REPORT = Option.of("--report", metavar="DIR")
"""``--report DIR``: a folder of plots and metrics."""

QUIET = Option.of("--quiet", action="store_true", help="no progress lines")
"""``--quiet``: no progress or status lines on stderr."""

SPEED = Option.of("--speed", type=float, help="pacing factor")
"""``--speed X``: pacing factor against real time."""


def limit_overrides(args: argparse.Namespace) -> dict[str, float | None]:
    """The keyword arguments of ``ActuatorLimits.from_platform`` set by
    :data:`LIMITS` (which every verb that calls it declares: each is None when not given)."""
    return {
        "stroke_margin": args.stroke_margin,
        "v_max": args.max_speed,
        "a_max": args.max_accel,
        "j_max": args.max_jerk,
    }


def limits_for(
    args: argparse.Namespace,
    platform: Platform,
    controller: Controller | None,
    rate_hz: float | None,
) -> ActuatorLimits:
    """The rig's :class:`~motioncue.trajectory.ActuatorLimits` at ``rate_hz`` (Hz), with the
    overrides of :data:`LIMITS` (:func:`limit_overrides`) applied."""
    from ..trajectory import ActuatorLimits

    return ActuatorLimits.from_platform(
        platform, controller, rate_hz=rate_hz, **limit_overrides(args)
    )


def load_rig(
    args: argparse.Namespace, rate_hz: float
) -> tuple[Platform, Controller, ActuatorLimits]:
    """The rig of ``--platform`` (with the ``--set`` overrides), ``--controller`` (checked
    to run frames at ``rate_hz``, Hz) and the actuator limits there (:func:`limits_for`)."""
    platform, controller, _rate_hz, limits = _load_rig(args, rate_hz, snap=False)
    return platform, controller, limits


def load_snapped_rig(
    args: argparse.Namespace,
) -> tuple[Platform, Controller, float, ActuatorLimits]:
    """:func:`load_rig` at ``--rate`` snapped to the controller's clock (the nearest rate it
    runs frames at): platform, controller, that rate (Hz), limits."""
    return _load_rig(args, args.rate, snap=True)


def _load_rig(
    args: argparse.Namespace, rate_hz: float, *, snap: bool
) -> tuple[Platform, Controller, float, ActuatorLimits]:
    from ..output import load_controller
    from ..output._controller_api import snap_rate_hz

    platform = load_platform_arg(args.platform, args.overrides)
    controller = load_controller(args.controller)
    if snap:
        rate_hz = snap_rate_hz(rate_hz, controller)
    controller.check_rate(rate_hz)
    return platform, controller, rate_hz, limits_for(args, platform, controller, rate_hz)


def set_option(targets: Sequence[str] = SET_TARGETS) -> Option:
    """``--set TARGET.SECTION.KEY=VALUE`` (repeatable), TARGET one of ``targets``."""
    names = " or ".join(targets)
    example = (
        "platform.stroke.margin_mm=5" if "platform" in targets else "preset.scaling.soft_knee=0.5"
    )
    return Option.of(
        "--set",
        action="append",
        default=[],
        dest="overrides",
        metavar="TARGET.SECTION.KEY=VALUE",
        help=f"override one key of the {names} file (TARGET: {', '.join(targets)}; VALUE in "
        f"TOML syntax, e.g. {example}); checked like the file; repeatable",
    )


def parse_set(item: str) -> tuple[str, tuple[str, ...], TomlValue]:
    """Split one ``--set`` item into its target, key path and TOML value.

    Returns
    -------
    target : str
        ``"platform"`` or ``"preset"``.
    path : tuple of str
        Keys below the file's top level, e.g. ``("stroke", "margin_mm")``.
    value
        The value parsed as TOML (``5``, ``[1.0, 2.0]``, ``"text"``); a bare word that is
        not TOML is taken as a string.

    Raises
    ------
    ConfigError
        No ``=``, no key, or an unknown target.
    """
    key, sep, text = item.partition("=")
    parts = tuple(p.strip() for p in key.split("."))
    if not sep or len(parts) < 2 or not all(parts):
        raise ConfigError(
            f"--set {item!r} is invalid; allowed: TARGET.SECTION.KEY=VALUE with TARGET one of "
            f"{', '.join(SET_TARGETS)} (e.g. platform.stroke.margin_mm=5)"
        )
    if parts[0] not in SET_TARGETS:
        raise ConfigError(
            f"--set {item!r}: unknown target {parts[0]!r}; allowed: {', '.join(SET_TARGETS)}"
        )
    try:
        value: TomlValue = tomllib.loads(f"v = {text.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = text.strip()
    return parts[0], parts[1:], value


def apply_overrides(
    data: dict[str, Any], items: Sequence[tuple[tuple[str, ...], TomlValue]]
) -> None:
    """Set each key path of ``items`` in the nested tables of ``data`` (in place).

    A missing table on the way is created, so that an optional table can be given; a key
    that is not a table where one is needed is refused. Unknown keys are left to the file's
    own loader, which refuses them by name.
    """
    for path, value in items:
        table = data
        for i, part in enumerate(path[:-1]):
            nxt = table.setdefault(part, {})
            if not isinstance(nxt, dict):
                raise ConfigError(
                    f"--set {'.'.join(path)}: {'.'.join(path[: i + 1])} is a value, not a table"
                )
            table = nxt
        table[path[-1]] = value


def _overrides_for(
    target: str, overrides: Sequence[str] | None
) -> list[tuple[tuple[str, ...], TomlValue]]:
    out = []
    for item in overrides or ():
        tgt, path, value = parse_set(item)
        if tgt == target:
            out.append((path, value))
    return out


def check_set_targets(overrides: Sequence[str] | None, targets: Sequence[str]) -> None:
    """Refuse a ``--set`` whose target this verb does not load."""
    for item in overrides or ():
        tgt = parse_set(item)[0]
        if tgt not in targets:
            raise ConfigError(
                f"--set {item!r}: this command loads no {tgt} file; allowed targets: "
                f"{', '.join(targets)}"
            )


def _overridden_copy(
    kind: str, name_or_path: str, items: Sequence[tuple[tuple[str, ...], TomlValue]], folder: Path
) -> Path:
    """The config file with ``items`` applied, written under ``folder`` with the same name
    (so the loaded object keeps its name)."""
    import tomli_w

    from .._config import find_config, load_toml

    src = find_config(kind, name_or_path)
    data = load_toml(src)
    apply_overrides(data, items)
    dst = folder / src.name
    with open(dst, "wb") as fh:
        tomli_w.dump(data, fh)
    return dst


def _load_with_overrides(
    load: Callable[[str | Path], _Loaded],
    kind: str,
    folder: str,
    name_or_path: str,
    overrides: Sequence[str] | None,
) -> _Loaded:
    """``load(name_or_path)``, or ``load`` of a copy with the ``kind.`` items of ``--set``."""
    items = _overrides_for(kind, overrides)
    if not items:
        return load(name_or_path)
    with tempfile.TemporaryDirectory(prefix="motioncue-set-") as tmp:
        path = _overridden_copy(folder, name_or_path, items, Path(tmp))
        try:
            return load(path)
        except ConfigError as exc:
            raise ConfigError(f"--set: {exc}") from exc


def load_platform_arg(name_or_path: str, overrides: Sequence[str] | None = None) -> Platform:
    """:func:`motioncue.kinematics.load_platform` with the ``platform.`` items of ``--set``."""
    from ..kinematics import load_platform

    return _load_with_overrides(load_platform, "platform", "platforms", name_or_path, overrides)


def load_preset_arg(name_or_path: str, overrides: Sequence[str] | None = None) -> CueingParams:
    """:func:`motioncue.cueing.load_cueing` with the ``preset.`` items of ``--set``."""
    from ..cueing import load_cueing

    return _load_with_overrides(load_cueing, "preset", "cueing", name_or_path, overrides)
