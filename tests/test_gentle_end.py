"""The gentle end of an intensity range is gentler in every channel (issue 20).

``motioncue tune --gentle-end`` maximises the strength (the geometric mean of the fx and fy
shares) within tighter cue-quality targets. Overall gentler is not enough: a gentle end
stronger than the strong end in fx made 0/50/100 % non-monotone in fx. So the targets carry a
per-channel cap (:attr:`StrengthTargets.max_share`, ``--gentle-share`` times the strong end's
shares): checked here against hand-computed violations, and on the tuner, which must find the
known optimum of a synthetic problem whose cap binds in one channel.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from motioncue._errors import ConfigError
from motioncue.analysis._tune import ChainMetrics, StrengthTargets, tune_cueing
from motioncue.cli import main
from motioncue.cueing._tune import STRENGTH_TUNED_PARAMETERS
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import Recording, read_recording_csv, write_recording_csv
from test_tune_strength import _cue, _Synthetic


def _m(sx: float, sy: float, false: float = 0.0) -> ChainMetrics:
    return ChainMetrics(0.0, (0.0,), duration_s=1.0, strength=math.sqrt(sx * sy),
                        cue=_cue(sx, sy, false))  # fmt: skip


def test_the_cap_counts_each_channel_on_its_own() -> None:
    t = StrengthTargets(max_share=(0.02, 0.08))
    assert t.violation(_m(0.02, 0.08)) == 0.0  # on the cap: met
    assert t.violation(_m(0.01, 0.05)) == 0.0
    # fx 0.03 over 0.02: 0.5, relative to the cap; fy within
    assert t.violation(_m(0.03, 0.05)) == pytest.approx(0.5)
    # fy 0.12 over 0.08: 0.5; both: 0.5 + 0.5
    assert t.violation(_m(0.01, 0.12)) == pytest.approx(0.5)
    assert t.violation(_m(0.03, 0.12)) == pytest.approx(1.0)
    # the other targets add as before (false cues 0.18 over 0.15: 0.2)
    assert t.violation(_m(0.03, 0.05, false=0.18)) == pytest.approx(0.7)
    # gentler overall but stronger in fx (last session's gentle end): not met
    assert math.sqrt(0.042 * 0.05) < math.sqrt(0.038 * 0.12)
    assert StrengthTargets(max_share=(0.038, 0.12)).violation(_m(0.042, 0.05)) > 0.0
    assert StrengthTargets().violation(_m(0.042, 0.05)) == 0.0  # without the cap it was


@pytest.mark.parametrize("bad", [(0.0, 0.1), (0.1, -1.0), (0.1, math.nan), (0.1,), (0.1, 11.0)])
def test_a_bad_cap_is_refused_with_its_value(bad: tuple[float, ...]) -> None:
    with pytest.raises(ConfigError, match="max_share"):
        StrengthTargets(max_share=bad)  # type: ignore[arg-type]


def test_the_tuner_finds_the_optimum_where_the_cap_binds_in_one_channel() -> None:
    """Strength sqrt(kx ky), false cues 0.1 (kx + ky) <= 0.15, and share fx <= 0.3: the
    best is kx = 0.3 on the cap and ky = 1.2 on the false-cue budget (strength 0.6); without
    the cap it is kx = ky = 0.75 (``test_tune_strength``)."""
    obj = _Synthetic()
    obj.targets = StrengthTargets(max_share=(0.3, 5.0))
    res = tune_cueing(obj, seed=3, generations=100, popsize=3, budget_s=600.0)
    kx, ky = res.params.tilt_scale  # type: ignore[misc]
    assert kx == pytest.approx(0.3, rel=0.03)
    assert ky == pytest.approx(1.2, rel=0.03)
    assert res.after.strength == pytest.approx(0.6, rel=0.03)
    assert obj.targets.violation(res.after) == 0.0


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        (["--gentle-end", "--gentle-share", "1.5"], "--gentle-share 1.5 is invalid"),
        (["--gentle-end", "--gentle-share", "nan"], "--gentle-share nan is invalid"),
        (["--gentle-end", "--gentle-keep", "tilt_wn", "lead_x_s"], "--gentle-keep 'tilt_wn'"),
        (["--gentle-keep", "lead_x_s"], "--gentle-keep needs --gentle-end"),
    ],
)
def test_bad_gentle_options_are_one_line_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], says: str
) -> None:
    lap = read_recording_csv(sample_drives("demo")[0])
    rec = tmp_path / "short.csv"
    write_recording_csv(rec, Recording(lap.t_s[:300] - lap.t_s[0], lap.f[:300], lap.w[:300]))
    out = tmp_path / "g.toml"
    rc = main(["tune", "--input", str(rec), "--platform", "stewart6-linear", "--controller",
               "mbox6", "--preset", "racing-hexapod-firm", "--out", str(out), *extra])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and err[-1].startswith("motioncue tune: error:") and says in err[-1], err
    assert not out.exists()


def test_a_held_parameter_stays_at_the_base_and_the_rest_find_their_optimum() -> None:
    """``hold`` (``--gentle-keep``): ky held at the base's 0.2, the budget kx + ky <= 1.5
    leaves kx = 1.3 (strength sqrt(0.26)); a bad index is refused."""
    obj = _Synthetic()
    i_ky = [p.name for p in STRENGTH_TUNED_PARAMETERS].index("tilt_scale_y")
    res = tune_cueing(obj, seed=3, generations=100, popsize=3, budget_s=600.0, hold=[i_ky])
    kx, ky = res.params.tilt_scale  # type: ignore[misc]
    assert ky == pytest.approx(0.2, rel=1e-9)
    assert kx == pytest.approx(1.3, rel=0.03)
    with pytest.raises(ConfigError, match="hold index 21"):
        tune_cueing(obj, generations=1, hold=[21])
