"""motioncue.trajectory: actuator limits, real-time limiting, offline ride optimisation,
workspace-aware pose limiting, time-optimal transitions, park/unpark/resume.

Discrete-time definitions shared by every function here (frame period ``dt``):
speed ``(q[k]-q[k-1])/dt``, acceleration ``(q[k]-2q[k-1]+q[k-2])/dt**2``, jerk
``(q[k]-3q[k-1]+3q[k-2]-q[k-3])/dt**3``; see :func:`check_trajectory`.
"""

from ._limits import ActuatorLimits, LimitCheck, check_trajectory, finite_differences
from ._offline import OptimisedRide, limit_ride
from ._plot import plot_ride
from ._realtime import LimiterState, RealtimeLimiter, braking_distance, braking_speed_cap
from ._transition import (
    Transition,
    brake_to_rest,
    park_path,
    resume_path,
    transition,
    transition_q,
    transition_through,
    unpark_path,
)
from ._workspace import PoseLimitResult, limit_pose

__all__ = [
    "ActuatorLimits",
    "LimitCheck",
    "LimiterState",
    "OptimisedRide",
    "PoseLimitResult",
    "RealtimeLimiter",
    "Transition",
    "brake_to_rest",
    "braking_distance",
    "braking_speed_cap",
    "check_trajectory",
    "finite_differences",
    "limit_pose",
    "limit_ride",
    "park_path",
    "plot_ride",
    "resume_path",
    "transition",
    "transition_q",
    "transition_through",
    "unpark_path",
]
