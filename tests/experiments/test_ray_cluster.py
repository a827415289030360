"""``--executor ray --address``: a head started with ``ray start --head`` on loopback, with token authentication on
(as on any machine where Ray ran locally once: it wrote ``~/.ray/auth_token``), gives the process pool's runs; a
driver it refuses hears why in one line, at once."""

import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

import connrl

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="the head's processes are found through /proc")
REPO = Path(connrl.__file__).resolve().parents[1]
HEAD_START_TIMEOUT_S = 60


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _env(home: Path, **extra) -> dict:
    """This machine's environment without any Ray settings, with ``home`` as HOME (its ``.ray/auth_token``)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("RAY_")}
    return {**env, "HOME": str(home), **extra}


def _kill_session(sid: int) -> None:
    """SIGKILL every process of the head's session (ray start, GCS, raylet, agents, workers), and only those:
    `ray stop` would stop every Ray instance on the machine, a parallel test's too."""
    for _ in range(3):  # a worker could be starting while we look
        pids = []
        for d in Path("/proc").iterdir():
            try:
                if d.name.isdigit() and os.getsid(int(d.name)) == sid:
                    pids.append(int(d.name))
            except OSError:
                pass
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        if not pids:
            return
        time.sleep(0.2)


@pytest.fixture
def head():
    """A Ray head on 127.0.0.1 whose HOME holds a token, so it starts with token authentication on."""
    pytest.importorskip("ray")
    ray_cli = Path(sys.executable).with_name("ray")
    if not ray_cli.exists():
        pytest.skip("no `ray` command beside this Python")
    root = Path(tempfile.mkdtemp(prefix="connrl-ray-", dir="/tmp"))  # short: Ray's socket paths are limited
    (root / "home" / ".ray").mkdir(parents=True)
    (root / "home" / ".ray" / "auth_token").write_text(secrets.token_hex(16))
    port = _free_port()
    log = root / "head.log"
    with open(log, "w") as out:
        proc = subprocess.Popen([str(ray_cli), "start", "--head", "--block", "--port", str(port),
                                 "--node-ip-address", "127.0.0.1", "--num-cpus", "2", "--include-dashboard", "false",
                                 "--disable-usage-stats", "--temp-dir", str(root / "ray")],
                                env=_env(root / "home"), stdout=out, stderr=subprocess.STDOUT,
                                start_new_session=True)  # its own session: the cleanup finds its processes by it
    try:
        t0 = time.monotonic()
        while "Ray runtime started" not in log.read_text():
            if proc.poll() is not None or time.monotonic() - t0 > HEAD_START_TIMEOUT_S:
                pytest.fail(f"ray start --head did not start:\n{log.read_text()[-2000:]}")
            time.sleep(0.1)
        yield f"127.0.0.1:{port}", root / "home"
    finally:
        _kill_session(proc.pid)
        proc.wait(timeout=10)
        shutil.rmtree(root, ignore_errors=True)


def _connrl(*calls: tuple[list[str], dict], timeout: float = 120) -> list[tuple[int, str, float]]:
    """``connrl ARGS`` with each (ARGS, environment), side by side; (exit status, stderr, seconds) of each."""
    logs = [tempfile.TemporaryFile("w+") for _ in calls]  # not pipes: a full pipe would stall its process
    t0 = time.monotonic()
    # from the repository: the driver imports this connrl, and Ray gives its workers the driver's folder too
    procs = [subprocess.Popen([sys.executable, "-c", "import sys; from connrl.cli import main; sys.exit(main())",
                               *args], cwd=REPO, env=env, stdout=subprocess.DEVNULL, stderr=log)
             for (args, env), log in zip(calls, logs, strict=True)]
    took: dict[int, float] = {}
    try:
        while len(took) < len(procs) and time.monotonic() - t0 < timeout:
            for i, p in enumerate(procs):
                if i not in took and p.poll() is not None:
                    took[i] = time.monotonic() - t0
            time.sleep(0.1)
        assert len(took) == len(procs), f"connrl still running after {timeout} s"
        for log in logs:
            log.seek(0)
        return [(p.returncode, log.read(), took[i]) for i, (p, log) in enumerate(zip(procs, logs, strict=True))]
    finally:
        for p, log in zip(procs, logs, strict=True):
            p.kill()
            p.wait()
            log.close()


