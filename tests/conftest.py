"""Shared test setup: hypothesis profiles for small, noisy machines, and a CPU-time report.

``--cpu-durations=N`` lists the N tests that used the most CPU time (this process and the
child processes it waited for; setup, call and teardown summed) and the suite's total. On a
machine shared with other work the wall-clock durations (``--durations``) grow with the load;
CPU time does not, so it is the figure to compare a change of the suite by. Works under
pytest-xdist (each worker measures its own tests and sends the figure with the report).
"""

from __future__ import annotations

import os
import resource
from collections import defaultdict
from collections.abc import Generator, Iterator

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile("default", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile(
    "ci", deadline=None, suppress_health_check=[HealthCheck.too_slow], print_blob=True
)
settings.load_profile("ci" if os.environ.get("CI") else "default")


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--cpu-durations",
        type=int,
        default=None,
        metavar="N",
        help="list the N tests that used the most CPU time (0: all) and the total",
    )


def _cpu_s() -> float:
    """CPU seconds (user + system) of this process and of its waited-for children."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


_PHASE_CPU = pytest.StashKey[dict[str, float]]()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_setup(item: pytest.Item) -> Iterator[None]:
    t0 = _cpu_s()
    yield
    item.stash.setdefault(_PHASE_CPU, {})["setup"] = _cpu_s() - t0


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_call(item: pytest.Item) -> Iterator[None]:
    t0 = _cpu_s()
    yield
    item.stash.setdefault(_PHASE_CPU, {})["call"] = _cpu_s() - t0


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_teardown(item: pytest.Item) -> Iterator[None]:
    t0 = _cpu_s()
    yield
    item.stash.setdefault(_PHASE_CPU, {})["teardown"] = _cpu_s() - t0


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    report = yield
    cpu = item.stash.get(_PHASE_CPU, {}).get(call.when)
    if cpu is not None:
        report.user_properties.append(("cpu_s", cpu))
    return report


_CPU_BY_TEST: dict[str, float] = defaultdict(float)
_WALL_BY_TEST: dict[str, float] = defaultdict(float)


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    for name, value in report.user_properties:
        if name == "cpu_s" and isinstance(value, float):
            _CPU_BY_TEST[report.nodeid] += value
    _WALL_BY_TEST[report.nodeid] += report.duration


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    n = terminalreporter.config.getoption("--cpu-durations")
    if n is None or not _CPU_BY_TEST:
        return
    ranked = sorted(_CPU_BY_TEST.items(), key=lambda kv: kv[1], reverse=True)
    terminalreporter.write_sep("=", "CPU time per test (setup + call + teardown, with children)")
    for nodeid, cpu in ranked[: n or None]:
        wall = _WALL_BY_TEST[nodeid]
        terminalreporter.write_line(f"{cpu:8.2f} s cpu {wall:8.2f} s wall  {nodeid}")
    total_cpu = sum(_CPU_BY_TEST.values())
    total_wall = sum(_WALL_BY_TEST.values())
    terminalreporter.write_line(
        f"{total_cpu:8.2f} s cpu {total_wall:8.2f} s wall  total of {len(ranked)} tests"
    )
