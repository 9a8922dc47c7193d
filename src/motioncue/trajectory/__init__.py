"""motioncue.trajectory: actuator limits, real-time limiting, offline ride optimisation,
workspace-aware pose limiting, time-optimal transitions, park/unpark/resume.

Discrete-time definitions shared by every function here (frame period ``dt``):
speed ``(q[k]-q[k-1])/dt``, acceleration ``(q[k]-2q[k-1]+q[k-2])/dt**2``, jerk
``(q[k]-3q[k-1]+3q[k-2]-q[k-3])/dt**3``; see :func:`check_trajectory`.

Contents
--------
- :class:`ActuatorLimits` (``from_platform(platform, controller, ...)``, ``to_pulses_table``,
  ``to_json``): stroke, speed, acceleration, optional jerk per actuator, in SI;
  :func:`pulse_rounding_limits` tightens them by the rounding to whole pulses.
  :func:`within_controller_stroke` keeps a table within the controller's own stroke.
- :class:`RealtimeLimiter` / :class:`LimiterState`: causal, one frame at a time
  (``state = rt.initial_state(q0); q = rt.step(state, target)``; ``rt.run`` for a stream).
- :func:`limit_ride` -> :class:`OptimisedRide`: offline casadi optimisation of a whole ride
  on its own clock; :func:`plot_ride` draws it.
- :func:`limit_pose` -> :class:`PoseLimitResult`: unreachable poses scaled towards neutral;
  :func:`reachable`: which poses it would leave untouched.
- :func:`transition`, :func:`transition_through`, :func:`transition_q` -> :class:`Transition`:
  toppra time-optimal moves at rest; :func:`park_path`, :func:`unpark_path`,
  :func:`resume_path`, :func:`brake_to_rest` built on them and on the limiter.
"""

from ._derive import planning_limits, pulse_rounding_limits, within_controller_stroke
from ._jerk import JerkLimiter, JerkLimiterState
from ._limits import ActuatorLimits, LimitCheck, PulsesRow, check_trajectory, finite_differences
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
from ._workspace import PoseLimitResult, limit_pose, reachable

__all__ = [
    "ActuatorLimits",
    "JerkLimiter",
    "JerkLimiterState",
    "LimitCheck",
    "LimiterState",
    "OptimisedRide",
    "PoseLimitResult",
    "PulsesRow",
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
    "planning_limits",
    "plot_ride",
    "pulse_rounding_limits",
    "reachable",
    "resume_path",
    "transition",
    "transition_q",
    "transition_through",
    "unpark_path",
    "within_controller_stroke",
]
