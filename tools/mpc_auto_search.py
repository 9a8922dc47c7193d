"""Issue 20, ``mpc``: a model-predictive preset at least 1.15x the classical default's shares.

A (1+2) random local search (:func:`_local_search.one_plus_two`, as
``tools/classical_forward_ratio_search.py``) over keys of an ``algorithm = "mpc"`` preset
(its ``[mpc]`` table and the ``[tilt]`` keys of the classical washout whose pose the plan's
``w_prior`` starts from), each candidate through the chain of ``motioncue compare``
(:func:`motioncue.analysis.run_chain`, then :func:`motioncue.cueing._metrics.cue_metrics`)
on whole tuning drives at 100 Hz, ``stewart6-linear`` with ``mbox6``: the bundled
chicane-gt, street-formula and flowing-road and the four generated tuning drives of
``configs/recordings/generated.toml`` (not bundled; written into ``build/drives/`` first)::

    python tools/make_generated_drives.py --set tuning

Never the held-out drives (configs/recordings/flowing-formula.csv, forest-rally.csv, lap.csv).

Objective. The reference is ``racing-hexapod-auto`` (the platform's default), measured on
every drive at the start (not hard-coded). On every drive the candidate must meet: corr fx
>= 0.955, corr fy >= 0.91, reversals <= 1.8 %, all false cues <= 13 %, clamped <= 1 %, no
frame changed by the actuator limiter (issue 20's acceptance 0.95 / 0.90 / 2 % / 15 % with a
margin for the held-out drives), and its strength ratio at least ``--min-ratio`` (default 1.0:
a plan weaker than the default is not a way out of the false-cue budget). Maximised: the
smallest over the drives of ``min(share_fx / auto_fx, share_fy / auto_fy)`` (issue 20 asks
1.15x in fx and fy on every drive; the target here is 1.2). Deb's rule: a candidate that
violates the constraints less is better; among those meeting them all, the stronger.

The preset: ``--base`` (an ``mpc`` preset TOML) with the searched keys replaced; written to
``--out`` at every improvement, with the drives' figures as a comment. ``--eval`` measures
the given presets (the reference first) and stops, for exploring by hand. Each candidate is
7 whole drives (about 50 s of CPU, 25-30 s on 2 processes, ``--workers``). The wall-clock
budget decides where the search stops; the seed gives the sequence of candidates.
``configs/cueing/mpc-hexapod-auto.toml`` was made (session 30, after about 30 candidates by
hand with ``--eval`` and a first search whose result is in :data:`BASE_KEYS`) by::

    python tools/mpc_auto_search.py --write-base start.toml
    python tools/mpc_auto_search.py --base start.toml --out mpc-hexapod-auto.toml \
        --budget-s 1800 --seed 2 --sigma 0.15 \
        --coords fz_use wvy tcy wprior_roll wprior_pitch cx reach ky

(about 35 rounds; its header, written by hand, holds the figures). No candidate met every
constraint: fy stays at 0.97-0.98x the default's on chicane-formula-106 and street-formula
(the roll the plan may hold without fz reversals binds; see the preset's header).
"""

from __future__ import annotations

import argparse
import math
import re
import time
import tomllib
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from _local_search import one_plus_two

from motioncue.analysis import run_chain
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0
REFERENCE = "racing-hexapod-auto"
DRIVES = (
    "configs/recordings/chicane-gt.csv",
    "configs/recordings/street-formula.csv",
    "configs/recordings/flowing-road.csv",
    "build/drives/chicane-formula-106.csv",
    "build/drives/flowing-formula-107.csv",
    "build/drives/flowing-gt-303.csv",
    "build/drives/forest-rally-108.csv",
)
HELD_OUT = ("flowing-formula.csv", "forest-rally.csv", "lap.csv")
MIN_CORR = (0.955, 0.91)
MAX_REVERSALS = 0.018
MAX_FALSE = 0.13
MAX_CLAMPED = 0.01


@dataclass(frozen=True)
class Figures:
    """One preset's figures on one drive."""

    drive: str
    share: tuple[float, float]
    corr: tuple[float, float]
    reversals: float
    false_any: float
    clamped: float
    limited: int
    false_cues: tuple[float, ...]

    def line(self, ref: Figures | None = None) -> str:
        """One line: shares (ratios to ``ref``), corr, reversals, false cues, clamped, L."""
        ratio = ""
        if ref is not None:
            ratio = f" ({self.share[0] / ref.share[0]:.2f}x/{self.share[1] / ref.share[1]:.2f}x)"
        fc = " ".join(f"{100 * v:.1f}" for v in self.false_cues)
        return (
            f"{Path(self.drive).stem:20s} {self.share[0]:.3f}/{self.share[1]:.3f}{ratio} "
            f"corr {self.corr[0]:.3f}/{self.corr[1]:.3f} rev {100 * self.reversals:.2f} "
            f"false {100 * self.false_any:.1f} cl {100 * self.clamped:.2f} L{self.limited} "
            f"[{fc}]"
        )


