"""The run's Dask cluster (support.daskcluster): started on demand, stopped once no test left needs it."""
from __future__ import annotations

from support import daskcluster
from support.daskcluster import SessionCluster, done_with_cluster, last_user

ORDER = ["a.py::t1", "b.py::t1", "b.py::t2", "c.py::t1", "d.py::t1"]
USERS = {"b.py::t1", "c.py::t1"}
GROUP = {"b.py", "c.py"}  # files naming the cluster: b.py::t2 does without it


def test_in_one_process_the_cluster_stops_after_the_last_test_asking_for_it():
    last = last_user(ORDER, USERS.__contains__)
    assert last == "c.py::t1" and last_user(ORDER, lambda nodeid: False) is None
    stops = [done_with_cluster(n, m, last, False, GROUP.__contains__) for n, m in zip(ORDER, ORDER[1:] + [None])]
    # not between the group's files (b.py::t2 is followed by c.py's user); after the last user; at the end
    assert stops == [False, False, False, True, True]


def test_under_file_groups_the_cluster_stops_when_the_next_file_is_outside_the_group():
    # a worker's order under -n 2's file groups: the whole group in one piece, other files before and after;
    # the run's last user (of every worker's tests together) is elsewhere
    order = ["a.py::t1", "b.py::t1", "b.py::t2", "c.py::t1", "d.py::t1", "e.py::t1"]
    stops = [done_with_cluster(n, m, "z.py::t9", True, GROUP.__contains__) for n, m in zip(order, order[1:] + [None])]
    assert stops == [False, False, False, True, True, True]
    # without file groups the same order keeps it until the run's last user
    assert not any(done_with_cluster(n, m, "z.py::t9", False, GROUP.__contains__) for n, m in zip(order, order[1:]))


def test_the_session_cluster_starts_on_demand_and_again_after_a_stop(monkeypatch):
    events = []

    def fake_cluster(factory):
        events.append("start")
        try:
            yield ("tcp://127.0.0.1:1", factory, [])
        finally:
            events.append("stop")

    monkeypatch.setattr(daskcluster, "cluster", fake_cluster)
    holder = SessionCluster("folder")
    assert not holder.running and events == []
    assert holder.get() == holder.get() == ("tcp://127.0.0.1:1", "folder", [])
    assert holder.running and events == ["start"]
    holder.stop()
    holder.stop()  # stopping a stopped cluster does nothing
    assert not holder.running and events == ["start", "stop"]
    holder.get()
    assert events == ["start", "stop", "start"] and holder.starts == 2


def test_the_cluster_processes_run_without_the_dashboard_diagnostics(dask_cluster):
    # the settings reach the real scheduler and workers (and a setting of the user's own is kept)
    import dask
    from distributed import Client

    from support.daskcluster import quiet_environment

    def settings():
        return (dask.config.get("distributed.worker.profile.enabled"),
                dask.config.get("distributed.admin.tick.interval"),
                dask.config.get("distributed.admin.system-monitor.interval"))

    with Client(dask_cluster[0], timeout="30s", set_as_default=False) as client:
        seen = [client.run_on_scheduler(settings), *client.run(settings).values()]
    assert len(seen) == 3 and all(s == (False, "1s", "5s") for s in seen), seen
    mine = {"DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL": "50ms"}
    assert quiet_environment(mine)["DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL"] == "50ms"
