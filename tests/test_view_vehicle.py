"""``motioncue view`` of a ride made from a recording: the vehicle's perceived motion beside
the rider's, on the ride's clock (checked against the recording filtered independently)."""

from __future__ import annotations

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
    # the same page without the recording has no vehicle traces
    (tmp_path / "drive.csv").rename(tmp_path / "moved.csv")
    assert load_view_input(ride_path).vehicle is None
    assert load_view_input(ride_path, recording=tmp_path / "moved.csv").vehicle is not None
    with pytest.raises(ConfigError, match="ride file"):
        load_view_input(tmp_path / "moved.csv", "stewart6-linear", recording=rec)
