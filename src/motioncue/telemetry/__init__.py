"""motioncue.telemetry (see the package docstring of motioncue)."""

__all__: list[str] = []
