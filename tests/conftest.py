"""Shared test setup: hypothesis profiles for small, noisy machines; xdist groups."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile("default", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile(
    "ci", deadline=None, suppress_health_check=[HealthCheck.too_slow], print_blob=True
)
settings.load_profile("ci" if os.environ.get("CI") else "default")


# pytest-xdist (``make test`` runs ``-n auto --dist loadgroup``): each module's tests go to one
# worker, so that a module's fixtures (a compare, a tuned preset, a ride) are built once, not
# once per worker; the modules listed here have no such fixture and cheap, independent parts
# that are better shared out among the workers.
_SPREAD_MODULES = frozenset({"test_fuzz_inputs"})


def pytest_collection_modifyitems(config, items):  # type: ignore[no-untyped-def]
    import pytest

    for item in items:
        module = item.module.__name__.rsplit(".", 1)[-1] if item.module else ""
        if module not in _SPREAD_MODULES and not item.get_closest_marker("xdist_group"):
            item.add_marker(pytest.mark.xdist_group(module))
