"""Issue 13 on loopback with kernel receive stamps (``tests/_loopback.py``): what works.

The bridge (stewart6-linear, SC-MBOX 6-axis, ``racing``) runs in this process at 250 Hz
with frames on arrival, telemetry decoded in a child process, no real-time priority; an
independent recorder process stamps every frame with the kernel's receive time
(``SO_TIMESTAMPNS``) and reads it with ``struct``; the F1 stream (real captures, 60 Hz, a
lateral-g step 0 <-> 1 g about every second) comes from a third process.

Here: every step reaches the frames, the frames come in order and keep the limits on the
controller's clock, and the bridge stops parked. The issue's timing figures (step delay p50
<= 1.5 ms and max <= 3 ms, output jitter p99 <= 1 ms with a core saturated) are wall-clock
figures that any busy machine misses; they are asserted, unchanged, against a reference loop
run in the same process, by ``benchmarks/bench_latency.py`` (``make bench``).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _loopback as lb

RATE_HZ = 250.0
SECONDS = 8.0  # from the bridge going live: 1.5 s warm-up, then about 6 steps
# A step counts when a frame moves with it within this time. Not a timing promise (that is
# 1.5 ms p50 / 3 ms max, in the bench): 100x the promise, so that only a step that never
# reaches the frames (dropped, or waiting for something that does not come) goes uncounted,
# even when a busy machine stops this process for tens of ms.
FUNCTIONAL_WINDOW_MS = 300.0


# A machine that stalls this process for seconds can leave fewer than 3 of one run's steps
# judgeable (below); the test then runs again, up to this many runs in all, and judges the
# steps of every run. Each run must pass every check on its own.
MAX_RUNS = 3
MIN_JUDGED = 3


def test_a_lateral_g_step_reaches_the_frames_in_order_and_within_the_limits() -> None:
    judged = live = 0
    runs = []
    while judged < MIN_JUDGED and len(runs) < MAX_RUNS:
        res = lb.run_loopback(
            RATE_HZ, SECONDS, False, True, "extrapolate", "arrival", window_ms=FUNCTIONAL_WINDOW_MS
        )
        runs.append(res)
        assert res["limits_ok"], res["limits"]
        assert res["error"] is None and res["state"] == "stopped", res
        assert res["in_order"], res["order"]
        assert res["frames"] > 0.1 * RATE_HZ * SECONDS, res  # the loop ran (not a rate check)
        # every step sent after the warm-up that can be judged moved the frames within the
        # window. A step cannot be judged when the 10 frames before it were not quiet (another
        # step's transient, or frames stamped unevenly while a busy machine stopped this
        # process: CI, session 31, 2 of 5 steps), or when no frame moved in its window while
        # the frames stopped (this process stopped 3 s by SIGSTOP: 2 steps)
        assert res["steps_missed"] == 0, res
        assert res["steps"] + res["steps_unjudged"] == res["steps_live"], res
        judged += res["steps"]
        live += res["steps_live"]
    # about 6 steps are sent per run; at least 3 judged over the runs
    assert live >= 4 * len(runs), runs
    assert judged >= MIN_JUDGED, runs
