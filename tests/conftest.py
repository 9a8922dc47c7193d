"""Shared test setup: hypothesis profiles for small, noisy machines, a CPU-time report, and the
order in which pytest-xdist hands out the work.

``--cpu-durations=N`` lists the N tests that used the most CPU time (this process and the
child processes it waited for; setup, call and teardown summed) and the suite's total. On a
machine shared with other work the wall-clock durations (``--durations``) grow with the load;
CPU time does not, so it is the figure to compare a change of the suite by. Works under
pytest-xdist (each worker measures its own tests and sends the figure with the report). It
also lists, per test, how long the test's thread was ready to run but waited for a core
(``runq``, from ``/proc/thread-self/schedstat``): wall minus that is what the test would
take on a quiet machine (roughly: the wait of child processes for a core is not seen).

Work order: ``make test`` runs more pytest-xdist workers than cores (many tests wait on
sleeps, emulators and real-time playback and need no core meanwhile) with ``--dist
loadscope``. Plain loadscope hands out the modules with the most tests first, which leaves
the few-but-long modules (tuning, MPC acceptance, fuzz) to the end, where one worker runs
them alone. :class:`_LongestFirst` hands out the units known to take longest first
(:data:`_LONG_UNITS`, measured) and splits the modules in :data:`_SPLIT` into one unit per
test (they share no module fixture), so that the run ends with short units on every worker.
"""

from __future__ import annotations

import os
import resource
from collections import defaultdict
from collections.abc import Generator, Iterator

import pytest
from hypothesis import HealthCheck, settings

# One BLAS/OpenMP thread per process, set before numpy loads (here, in every xdist worker,
# and inherited by the motioncue processes the tests start): the suite runs two workers
# per core, and threaded BLAS on top of that made SciPy's SLSQP about 15x slower on a
# loaded 2-core machine (14 s against 0.9 s for the same bound test).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

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


def _runq_s() -> float:
    """Seconds this thread has waited, ready to run, for a core (0 where not available)."""
    try:
        with open("/proc/thread-self/schedstat") as f:
            return int(f.read().split()[1]) / 1e9
    except (OSError, ValueError, IndexError):
        return 0.0


_PHASE_CPU = pytest.StashKey[dict[str, float]]()
_PHASE_RUNQ = pytest.StashKey[dict[str, float]]()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_setup(item: pytest.Item) -> Iterator[None]:
    t0, q0 = _cpu_s(), _runq_s()
    yield
    item.stash.setdefault(_PHASE_CPU, {})["setup"] = _cpu_s() - t0
    item.stash.setdefault(_PHASE_RUNQ, {})["setup"] = _runq_s() - q0


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_call(item: pytest.Item) -> Iterator[None]:
    t0, q0 = _cpu_s(), _runq_s()
    yield
    item.stash.setdefault(_PHASE_CPU, {})["call"] = _cpu_s() - t0
    item.stash.setdefault(_PHASE_RUNQ, {})["call"] = _runq_s() - q0


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_teardown(item: pytest.Item) -> Iterator[None]:
    t0, q0 = _cpu_s(), _runq_s()
    yield
    item.stash.setdefault(_PHASE_CPU, {})["teardown"] = _cpu_s() - t0
    item.stash.setdefault(_PHASE_RUNQ, {})["teardown"] = _runq_s() - q0


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    report = yield
    cpu = item.stash.get(_PHASE_CPU, {}).get(call.when)
    if cpu is not None:
        report.user_properties.append(("cpu_s", cpu))
    runq = item.stash.get(_PHASE_RUNQ, {}).get(call.when)
    if runq is not None:
        report.user_properties.append(("runq_s", runq))
    return report


_CPU_BY_TEST: dict[str, float] = defaultdict(float)
_WALL_BY_TEST: dict[str, float] = defaultdict(float)
_RUNQ_BY_TEST: dict[str, float] = defaultdict(float)


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    for name, value in report.user_properties:
        if name == "cpu_s" and isinstance(value, float):
            _CPU_BY_TEST[report.nodeid] += value
        elif name == "runq_s" and isinstance(value, float):
            _RUNQ_BY_TEST[report.nodeid] += value
    _WALL_BY_TEST[report.nodeid] += report.duration


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    n = terminalreporter.config.getoption("--cpu-durations")
    if n is None or not _CPU_BY_TEST:
        return
    ranked = sorted(_CPU_BY_TEST.items(), key=lambda kv: kv[1], reverse=True)
    terminalreporter.write_sep(
        "=", "CPU time per test (setup + call + teardown, with children; runq: waited for a core)"
    )
    for nodeid, cpu in ranked[: n or None]:
        wall, runq = _WALL_BY_TEST[nodeid], _RUNQ_BY_TEST[nodeid]
        terminalreporter.write_line(
            f"{cpu:8.2f} s cpu {wall:8.2f} s wall {runq:8.2f} s runq  {nodeid}"
        )
    total_cpu = sum(_CPU_BY_TEST.values())
    total_wall = sum(_WALL_BY_TEST.values())
    total_runq = sum(_RUNQ_BY_TEST.values())
    terminalreporter.write_line(
        f"{total_cpu:8.2f} s cpu {total_wall:8.2f} s wall {total_runq:8.2f} s runq"
        f"  total of {len(ranked)} tests"
    )


