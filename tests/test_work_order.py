"""The order in which ``make test`` hands out its units of work (tests/conftest.py).

A wrong choice fails no test of the package; it only makes the run longer (in session 25 the
four units that wait longest started together and left a core idle). So the choice itself is
checked here, on the measured table.
"""

from __future__ import annotations

import conftest as ct

LIVENESS = "tests/test_liveness.py"  # waits: CPU share 0.21
FAULTS = "tests/test_fault_injection.py"  # waits: CPU share 0.20
BOUND = "tests/test_cue_bound_corr.py"  # computes: CPU share 1.0
WIRE = "tests/test_wire_clock.py"  # computes: CPU share 0.98
UNLISTED = "tests/test_wrc.py"  # not in the table: counts as computing


def test_the_table_says_which_units_wait() -> None:
    assert ct._cpu_share(LIVENESS) < ct._WAITING_SHARE
    assert ct._cpu_share(FAULTS) < ct._WAITING_SHARE
    assert ct._cpu_share(BOUND) >= ct._WAITING_SHARE
    assert ct._cpu_share(UNLISTED) == 1.0
    # longest first: the table is in that order, and an unlisted unit goes last
    walls = [wall for _, wall in ct._UNITS.values()]
    assert walls == sorted(walls, reverse=True)
    assert ct._rank(UNLISTED) == len(ct._UNITS) > ct._rank(LIVENESS)


def test_a_waiting_unit_goes_beside_units_that_keep_every_core_busy() -> None:
    queue = [LIVENESS, FAULTS, BOUND, WIRE, UNLISTED]
    # two cores, both busy with computing units: the longest waiting unit
    assert ct._next_unit(queue, [BOUND, WIRE], cores=2) == LIVENESS
    # a core free (one computing unit and one waiting): the longest computing unit
    assert ct._next_unit(queue, [WIRE, FAULTS], cores=2) == BOUND
    assert ct._next_unit(queue, [], cores=2) == BOUND
    # none of the kind wanted left: the first of the queue
    assert ct._next_unit([UNLISTED, WIRE], [BOUND, WIRE], cores=2) == UNLISTED
    assert ct._next_unit([FAULTS], [LIVENESS], cores=2) == FAULTS