# (label, section, key, index or None, lo, hi): one searched coordinate, in log space.
Coord = tuple[str, str, str, int | None, float, float]
COORDS: tuple[Coord, ...] = (
    ("kx", "mpc", "ref_scale", 0, 0.05, 0.5),
    ("ky", "mpc", "ref_scale", 1, 0.1, 0.8),
    ("cx", "mpc", "ref_adapt_peak_m_s2", 0, 0.5, 6.0),
    ("tau", "mpc", "ref_adapt_tau_s", None, 5.0, 300.0),
    ("wvx", "mpc", "w_vehicle", 0, 0.005, 0.5),
    ("wvy", "mpc", "w_vehicle", 1, 0.005, 0.5),
    ("wacc_rp", "mpc", "w_acc", 3, 0.02, 20.0),
    ("werr_rp", "mpc", "w_error", 3, 0.1, 10.0),
    ("wprior_roll", "mpc", "w_prior", 3, 100.0, 3e5),
    ("wprior_pitch", "mpc", "w_prior", 4, 100.0, 3e5),
    ("guard_x", "mpc", "sign_guard", 0, 0.2, 3.0),
    ("guard_y", "mpc", "sign_guard", 1, 0.2, 3.0),
    ("shape", "mpc", "ref_shape", None, 1.0, 20.0),
    ("reach", "mpc", "ref_reach_use", None, 0.5, 1.0),
    ("fz_use", "mpc", "tilt_fz_use", None, 0.4, 1.0),
    ("rate", "mpc", "tilt_rate_limit_deg_s", None, 15.0, 40.0),
    ("tcx", "tilt", "adapt_peak_m_s2", 0, 0.3, 5.0),
    ("tcy", "tilt", "adapt_peak_m_s2", 1, 0.3, 5.0),
)
# Coordinates tied to another: the pitch entries of these [mpc] vectors follow roll's (index 3
# is roll, 4 pitch; the searched value is written to both).
TIED = {("mpc", "w_acc", 3): 4, ("mpc", "w_error", 3): 4}


# The search's start (``--write-base``): racing-hexapod-auto's classical tables (the fallback,
# and the pose the plan's w_prior starts from) with mpc-hexapod's [mpc] table, heave and yaw
# not moved, and these keys, chosen by hand on the tuning drives (about 30 candidates with
# --eval; the measurements are in configs/cueing/mpc-hexapod-auto.toml's header) and by a
# first search (--coords cx wprior_roll wprior_pitch fz_use wvy tcx tcy werr_rp reach
# --sigma 0.2 --seed 1, stopped after 13 rounds: the values with many digits).
BASE_KEYS: dict[tuple[str, str], object] = {
    ("tilt", "adapt_peak_m_s2"): [1.0611884024844644, 2.0501397430318784],
    ("mpc", "ref_scale"): [0.2, 0.3, 1.0, 1.0, 1.0, 1.0],
    ("mpc", "ref_adapt_peak_m_s2"): [1.24054995159044, 0.0],
    ("mpc", "ref_adapt_tau_s"): 60.0,
    ("mpc", "ref_adapt_start_m_s2"): 22.0,
    ("mpc", "w_error"): [1.0, 1.0, 0.3, 0.10000000000000002, 0.10000000000000002, 0.3],
    ("mpc", "w_prior"): [10000.0, 10000.0, 0.0, 21572.9, 3000.0, 0.0],
    ("mpc", "w_vehicle"): [0.0, 0.02328096742484071, 0.0, 0.0, 0.0, 0.0],
    ("mpc", "tilt_fz_use"): 0.6006923675448235,
}


def base_text(root: Path) -> str:
    """The search's start preset (TOML text; see :data:`BASE_KEYS`)."""
    classical = (root / "configs/cueing/racing-hexapod-auto.toml").read_text()
    mpc = (root / "configs/cueing/mpc-hexapod.toml").read_text()
    keep = [ln for ln in classical.splitlines() if not ln.startswith("#")]
    cut = next(i for i, ln in enumerate(keep) if ln.startswith("[intensity."))
    text = "\n".join(keep[:cut]).rstrip() + "\n\n"
    table = [ln for ln in mpc.splitlines() if not ln.startswith("#")]
    text += "\n".join(table[table.index("[mpc]") :]).rstrip() + "\n"
    text = text.replace('algorithm = "classical"', 'algorithm = "mpc"')
    text = re.sub(r"(?m)^dofs = .*$", 'dofs = ["x", "y", "roll", "pitch"]', text)
    return edit_toml(text, BASE_KEYS)