def _per_run(out: Path) -> dict:
    summary = json.loads((out / "pole-full" / "summary.json").read_text())
    return {v: {q: x["per_run"] for q, x in d["quantities"].items()} for v, d in summary["variants"].items()}


def test_ray_start_head_then_address_gives_the_pools_runs_and_a_refused_driver_one_line(head, tmp_path):
    # one test, all its commands side by side: one head (under xdist, two tests could start one each)
    address, home = head
    run = ["run", "pole-full", "--profile", "tiny", "--runs", "2", "--quiet"]
    (tmp_path / "bare").mkdir()  # a machine where Ray never ran: no ~/.ray/auth_token
    refusals = {"requires token authentication and this machine has no token; set RAY_AUTH_TOKEN": {},
                "refused this machine's token": {"RAY_AUTH_TOKEN": "not-the-heads-token"},
                "RAY_AUTH_MODE=disabled here; unset it and set RAY_AUTH_TOKEN": {"RAY_AUTH_MODE": "disabled"}}
    by_ray, by_pool, *refused = _connrl(
        ([*run, "--executor", "ray", "--address", address, "--out", str(tmp_path / "ray")], _env(home)),
        ([*run, "--workers", "2", "--out", str(tmp_path / "pool")], _env(home)),
        *[([*run, "--executor", "ray", "--address", address, "--out", str(tmp_path / f"refused{i}")],
           _env(tmp_path / "bare", **extra)) for i, extra in enumerate(refusals.values())])

    assert by_ray[0] == 0 and "InvalidAuthToken" not in by_ray[1], by_ray[1][-2000:]
    assert by_pool[0] == 0, by_pool[1][-2000:]
    assert _per_run(tmp_path / "ray") == _per_run(tmp_path / "pool")
    pool_csvs = sorted((tmp_path / "pool" / "pole-full").rglob("*.csv"))
    assert len(pool_csvs) == 2  # the driver wrote both runs' learning curves, trial by trial the pool's
    for pool in pool_csvs:
        ray = tmp_path / "ray" / pool.relative_to(tmp_path / "pool")
        assert ray.read_text() == pool.read_text()

    for says, (code, err, took) in zip(refusals, refused, strict=True):
        lines = err.strip().splitlines()  # one line, nothing of Ray's own (it retries for 20 s, logging each try)
        assert code != 0 and len(lines) == 1, err[-2000:]
        assert lines[0].startswith(f"connrl: the Ray cluster at {address} ") and says in lines[0]
        assert took < 60  # loose for a loaded machine: Ray's own 20 s of retries would break the one line
    assert not any((tmp_path / f"refused{i}").exists() for i in range(len(refusals)))


def test_a_port_that_is_not_a_ray_head_is_refused_within_the_timeout(monkeypatch):
    pytest.importorskip("ray")
    from connrl.experiments.guards import ExecutorError, check_ray_cluster

    monkeypatch.setenv("RAY_AUTH_MODE", "disabled")  # leaves this process's Ray settings as they are
    with socket.socket() as server:  # accepts connections, speaks no gRPC
        server.bind(("127.0.0.1", 0))
        server.listen()
        address = f"127.0.0.1:{server.getsockname()[1]}"
        t0 = time.monotonic()
        with pytest.raises(ExecutorError, match="accepts connections but does not answer as a Ray cluster's head"):
            check_ray_cluster(address, timeout=1)
        assert time.monotonic() - t0 < 15  # loading Ray, then the 1 s timeout (Ray alone retries for 40 s)
