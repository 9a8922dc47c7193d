"""The jobs users run, built from the pipeline stages: ride files, generate, play, bridge, demo."""

from ._bridge import Bridge, BridgeConfig, BridgeStats
from ._ridefile import RIDE_FORMAT, RIDE_FORMAT_VERSION, Ride, load_ride, save_ride

__all__ = [
    "RIDE_FORMAT",
    "RIDE_FORMAT_VERSION",
    "Bridge",
    "BridgeConfig",
    "BridgeStats",
    "Ride",
    "load_ride",
    "save_ride",
]