def _fmt(v: object) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    if isinstance(v, float):
        return repr(v)
    return repr(v) if not isinstance(v, str) else f'"{v}"'


def edit_toml(text: str, values: dict[tuple[str, str], object]) -> str:
    """``text`` with ``[section] key = value`` set for each item (added if absent)."""
    lines = text.splitlines()
    for (section, key), value in values.items():
        start = next(i for i, ln in enumerate(lines) if ln.strip() == f"[{section}]")
        end = next(
            (i for i in range(start + 1, len(lines)) if lines[i].startswith("[")), len(lines)
        )
        new = f"{key} = {_fmt(value)}"
        for i in range(start + 1, end):
            if re.match(rf"{re.escape(key)}\s*=", lines[i]):
                lines[i] = new
                break
        else:
            while end > start + 1 and not lines[end - 1].strip():
                end -= 1
            lines.insert(end, new)
    out = "\n".join(lines) + "\n"
    tomllib.loads(out)
    return out


def point_values(
    base: dict[str, dict[str, object]], coords: Sequence[Coord], x: np.ndarray
) -> dict[tuple[str, str], object]:
    """The TOML values of the point ``x`` (log space) of ``coords`` over the ``base`` tables
    (the other entries of a vector stay the base's)."""
    out: dict[tuple[str, str], object] = {}
    for (_, section, key, idx, _, _), xv in zip(coords, x, strict=True):
        v = float(math.exp(xv))
        if idx is None:
            out[(section, key)] = v
            continue
        cur = out.get((section, key))
        if cur is None:
            raw = base[section].get(key)
            cur = list(raw) if isinstance(raw, list) else [0.0] * (6 if section == "mpc" else 2)
            if key == "ref_adapt_peak_m_s2":
                cur = cur[:2]
        assert isinstance(cur, list)
        cur[idx] = v
        tied = TIED.get((section, key, idx))
        if tied is not None:
            cur[tied] = v
        out[(section, key)] = cur
    return out


def start_point(base: dict[str, dict[str, object]]) -> np.ndarray:
    """The base preset's values of the searched coordinates (clipped into their bounds)."""
    x = []
    for _, section, key, idx, lo, hi in COORDS:
        raw = base[section].get(key)
        v = raw[idx] if isinstance(raw, list) and idx is not None else raw
        v = float(v) if isinstance(v, int | float) and v > 0 else lo
        x.append(math.log(min(max(v, lo), hi)))
    return np.array(x)


_CHAIN: dict[str, Any] = {}  # per process: the platform, its limits, the drives read


def measure(job: tuple[str, str]) -> Figures:
    """Figures of one preset (bundled name or TOML path) on one drive."""
    preset, drive = job
    if not _CHAIN:
        platform = load_platform("stewart6-linear")
        _CHAIN["platform"] = platform
        _CHAIN["limits"] = ActuatorLimits.from_platform(
            platform, load_controller("mbox6"), rate_hz=RATE
        )
    if drive not in _CHAIN:
        _CHAIN[drive] = resample(read_recording_csv(Path(drive)), RATE)
    rec = _CHAIN[drive]
    run = run_chain(
        rec.f,
        rec.w,
        load_cueing(preset),
        _CHAIN["platform"],
        _CHAIN["limits"],
        RATE,
    )
    m = run.evaluation.metrics  # cue_metrics with the clamped share run_chain passes
    return Figures(
        drive=drive,
        share=(float(m.rendered_share[0]), float(m.rendered_share[1])),
        corr=(float(m.correlation[0]), float(m.correlation[1])),
        reversals=float(m.reversals_any),
        false_any=float(m.false_any),
        clamped=float(m.clamped),
        limited=int(run.actuator_limited),
        false_cues=tuple(float(v) for v in m.false_cues),
    )


