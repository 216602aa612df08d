"""mi-brdfs fit on a Dask cluster (issue 26, point 5): a malformed address is
refused before anything connects, a scheduler without a worker ends the
command with one line, and a worker lost mid-sweep has its task run again
elsewhere, which the records and the report say."""
import os
import signal
import threading
import time

import pytest

from mi_brdfs.tools import cli
from mi_brdfs.tools.fit import models, report, sweep, targets, task

distributed = pytest.importorskip("distributed")

TINY = task.QUICK.replace(viewers=(4, 2), uniform=(4, 4), lobe=4, scan=2, starts=1, steps=0,
                          res=24, spp=4, cost=False)


def one_line_error(capsys, args: list[str]) -> str:
    code = cli.main(["fit", *args])
    err = capsys.readouterr().err.strip()
    assert code == 1 and len(err.splitlines()) == 1, err
    return err


@pytest.mark.parametrize("address, message", [
    ("foo://bar", "--scheduler foo://bar: unknown protocol 'foo'; valid: "),
    ("tcp://127.0.0.1:notaport", "'127.0.0.1:notaport' is not HOST:PORT"),
    ("tcp://:8786", "is not HOST:PORT"),
])
def test_a_malformed_address_is_refused_before_connecting(tmp_path, capsys, monkeypatch,
                                                          address, message):
    def refuse(*args, **kwargs):
        raise AssertionError("a malformed address must not be connected to")
    monkeypatch.setattr(distributed, "Client", refuse)
    err = one_line_error(capsys, ["diffuse:", "-o", str(tmp_path / "r"), "--scheduler", address])
    assert message in err and not (tmp_path / "r").exists()


def test_a_scheduler_without_a_worker_ends_with_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sweep, "WORKER_TIMEOUT", 2.0)
    with distributed.LocalCluster(n_workers=0, dashboard_address=None) as cluster:
        err = one_line_error(capsys, ["diffuse:", "-o", str(tmp_path / "r"), "--scheduler",
                                      cluster.scheduler_address])
    assert "no worker joined the scheduler in 2 s" in err and not (tmp_path / "r").exists()


def kill_a_busy_worker(client, pids: dict, killed: list, stop: threading.Event) -> None:
    """Kill (SIGKILL) the first worker seen running a task: a worker lost mid-task."""
    while not stop.is_set():
        busy = [address for address, keys in client.processing().items() if keys]
        if busy:
            os.kill(pids[busy[0]], signal.SIGKILL)
            killed.append(pids[busy[0]])
            return
        time.sleep(0.05)


def test_a_lost_worker_has_its_task_run_again_and_the_report_says_so(tmp_path):
    tasks = [(t, m) for t in targets.parse(["diffuse:reflectance=[0.7,0.5,0.3]"])
             for m in models.select(["lambert", "oren_nayar", "phong", "ward"])]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        client = distributed.Client(cluster)
        pids = client.run(os.getpid)
        killed, stop = [], threading.Event()
        killer = threading.Thread(target=kill_a_busy_worker, args=(client, pids, killed, stop))
        killer.start()
        try:
            records = sweep.run_fits(tasks, TINY, scheduler=cluster.scheduler_address,
                                     client=client)
        finally:
            stop.set()
            killer.join()
            client.close()
    assert killed, "no worker was seen busy"
    assert len(records) == len(tasks) and not [r for r in records if "error" in r]
    rerun = [r for r in records if r.get("reruns")]
    assert rerun, [r.get("reruns") for r in records]
    assert all(not r["worker"].endswith(f":{killed[0]}") for r in rerun)   # finished elsewhere
    report.write(str(tmp_path), records, TINY, "test")
    assert "re-run after its worker was lost" in (tmp_path / "index.html").read_text()
