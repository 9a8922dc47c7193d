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

``--timeline=PATH`` writes, per test, the worker that ran it, when it started and ended
(seconds from the first test's start, setup to teardown), its CPU and wall seconds, as CSV,
and prints the span of each worker and an estimate of the cores left idle (at each moment
the running tests' CPU shares, CPU over wall, summed and capped at the cores): the figures to
find what limits a run's wall time (the last unit to end, a gap before it, idle cores).

Work order: ``make test`` runs more pytest-xdist workers than cores (many tests wait on
sleeps, emulators and real-time playback and need no core meanwhile) with ``--dist
loadscope``. Plain loadscope hands out the modules with the most tests first, which leaves
the few-but-long modules (tuning, MPC acceptance, fuzz) to the end, where one worker runs
them alone. :class:`_LongestFirst` hands out the units known to take longest first
(:data:`_UNITS`, measured), one that mostly waits to a worker whose fellows already keep
every core busy and one that computes otherwise (:func:`_next_unit`), and splits the modules
in :data:`_SPLIT` into one unit per test (they share no module fixture), so that the run
ends with short units on every worker.
"""

from __future__ import annotations

import os
import resource
from collections import defaultdict
from collections.abc import Generator, Iterator
from typing import Any

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
    parser.addoption(
        "--timeline",
        default=None,
        metavar="PATH",
        help="write each test's worker, start, end, CPU and wall seconds to PATH (CSV)",
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
_SPAN_BY_TEST: dict[str, tuple[str, float, float]] = {}
"""Per test: the worker that ran it (``-`` without xdist), its first start and last stop."""


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    for name, value in report.user_properties:
        if name == "cpu_s" and isinstance(value, float):
            _CPU_BY_TEST[report.nodeid] += value
        elif name == "runq_s" and isinstance(value, float):
            _RUNQ_BY_TEST[report.nodeid] += value
    _WALL_BY_TEST[report.nodeid] += report.duration
    node = getattr(report, "node", None)  # pytest-xdist's controller sets it
    worker = str(getattr(report, "worker_id", None) or (node and node.gateway.id) or "-")
    start, stop = float(getattr(report, "start", 0.0)), float(getattr(report, "stop", 0.0))
    if report.nodeid in _SPAN_BY_TEST:
        _, t0, t1 = _SPAN_BY_TEST[report.nodeid]
        start, stop = min(start, t0), max(stop, t1)
    _SPAN_BY_TEST[report.nodeid] = (worker, start, stop)


def _write_timeline(terminalreporter: pytest.TerminalReporter, path: str) -> None:
    """The ``--timeline`` file and its summary (module docstring)."""
    import csv

    if not _SPAN_BY_TEST:
        return
    t_first = min(t0 for _, t0, _ in _SPAN_BY_TEST.values())
    rows = sorted(
        (t0 - t_first, t1 - t_first, worker, nodeid)
        for nodeid, (worker, t0, t1) in _SPAN_BY_TEST.items()
    )
    with open(path, "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["worker", "start_s", "end_s", "cpu_s", "wall_s", "nodeid"])
        for t0, t1, worker, nodeid in rows:
            cpu = _CPU_BY_TEST.get(nodeid, 0.0)
            out.writerow([worker, f"{t0:.3f}", f"{t1:.3f}", f"{cpu:.3f}", f"{t1 - t0:.3f}",
                          nodeid])  # fmt: skip
    terminalreporter.write_sep("=", f"timeline ({len(rows)} tests): {path}")
    spans: dict[str, list[float]] = {}
    for t0, t1, worker, _ in rows:
        w = spans.setdefault(worker, [t0, t1])
        w[0], w[1] = min(w[0], t0), max(w[1], t1)
    for worker, (t0, t1) in sorted(spans.items()):
        last = max((r for r in rows if r[2] == worker), key=lambda r: r[1])
        terminalreporter.write_line(f"{worker}: {t0:7.1f} - {t1:7.1f} s, last {last[3]}")
    # the cores the running tests kept busy (a step function: each test's CPU share from its
    # start to its end), swept over the starts and ends
    cores = _cores()
    steps: list[tuple[float, float]] = []
    for t0, t1, _, nodeid in rows:
        share = min(1.0, _CPU_BY_TEST.get(nodeid, 0.0) / max(t1 - t0, 1e-9))
        steps += [(t0, share), (t1, -share)]
    steps.sort()
    idle = demand = 0.0
    before = steps[0][0]
    for t, change in steps:
        idle += (t - before) * max(0.0, cores - demand)
        demand, before = demand + change, t
    end = steps[-1][0]
    terminalreporter.write_line(
        f"estimated idle: {idle:.1f} core-seconds of {cores} x {end:.1f} s"
        " (cores not kept busy by the running tests' CPU shares)"
    )


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    timeline = terminalreporter.config.getoption("--timeline")
    if timeline:
        _write_timeline(terminalreporter, timeline)
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
# The units of work that take longest on a quiet machine, by node id prefix (a module, a class
# or a single test): (CPU seconds, seconds of wall time less the wait for a core), setup
# included, summed over the unit's tests, longest first. A unit's CPU share (the first figure
# over the second) says whether it mostly computes or mostly waits (sleeps, emulators,
# playback at real time, a browser, other processes starting). The figures decide only the
# order of hand-out (:class:`_LongestFirst`); a unit missing here (under 3 s) counts as one
# that computes and goes after those listed, in file order. Measured in session 25's `make
# test PYTEST_ARGS=--cpu-durations=0` (2058 passed in 248.2 s); in session 27 the units that
# compute (wall less runq within 15 % of their CPU) were measured again (2144 tests, a machine
# loaded by other work: CPU time and wall less runq of computing units hold there, the wall
# of waiting units does not, so those keep session 25's figures), which lists
# test_cue_bound_rotation (8 s), test_optimal_solver_route (6 s), test_cue_bound_coupled and
# three more units that had come after every listed unit, and moves test_limiter_jerk from
# 10 s to 15 s; test_cue_bound, test_cue_bound_corr, test_cue_bound_rotation and
# test_platform_defaults with session 27's cuts subtracted; test_telemetry, test_wire_clock,
# test_limiter_jerk, test_easysmc_protocol and test_limiter with session 28's (CPU measured
# before and after on a busy machine) subtracted from both figures.
_UNITS: dict[str, tuple[float, float]] = {
    "tests/test_liveness.py": (14.9, 70.9),
    "tests/test_fault_injection.py": (8.6, 43.4),
    "tests/test_tune.py": (12.6, 28.2),
    "tests/test_browser_drawing.py": (6.1, 23.2),
    "tests/test_bridge.py": (7.3, 19.3),
    "tests/test_pipeline.py": (6.5, 16.3),
    "tests/test_easysmc_emulator.py": (0.4, 14.6),
    "tests/test_telemetry.py": (10.7, 13.9),
    "tests/test_safety_files.py": (10.7, 13.6),
    "tests/test_wire_clock.py": (12.7, 13.5),
    "tests/test_limiter_jerk.py": (13.3, 13.5),
    "tests/test_cue_bound_corr.py": (13.0, 13.3),
    "tests/test_docs.py::test_docs_build_with_warnings_as_errors": (9.1, 12.7),
    "tests/test_bridge_new_games.py": (3.7, 12.4),
    "tests/test_cue_bound.py": (12.1, 12.3),
    "tests/test_browser.py::test_view_renders_offline_plays_and_the_slider": (2.2, 12.3),
    "tests/test_browser.py::test_view_of_the_demo_ride_is_under_10_mb_and_renders": (5.2, 11.9),
    "tests/test_browser.py::test_play_cli_monitor_stop_parks_on_the_emulator": (3.4, 11.1),
    "tests/test_fk_rides.py": (7.0, 11.1),
    "tests/test_mpc_acceptance.py": (11.0, 11.0),
    "tests/test_browser.py::test_stop_button_parks_the_bridge": (3.1, 11.0),
    "tests/test_browser.py::test_stop_button_parks_a_play": (2.8, 10.7),
    "tests/test_easysmc_pipeline.py": (7.2, 10.7),
    "tests/test_viewer.py": (8.5, 10.0),
    "tests/test_extend_all.py": (6.0, 9.4),
    "tests/test_profiles.py": (2.4, 9.2),
    "tests/test_latency_acceptance.py": (2.8, 8.6),
    "tests/test_browser.py::test_monitor_renders_and_its_3d_view_follows_the_poses": (2.3, 8.3),
    "tests/test_corner4.py": (6.0, 8.1),
    "tests/test_omct.py": (7.2, 7.6),
    "tests/test_extend_cueing.py": (5.2, 7.5),
    "tests/test_sample_drives.py": (7.2, 7.5),
    "tests/test_strength_bound.py": (7.2, 7.3),
    "tests/test_cue_bound_rotation.py": (7.1, 7.2),
    "tests/test_vestibular_models.py": (6.6, 7.0),
    "tests/test_iface.py": (3.2, 6.5),
    "tests/test_compare.py": (6.0, 6.4),
    "tests/test_bridge_games.py": (1.8, 6.4),
    "tests/test_cli_defects.py": (3.3, 6.3),
    "tests/test_optimal_solver_route.py": (6.2, 6.2),
    "tests/test_cueing_filters.py": (5.7, 6.1),
    "tests/test_arrival.py": (2.2, 6.1),
    "tests/test_new_user.py": (3.8, 6.0),
    "tests/test_mpc.py": (3.2, 6.0),
    "tests/test_kinematics.py": (5.2, 5.9),
    "tests/test_cli_control.py": (1.1, 5.7),
    "tests/test_cue_acceptance.py": (5.3, 5.4),
    "tests/test_demo_held_up.py": (1.2, 5.1),
    "tests/test_cue_bound_coupled.py": (4.9, 5.0),
    "tests/test_intensity_rides.py": (4.9, 5.0),
    "tests/test_bridge_cli.py": (1.8, 4.9),
    "tests/test_shm_source.py": (2.6, 4.9),
    "tests/test_fuzz_inputs.py::test_mutated_config_files": (4.6, 4.8),
    "tests/test_platform_defaults.py": (4.6, 4.6),
    "tests/test_mpc_reference.py::test_tune_drives_an_optimal_preset": (4.6, 4.6),
    "tests/test_extend_platform_game.py": (2.8, 4.6),
    "tests/test_limiter.py": (4.3, 4.5),
    "tests/test_bridge_replay.py": (0.8, 4.5),
    "tests/test_trajectory_ride_qp.py": (4.2, 4.4),
    "tests/test_easysmc_protocol.py": (4.1, 4.3),
    "tests/test_cueing_cli.py": (3.2, 4.3),
    "tests/test_cli_pipeline.py": (3.1, 4.0),
    "tests/test_upsample.py": (3.5, 3.7),
    "tests/test_console_exit.py": (0.2, 3.6),
    "tests/test_mpc_tilt_fz.py": (3.4, 3.5),
    "tests/test_f1_orientation.py": (0.7, 3.4),
    "tests/test_optimal_fz_guard.py": (3.0, 3.1),
    "tests/test_optimal_working_set.py": (2.9, 3.0),
}
_WAITING_SHARE = 0.5
"""A unit whose CPU share is under this mostly waits: it can run beside the computing ones."""
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
    """The place of a test's unit in :data:`_UNITS` (their number for an unlisted one)."""
    for k, prefix in enumerate(_UNITS):
        if nodeid.startswith(prefix):
            return k
    return len(_UNITS)


def _cpu_share(unit: str) -> float:
    """The CPU share of a unit of work (:data:`_UNITS`; 1 for an unlisted one)."""
    k = _rank(unit)
    if k == len(_UNITS):
        return 1.0
    cpu_s, wall_s = list(_UNITS.values())[k]
    return cpu_s / wall_s


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _next_unit(waiting: list[str], running: list[str], cores: int) -> str:
    """The unit to hand to a worker asking for work: the first of ``waiting`` (the queue,
    longest first) that mostly waits when at least as many of the units ``running`` on the
    other workers compute as there are cores, else the first that computes; the first of the
    queue when there is none of the kind wanted.

    Chosen on a simulation of the run from session 25's figures per test (two cores shared
    fairly, xdist's hand-out): 4 workers in 224.6 s with the longest units first, 211.4 s
    with this choice (the CPU time alone needs 203 s); with every test's time changed at
    random by up to 30 % (the table left as it is) 11-17 s less in each of five draws."""
    computing = sum(_cpu_share(unit) >= _WAITING_SHARE for unit in running)
    busy = computing >= cores
    for unit in waiting:
        if (_cpu_share(unit) < _WAITING_SHARE) == busy:
            return unit
    return waiting[0]


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """``-n auto``: two workers per core (at most 16). About a third of the suite's time is
    waiting (sleeps, emulators, playback at real time, other processes starting), which a
    second worker on the core fills with another test."""
    return min(2 * _cores(), 16)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object:
    """``--dist loadscope``: :class:`_LongestFirst`; any other mode: xdist's own."""
    if config.getoption("dist", None) != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class _LongestFirst(LoadScopeScheduling):
        """Loadscope in the workers' (longest first) order, with :data:`_SPLIT` split, each
        unit chosen by :func:`_next_unit`: the units that mostly wait run beside those that
        compute instead of all at once (in session 25 the four that wait longest started
        together, and the first 30 s of the run left a core idle)."""

        def _split_scope(self, nodeid: str) -> str:
            return _unit_of(nodeid)

        def schedule(self) -> None:
            self.config.option.loadscopereorder = False  # keep the longest-first order
            super().schedule()

        def _assign_work_unit(self, node: Any) -> None:
            """xdist's own, but the unit chosen by :func:`_next_unit`, not the first."""
            assert self.workqueue
            running = []
            for other, work in self.assigned_work.items():
                if other is not node:  # its unit under way: the first with a test to run
                    running += [s for s, done in work.items() if not all(done.values())][:1]
            scope = _next_unit(list(self.workqueue), running, _cores())
            work_unit = self.workqueue.pop(scope)
            self.assigned_work.setdefault(node, {})[scope] = work_unit
            collection = self.registered_collections[node]
            node.send_runtest_some(
                [collection.index(nodeid) for nodeid, done in work_unit.items() if not done]
            )

    return _LongestFirst(config, log)
