"""The jobs users run, built from the pipeline stages: ride files, generate, play, bridge, demo.

reader -> resample -> cueing -> workspace limiting -> IK -> drives -> actuator limits ->
controller encoder -> transport; offline (:func:`generate_ride`) and on time
(:func:`play_ride`, the live bridge).
"""

from ._bridge import Bridge, BridgeConfig, BridgeStats
from ._demo import DemoResult, compare_trace, run_demo
from ._generate import (
    RAMP_ACCEL,
    RAMP_SPEED,
    GenerateReport,
    generate_keyframe_ride,
    generate_ride,
    pulse_rounding_limits,
)
from ._inputs import Keyframes, load_generate_input, read_keyframes_csv
from ._report import delivered_poses, plot_actuators, write_report
from ._ridecheck import check_ride_for, check_ride_integrity
from ._ridefile import RIDE_FORMAT, RIDE_FORMAT_VERSION, Ride, load_ride, save_ride
from ._stream import OutputStage, PlayReport, make_frame_encoder, play_ride, receiver_throttle
from ._verify import FrameCheck, check_frames

__all__ = [
    "RAMP_ACCEL",
    "RAMP_SPEED",
    "RIDE_FORMAT",
    "RIDE_FORMAT_VERSION",
    "Bridge",
    "BridgeConfig",
    "BridgeStats",
    "DemoResult",
    "FrameCheck",
    "GenerateReport",
    "Keyframes",
    "OutputStage",
    "PlayReport",
    "Ride",
    "check_frames",
    "check_ride_for",
    "check_ride_integrity",
    "compare_trace",
    "delivered_poses",
    "generate_keyframe_ride",
    "generate_ride",
    "load_generate_input",
    "load_ride",
    "make_frame_encoder",
    "play_ride",
    "plot_actuators",
    "pulse_rounding_limits",
    "read_keyframes_csv",
    "receiver_throttle",
    "run_demo",
    "save_ride",
    "write_report",
]