def score(figs: Sequence[Figures], ref: Sequence[Figures], min_ratio: float) -> tuple[float, float]:
    """``(violation, strength)``: the constraints' summed violation (0: all met) and the
    smallest ratio of a share to the reference's over the drives and fx, fy."""
    viol, ratios = 0.0, []
    for f, r in zip(figs, ref, strict=True):
        ratio = min(f.share[0] / r.share[0], f.share[1] / r.share[1])
        ratios.append(ratio)
        viol += 10 * max(0.0, MIN_CORR[0] - f.corr[0]) + 10 * max(0.0, MIN_CORR[1] - f.corr[1])
        viol += 10 * max(0.0, f.reversals - MAX_REVERSALS) + max(0.0, f.false_any - MAX_FALSE)
        viol += 10 * max(0.0, f.clamped - MAX_CLAMPED) + f.limited / 100
        viol += max(0.0, min_ratio - ratio)
    return viol, min(ratios)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--budget-s", type=float, default=0.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--base", help="the mpc preset TOML the search starts from")
    ap.add_argument("--out", help="where the best preset is written")
    ap.add_argument("--drives", nargs="*", default=list(DRIVES), help="tuning drives (CSV)")
    ap.add_argument("--min-ratio", type=float, default=1.0, help="least strength ratio")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--sigma", type=float, default=0.15, help="step in log space")
    ap.add_argument(
        "--coords", nargs="*", help="search only these coordinates (labels; default: all)"
    )
    ap.add_argument("--write-base", help="write the search's start preset here and stop")
    ap.add_argument("--eval", nargs="*", help="only measure these presets (TOML or names)")
    args = ap.parse_args()
    if args.write_base:
        Path(args.write_base).write_text(base_text(Path(__file__).resolve().parents[1]))
        return
    for d in args.drives:
        if Path(d).name in HELD_OUT and "recordings" in d:
            ap.error(f"{d} is a held-out drive")
    # longest drives first, so that the two processes finish together
    drives = sorted(args.drives, key=lambda d: -Path(d).stat().st_size)
    ex = ProcessPoolExecutor(args.workers)

    def run(preset: str) -> list[Figures]:
        figs = list(ex.map(measure, [(preset, d) for d in drives]))
        return sorted(figs, key=lambda f: args.drives.index(f.drive))

    t0 = time.time()
    ref = run(REFERENCE)
    print(f"{REFERENCE} ({time.time() - t0:.0f} s):", flush=True)
    for f in ref:
        print("  " + f.line(), flush=True)
    if args.eval is not None:
        for preset in args.eval:
            figs = run(preset)
            viol, ratio = score(figs, ref, args.min_ratio)
            print(f"{preset}: violation {viol:.4f} ratio {ratio:.3f}", flush=True)
            for f, r in zip(figs, ref, strict=True):
                print("  " + f.line(r), flush=True)
        return
    if not (args.base and args.out and args.budget_s > 0):
        ap.error("a search needs --base, --out and --budget-s")
    start_text = Path(args.base).read_text()
    base = tomllib.loads(start_text)
    labels = [c[0] for c in COORDS]
    for lab in args.coords or []:
        if lab not in labels:
            ap.error(f"unknown coordinate {lab!r}; known: {' '.join(labels)}")
    free = np.array([not args.coords or c[0] in args.coords for c in COORDS])
    x0 = start_point(base)
    searched = [c for c, on in zip(COORDS, free, strict=True) if on]
    lo = np.log([c[4] for c in COORDS])[free]
    hi = np.log([c[5] for c in COORDS])[free]
    tmp = Path(args.out).with_suffix(".candidate.toml")

    def full(xf: np.ndarray) -> np.ndarray:
        """The whole point: the searched coordinates ``xf``, the others the base's."""
        x = x0.copy()
        x[free] = xf
        return x

    def text_of(xf: np.ndarray) -> str:
        return edit_toml(start_text, point_values(base, searched, xf))

    def evaluate(xf: np.ndarray) -> tuple[float, list[Figures]]:
        tmp.write_text(text_of(xf))
        figs = run(str(tmp))
        viol, ratio = score(figs, ref, args.min_ratio)
        return (-ratio if viol == 0.0 else 1.0 + viol), figs

    def better(it: int, elapsed_s: float, fit: float, xf: np.ndarray, figs: list[Figures]) -> None:
        lines = [f.line(r) for f, r in zip(figs, ref, strict=True)]
        head = f"# search it {it} t {elapsed_s:.0f} s fit {fit:.5f}\n"
        Path(args.out).write_text(head + "".join(f"#   {ln}\n" for ln in lines) + text_of(xf))
        vals = ", ".join(f"{c[0]} {math.exp(v):.4g}" for c, v in zip(COORDS, full(xf), strict=True))
        print(f"it {it} t {elapsed_s:.0f} s fit {fit:.5f}: {vals}", flush=True)
        print("\n".join("  " + ln for ln in lines), flush=True)

    one_plus_two(
        evaluate,
        x0[free],
        lo,
        hi,
        seed=args.seed,
        budget_s=args.budget_s,
        k_max=min(4, int(free.sum()) + 1),
        sigma=args.sigma,
        on_better=better,
    )
    tmp.unlink(missing_ok=True)


if __name__ == "__main__":
    main()
