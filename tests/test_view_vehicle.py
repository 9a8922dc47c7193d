"""``motioncue view`` of a ride made from a recording: the vehicle's perceived motion beside
the rider's, on the ride's clock (checked against the recording filtered independently)."""

from __future__ import annotations

import dataclasses
import html
import json
import re
from pathlib import Path

import numpy as np
import pytest

from _lapcsv import lap_excerpt as _excerpt
from motioncue import ConfigError
from motioncue.cli import main
from motioncue.cueing import GRAVITY_M_S2, get_model_set
from motioncue.pipeline import load_ride
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.viewer import load_view_input, view_html


def test_view_draws_the_vehicle_beside_the_rider(tmp_path: Path) -> None:
    rec = _excerpt(tmp_path / "drive.csv", 1000, 600)
    ride_path = tmp_path / "drive.ride"
    assert main(["generate", "--input", str(rec), "--platform", "stewart6-linear",
                 "--controller", "mbox6", "--out", str(ride_path), "--quiet"]) == 0  # fmt: skip
    ride = load_ride(ride_path)
    v = load_view_input(ride_path)  # the recording lies next to the ride: found by its name
    assert v.vehicle is not None and v.vehicle.shape == (v.scene.t_s.size, 6)
    # independent: the recording at the ride's rate through the models, sample j on frame
    # cue_frames[0] + j
    u = resample(read_recording_csv(rec), ride.rate_hz)
    ms = get_model_set("telban-cardullo-2005")
    pv = ms.filter(np.concatenate([u.f - [0, 0, GRAVITY_M_S2], u.w], axis=1), ride.rate_hz)
    start = ride.notes["cue_frames"][0]
    j = np.arange(50, 550, 25)
    t_frames = ride.t_s[start + j]
    got = np.column_stack([np.interp(t_frames, v.scene.t_s, v.vehicle[:, i]) for i in range(2)])
    np.testing.assert_allclose(got, pv[j, :2], atol=0.05 * np.abs(pv[:, :2]).max())
    assert np.all(v.vehicle[v.scene.t_s < ride.t_s[start] - 0.05] == 0.0)  # ramp in: at rest
    page = view_html(v)
    blob = re.search(r'<script id="mc-data" type="application/json">(.*?)</script>', page, re.S)
    assert blob is not None
    names = [tr.get("name", "") for tr in json.loads(blob.group(1))["curves"]["data"]]
    veh = [n for n in names if n.startswith("vehicle f")]
    assert len(veh) == 2 and all("rider gets" in n for n in veh)
    assert v.notes[0].startswith("cueing: optimal-hexapod-auto")  # the ride-file default
    assert any(n.startswith("strength: the rider perceives") for n in v.notes)
    # the same page without the recording has no vehicle traces, and says why
    (tmp_path / "drive.csv").rename(tmp_path / "moved.csv")
    gone = load_view_input(ride_path)
    assert gone.vehicle is None
    why = "vehicle: not drawn: the ride's source 'drive.csv' is not next to the ride file"
    assert any(n.startswith(why) for n in gone.notes), gone.notes
    assert html.escape(why, quote=True) in view_html(gone)
    assert load_view_input(ride_path, recording=tmp_path / "moved.csv").vehicle is not None
    with pytest.raises(ConfigError, match="ride file"):
        load_view_input(tmp_path / "moved.csv", "stewart6-linear", recording=rec)


