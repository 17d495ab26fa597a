"""A sweep on a cluster of separate processes, started as docs/guide/cluster.md starts one (a ``dask scheduler``
and ``dask worker`` processes with vibkit's preload), gives the numbers of the same sweep run in this process; and
where runs go when nothing is said: in this process while a cluster would not pay."""

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import vibkit
from vibkit.runtime import cluster

SW = sys.modules["vibkit.sweep.run"]
ROOT = Path(__file__).resolve().parents[2]

# the no-load forward scene, 0.3 s from 0.5 m/s, delta only: a run takes milliseconds
SCENE = (ROOT / "sim" / "thesis-forward.toml").read_text()
VARY = {"effects.contact.stiffness": "5e5:2e6:4"}


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    import tomllib

    from vibkit.sweep.plan import to_toml

    data = tomllib.loads(SCENE)
    data["run"].update(duration=0.3, initial_speed=0.5)
    data["outputs"] = {"variables": ["delta"]}
    p = tmp_path_factory.mktemp("cluster") / "scene.toml"
    p.write_text(to_toml(data))
    return p


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _same_numbers(a, b):
    assert set(a.data_vars) == set(b.data_vars)
    for name in a.data_vars:
        if name == "wall_time":
            continue
        x, y = a[name].values, b[name].values
        if x.dtype.kind == "f":
            np.testing.assert_array_equal(x, y, err_msg=name)  # bit for bit: the same arithmetic
        else:
            assert (x == y).all(), name


def _stop(proc):
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(timeout=20)


@pytest.mark.slow  # 20 to 50 s on two loaded cores: the scheduler and two workers start, each imports vibkit
@pytest.mark.filterwarnings("ignore::ResourceWarning")
def test_sweep_on_scheduler_and_worker_processes_equals_the_sweep_in_process(scene_file, tmp_path):
    from distributed import Client

    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    addr = f"tcp://127.0.0.1:{_free_port()}"
    port = addr.rsplit(":", 1)[1]
    common = dict(env=env, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    scheduler = subprocess.Popen(
        [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", port]
        + ["--no-dashboard"],
        **common,
    )
    workers = None
    try:
        workers = subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", addr, "--nworkers", "2", "--nthreads", "1"]
            + ["--preload", "vibkit.sweep.worker_preload", "--no-dashboard", "--local-directory", str(tmp_path)],
            **common,
        )
        with Client(addr, timeout=60) as c:
            c.wait_for_workers(2, timeout=120)
            pids = set(c.run(os.getpid).values())
            # the preload ran in each worker as it started: the simulation imported and its kernels loaded
            loaded = c.run(lambda: "vibkit.analyses.simulation" in sys.modules and "vibkit.fleet.scan" in sys.modules)
            assert all(loaded.values()) and len(pids) == 2 and os.getpid() not in pids
        t0 = time.perf_counter()
        on_cluster = vibkit.sweep(scene_file, VARY, scheduler=addr, progress=False)
        wall = time.perf_counter() - t0
        here = vibkit.sweep(scene_file, VARY, parallel=False, progress=False)
        _same_numbers(on_cluster, here)
        assert int((on_cluster.status == 0).sum()) == 4
        assert wall < 60  # the workers were warm: no kernel compiled or loaded per run
    finally:
        if workers is not None:
            _stop(workers)
        _stop(scheduler)
    assert scheduler.poll() is not None and workers.poll() is not None


def test_a_small_sweep_runs_in_this_process_without_a_cluster(scene_file, monkeypatch):
    def no_cluster(*a, **k):
        raise AssertionError("a cluster was started for a sweep that does not pay for one")

    monkeypatch.setattr(SW, "dask_client", no_cluster)
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "")
    ds = vibkit.sweep(scene_file, VARY, progress=False)
    assert int((ds.status == 0).sum()) == 4 and ds.attrs["runs_computed"] == 4


def test_a_sweep_hands_its_runs_to_a_cluster_where_that_pays(scene_file, monkeypatch):
    """With a start-up of no cost the rule sends the runs left after the first two to the cluster."""
    import contextlib

    from distributed import Client

    monkeypatch.setattr(cluster, "LOCAL_CLUSTER_START_S", 0.0)
    with Client(processes=False, n_workers=2, threads_per_worker=1, dashboard_address=":0") as c:
        monkeypatch.setattr(SW, "dask_client", lambda scheduler=None, n_workers=None: contextlib.nullcontext(c))
        sent = []
        real = SW._submit

        def submit(client, tasks, *args):
            tasks = list(tasks)
            sent.extend(t["index"] for t in tasks)
            return real(client, iter(tasks), *args)

        monkeypatch.setattr(SW, "_submit", submit)
        ds = vibkit.sweep(scene_file, VARY, n_workers=2, progress=False)
    assert sent == [2, 3] and ds.attrs["runs_computed"] == 4  # two here, then the two left on the cluster
    _same_numbers(ds, vibkit.sweep(scene_file, VARY, parallel=False, progress=False))


def test_the_rule_shares_the_work_after_the_start_up():
    s = cluster.LOCAL_CLUSTER_START_S
    assert not cluster.dask_pays(1e9, 1)  # one worker does the same work after the start-up
    assert not cluster.dask_pays(1.9 * s, 2) and cluster.dask_pays(2.1 * s, 2)  # half the work saved
    assert not cluster.dask_pays(1.3 * s, 4) and cluster.dask_pays(1.4 * s, 4)  # three quarters saved: 4/3 s
