"""``--intensity PCT`` (issue 20, Build item 5): a point of the preset's tuned range.

``racing-hexapod-strong`` (the preset with a tuned intensity range) at 0, 50 and 100 % is a
complete washout between the two tuned ends (not a plain gain); that those points give
monotonically stronger rides, each within the limits, is tests/test_intensity_rides.py.
Bad intensities and presets without a range are refused with one line.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from motioncue.cli import main
from motioncue.cueing import at_intensity, load_cueing
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import Recording, read_recording_csv, write_recording_csv

PLATFORM, CONTROLLER, PRESET, RATE = "stewart6-linear", "mbox6", "racing-hexapod-strong", 100.0


@pytest.fixture(scope="module")
def lap_excerpt(tmp_path_factory: pytest.TempPathFactory) -> Path:
    rec = read_recording_csv(sample_drives("demo")[0])
    a, b = 1000, 4000  # 10 s to 40 s: braking, corners, a crest
    out = tmp_path_factory.mktemp("intensity") / "lap-10-40.csv"
    write_recording_csv(out, Recording(rec.t_s[a:b] - rec.t_s[a], rec.f[a:b], rec.w[a:b]))
    return out


def test_intensity_points_are_tuned_designs_between_the_ends() -> None:
    strong = load_cueing(PRESET)
    assert strong.intensity_gentle is not None
    assert at_intensity(strong, 100.0) is strong
    gentle = at_intensity(strong, 0.0)
    mid = at_intensity(strong, 50.0)
    # geometric midpoint of every tuned value, e.g. the tilt gains and the tilt rate
    for name, i in (("tilt_scale", 0), ("tilt_scale", 1), ("f_scale", 1)):
        lo, hi, m = getattr(gentle, name)[i], getattr(strong, name)[i], getattr(mid, name)[i]
        assert m == pytest.approx(math.sqrt(lo * hi), rel=1e-9)
    assert mid.tilt_rate_limit_rad_s == pytest.approx(
        math.sqrt(gentle.tilt_rate_limit_rad_s * strong.tilt_rate_limit_rad_s), rel=1e-9
    )
    # not a plain gain: more than the scales differ between the ends
    assert gentle.tilt_wn_rad_s != pytest.approx(strong.tilt_wn_rad_s, rel=1e-3) or (
        gentle.tilt_reach_use != pytest.approx(strong.tilt_reach_use, rel=1e-3)
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--intensity", "120"], "intensity 120.0 % is invalid"),
        (["--intensity", "nan"], "intensity nan % is invalid"),
        (["--intensity", "50", "--preset", "racing"], "has no tuned intensity range"),
        # the platform's default (with or without a range): test_intensity_play.py
    ],
)
def test_bad_intensity_is_one_line(
    lap_excerpt: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str],
    message: str,
) -> None:  # fmt: skip
    out = tmp_path / "x.ride"
    rc = main([
        "generate", "--input", str(lap_excerpt), "--platform", PLATFORM, "--controller",
        CONTROLLER, "--out", str(out), "--quiet", *args,
    ])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 2
    assert message in err and "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("motioncue generate: error:")
    assert not out.exists()


def test_profile_intensity_is_read_and_checked(tmp_path: Path) -> None:
    from motioncue._errors import ConfigError
    from motioncue.pipeline._profile import load_profile

    good = tmp_path / "p.toml"
    good.write_text('source = "f1"\npreset = "racing-hexapod-strong"\nintensity = 40\n')
    assert load_profile(good).intensity == 40.0
    bad = tmp_path / "q.toml"
    bad.write_text('source = "f1"\nintensity = 140\n')
    with pytest.raises(ConfigError, match="intensity"):
        load_profile(bad)