def test_a_ride_whose_source_is_missing_or_unreadable_is_still_viewed(tmp_path: Path) -> None:
    """No source named, a source that is not a recording, a damaged one: the view is made
    and says why the vehicle is not drawn; an explicit --recording that is bad is an error."""
    from motioncue.kinematics import load_platform
    from motioncue.pipeline import Ride, save_ride

    plat = load_platform("stewart6-linear")
    n = 40
    pulses = np.repeat(plat.drives.to_pulses(plat.q_park[None, :]), n, axis=0)
    base = Ride(
        platform="stewart6-linear", controller="mbox6", rate_hz=100.0,
        actuator_names=plat.actuator_names, t_s=np.arange(n) / 100.0,
        pulses=pulses.astype(np.int32), dout=np.zeros(n, np.uint16),
        dacs=np.zeros((n, 2), np.uint16),
    )  # fmt: skip
    (tmp_path / "keys.csv").write_text("t,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n1,0,0,0.01,0,0,0\n")
    (tmp_path / "bad.csv").write_text("t,fx,fy\nnot,a,recording\n")
    cases = {
        "": "the ride does not name the recording it was made from",
        "keys.csv": "the ride's source 'keys.csv' is pose keyframes, not a vehicle",
        "bad.csv": "the ride's source could not be read",
    }
    for source, says in cases.items():
        path = save_ride(
            tmp_path / f"r{len(source)}.ride", dataclasses.replace(base, source=source)
        )
        v = load_view_input(path)
        assert v.vehicle is None
        assert "cueing: not recorded" in v.notes[0]  # a ride made without generate
        assert any(n.startswith(f"vehicle: not drawn: {says}") for n in v.notes), v.notes
        assert view_html(v)  # the page is still made
    with pytest.raises(ConfigError):
        load_view_input(path, recording=tmp_path / "bad.csv")
    with pytest.raises(ConfigError, match="not a recording of vehicle motion"):
        load_view_input(path, recording=tmp_path / "keys.csv")


def test_view_reports_every_cue_metric_in_its_notes_and_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 20: the metrics in ``view`` and its JSON. Closed forms on the view's own rider:
    a vehicle twice the rider's perceived motion is rendered at share and gain 0.5 with
    correlation 1 and no false cue; its mirror gives reversals wherever both are above
    threshold. The JSON carries what the notes say."""
    from motioncue.cueing._vestibular import DEFAULT_MODEL_SET
    from motioncue.viewer import view_metrics
    from motioncue.viewer._view import _perceived

    rec = _excerpt(tmp_path / "drive.csv", 1000, 400)
    ride_path = tmp_path / "drive.ride"
    assert main(["generate", "--input", str(rec), "--platform", "stewart6-linear",
                 "--controller", "mbox6", "--out", str(ride_path), "--quiet"]) == 0  # fmt: skip
    v = load_view_input(ride_path)
    assert v.metrics is not None and v.vehicle is not None
    assert any(n.startswith("cues fx / fy: gain") for n in v.notes), v.notes
    p, _ = _perceived(v.scene, v.rate_hz)
    lo, hi = v.vehicle_window_s or (0.0, 0.0)
    inside = (v.scene.t_s >= lo) & (v.scene.t_s <= hi)
    assert inside.sum() == v.metrics.n_samples > 100
    twice = view_metrics(dataclasses.replace(v, vehicle=2.0 * p), p)
    np.testing.assert_allclose(twice.rendered_share, 0.5, rtol=1e-9)
    np.testing.assert_allclose(twice.gain, 0.5, rtol=1e-9)
    np.testing.assert_allclose(twice.correlation[:2], 1.0, atol=1e-9)
    assert twice.false_any == 0.0 and twice.reversals_any == 0.0
    mirror = view_metrics(dataclasses.replace(v, vehicle=-p), p)
    thr = np.asarray(get_model_set(DEFAULT_MODEL_SET).thresholds)
    both = np.abs(p[inside]) > thr
    np.testing.assert_allclose(mirror.reversals, both.mean(axis=0), atol=1e-12)
    assert mirror.reversals[0] > 0.0
    capsys.readouterr()  # generate's summary line
    assert main(["view", str(ride_path), "--out", str(tmp_path / "v.html"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)["metrics"]
    assert out["n_samples"] == v.metrics.n_samples
    for key in ("rendered_share", "gain", "correlation", "missed", "reversals", "spurious"):
        got = [out[key][c] for c in ("fx", "fy")]  # written to three decimals
        np.testing.assert_allclose(got, getattr(v.metrics, key)[:2], atol=5e-4, err_msg=key)
    assert out["false_any"] == pytest.approx(v.metrics.false_any, abs=5e-4)