# --------------------------------------------------------------------------- work order
# The units of work that take longest on a quiet machine (setup included), longest first: a
# module, a class or a single test, by node id prefix. Only the order of hand-out depends on
# this list; a unit missing from it goes after those listed, in pytest-xdist's own order (file
# order here). Ranked by wall time less the time spent waiting for a core (runq), per unit
# summed over its tests, from session 25's `make test PYTEST_ARGS=--cpu-durations=0` on this
# branch (2058 passed in 248.2 s, load 2.5-4.3: other work on the machine), so with this
# session's cuts (the browser's and the held-up demo's report not drawn, tune's fork server):
# the units that mostly wait (liveness, fault injection, tune's processes, the browser) first,
# since their time does not shrink with the CPU. Units under 3.5 s are left to the end.
_LONG_UNITS: tuple[str, ...] = (
    "tests/test_liveness.py",
    "tests/test_fault_injection.py",
    "tests/test_tune.py",
    "tests/test_browser_drawing.py",
    "tests/test_bridge.py",
    "tests/test_telemetry.py",
    "tests/test_pipeline.py",
    "tests/test_wire_clock.py",
    "tests/test_easysmc_emulator.py",
    "tests/test_cue_bound_corr.py",
    "tests/test_safety_files.py",
    "tests/test_docs.py::test_docs_build",
    "tests/test_bridge_new_games.py",
    "tests/test_browser.py::test_view_renders_offline_plays_and_the_slider_moves_the_platform",
    "tests/test_cue_bound.py",
    "tests/test_browser.py::test_view_of_the_demo_ride_is_under_10_mb_and_renders",
    "tests/test_browser.py::test_play_cli_monitor_stop_parks_on_the_emulator",
    "tests/test_fk_rides.py",
    "tests/test_browser.py::test_stop_button_parks_the_bridge",
    "tests/test_mpc_acceptance.py",
    "tests/test_browser.py::test_stop_button_parks_a_play",
    "tests/test_easysmc_pipeline.py",
    "tests/test_viewer.py",
    "tests/test_limiter_jerk.py",
    "tests/test_extend_all.py",
    "tests/test_profiles.py",
    "tests/test_latency_acceptance.py",
    "tests/test_browser.py::test_monitor_renders_and_its_3d_view_follows_the_poses",
    "tests/test_corner4.py",
    "tests/test_extend_cueing.py",
    "tests/test_sample_drives.py",
    "tests/test_omct.py",
    "tests/test_bridge_games.py",
    "tests/test_iface.py",
    "tests/test_cli_defects.py",
    "tests/test_arrival.py",
    "tests/test_strength_bound.py",
    "tests/test_mpc.py",
    "tests/test_new_user.py",
    "tests/test_vestibular_models.py",
    "tests/test_cli_control.py",
    "tests/test_cueing_filters.py",
    "tests/test_easysmc_protocol.py",
    "tests/test_compare.py",
    "tests/test_demo_held_up.py",
    "tests/test_platform_defaults.py",
    "tests/test_kinematics.py",
    "tests/test_bridge_cli.py",
    "tests/test_cue_acceptance.py",
    "tests/test_extend_platform_game.py",
    "tests/test_bridge_replay.py",
    "tests/test_intensity_rides.py",
    "tests/test_cueing_cli.py",
    "tests/test_cli_pipeline.py",
    "tests/test_mpc_reference.py::test_tune_drives_an_optimal_preset_and_never_returns_a_worse_one",
    "tests/test_shm_source.py",
    "tests/test_fuzz_inputs.py::test_mutated_config_files_give_only_motioncue_errors",
    "tests/test_console_exit.py",
)
# Modules handed out one test at a time: long tests that share no module or class fixture.
_SPLIT: frozenset[str] = frozenset(
    {
        "tests/test_mpc_reference.py",
        "tests/test_fuzz_inputs.py",
        "tests/test_browser.py",
        "tests/test_docs.py",
    }
)


def _unit_of(nodeid: str) -> str:
    """The unit of work of a test: its own id in a split module, else its class or module."""
    if nodeid.split("::", 1)[0] in _SPLIT:
        return nodeid
    return nodeid.rsplit("::", 1)[0]


def _rank(nodeid: str) -> int:
    for k, prefix in enumerate(_LONG_UNITS):
        if nodeid.startswith(prefix):
            return k
    return len(_LONG_UNITS)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """In a pytest-xdist worker, the long units first (every worker sorts alike, as xdist
    requires; a single-process run keeps the file order)."""
    if hasattr(config, "workerinput"):
        items.sort(key=lambda item: _rank(item.nodeid))  # stable: file order within a rank


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """``-n auto``: two workers per core (at most 16). About a third of the suite's time is
    waiting (sleeps, emulators, playback at real time, other processes starting), which a
    second worker on the core fills with another test."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return min(2 * cores, 16)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object:
    """``--dist loadscope``: :class:`_LongestFirst`; any other mode: xdist's own."""
    if config.getoption("dist", None) != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class _LongestFirst(LoadScopeScheduling):
        """Loadscope in the workers' (longest first) order, with :data:`_SPLIT` split."""

        def _split_scope(self, nodeid: str) -> str:
            return _unit_of(nodeid)

        def schedule(self) -> None:
            self.config.option.loadscopereorder = False  # keep the longest-first order
            super().schedule()

    return _LongestFirst(config, log)
