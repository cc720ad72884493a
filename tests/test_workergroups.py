"""support.workergroups: the order in which ``pytest -n 2`` hands out its units of work, longest first."""
from __future__ import annotations

from collections import OrderedDict

from support.workergroups import SECONDS_PER_TEST, file_seconds_from_durations, longest_first, unit_seconds

MEASURED = {"a.py": 1.0, "b.py": 30.0, "c.py": 5.0}


def _queue(*units):
    """xdist's queue: each unit (scope, node ids) with every test not done yet, in xdist's order."""
    return OrderedDict((scope, {nodeid: False for nodeid in nodeids}) for scope, nodeids in units)


def test_the_longest_unit_goes_first_whatever_its_number_of_tests():
    # xdist's order, by number of tests: a.py (many short tests), then c.py, the group (b.py and c2.py), d.py
    queue = _queue(("a.py", [f"a.py::t{i}" for i in range(40)]),
                   ("c.py", ["c.py::t1", "c.py::t2"]),
                   ("group", ["b.py::t1", "c2.py::t1"]),
                   ("d.py", ["d.py::t1"]))
    # the group: b.py's 30 s and c2.py (not measured: one test's estimate); d.py, not measured, one test's
    assert unit_seconds(queue["group"], MEASURED) == 30.0 + SECONDS_PER_TEST
    assert unit_seconds(queue["d.py"], MEASURED) == SECONDS_PER_TEST
    ordered = longest_first(queue, MEASURED)
    assert list(ordered) == ["group", "c.py", "a.py", "d.py"]
    assert ordered["a.py"] == queue["a.py"]  # the units themselves are handed on as they were


def test_units_of_the_same_estimate_keep_xdists_order():
    queue = _queue(("x.py", ["x.py::t1", "x.py::t2"]), ("y.py", ["y.py::t1", "y.py::t2"]))
    assert list(longest_first(queue, {})) == ["x.py", "y.py"]


def test_the_table_is_read_from_a_durations_report():
    report = """============================= slowest durations ==============================
12.50s call     tests/a.py::test_one[1]
0.40s setup    tests/a.py::test_one[1]
0.10s teardown tests/a.py::test_one[1]
3.00s call     tests/b/test_c.py::Test::test_two
(2 durations < 0.005s hidden.  Use -vv to show these durations.)
2 passed in 16.00s"""
    assert file_seconds_from_durations(report) == {"tests/a.py": 13.0, "tests/b/test_c.py": 3.0}
