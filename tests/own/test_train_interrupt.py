"""`connrl train` stopped by a signal or by a full disk (issue 24): one line saying what was (not) saved, no traceback,
and what is on disk is a loadable agent or nothing (no temporary files left behind)."""

from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

from tests import fault_tools as ft

TRAIN = ["train", "CartPole-v1", "--steps", "200000", "--quiet", "--save", "agent"]


def _start_training(cwd: Path) -> subprocess.Popen:
    # SIGINT back to its default in the child: a test run started in the background inherits it ignored, and
    # Python then never raises KeyboardInterrupt (as it would not for a user's backgrounded train)
    return subprocess.Popen([ft.PY, "-m", "connrl.cli", *TRAIN], cwd=cwd, env=ft.env(), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _cpu_seconds(pid: int) -> float | None:
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime + stime


def _wait_until_training(proc: subprocess.Popen, cpu: float = 6.0, timeout: float = 90.0) -> None:
    """Until the process has used ``cpu`` seconds of CPU (imports, warm-up and compiling take less: a whole
    2000-step `connrl train` takes about that), so it is inside learn() whatever the machine's load; without
    /proc, 4 s of wall time."""
    start = time.monotonic()
    while time.monotonic() - start < timeout:
        assert proc.poll() is None, f"train ended before the signal: {proc.returncode}, {proc.stderr.read()}"
        used = _cpu_seconds(proc.pid)
        if (used is None and time.monotonic() - start > 4.0) or (used is not None and used >= cpu):
            return
        time.sleep(0.1)
    pytest.fail(f"train did not get {cpu} s of CPU in {timeout} s")


@pytest.mark.parametrize("sig, codes", [(signal.SIGINT, (130,)), (signal.SIGTERM, (143, 1))],
                         ids=["SIGINT", "SIGTERM"])
def test_a_stopped_train_saves_a_loadable_agent_and_says_so(sig, codes, tmp_path):
    proc = _start_training(tmp_path)
    try:
        _wait_until_training(proc)
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    done = subprocess.CompletedProcess(proc.args, proc.returncode, out, err)
    ft.normal_exit(done)  # a negative code: the signal killed it without a handler
    assert "Traceback" not in err, ft.describe(done)
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("connrl: "), f"not one 'connrl: ' line: {ft.describe(done)}"
    assert "agent" in lines[0] and "saved" in lines[0], f"the line does not say what was saved: {ft.describe(done)}"
    assert done.returncode != 0, ft.describe(done)
    if done.returncode not in codes:
        pytest.fail(f"exit code {done.returncode}, expected one of {codes}: {ft.describe(done)}")
    assert (tmp_path / "agent" / "agent.json").is_file() and (tmp_path / "agent" / "agent.npz").is_file()
    assert not list((tmp_path / "agent").glob(".*.tmp")), "a temporary file was left behind"
    check = ft.cli(["evaluate", "agent", "--episodes", "1"], tmp_path)
    assert check.returncode == 0, f"the saved agent is not loadable: {ft.describe(check)}"


@pytest.fixture
def tiny_disk(tmp_path):
    """A 64 KiB tmpfs at tmp_path/disk (root only; skipped where it cannot be mounted)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    mount = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)], capture_output=True,
                           text=True)
    if mount.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here: {mount.stderr.strip() or mount.returncode}")
    try:
        yield disk
    finally:
        subprocess.run(["umount", "-l", str(disk)], capture_output=True)


def test_train_on_a_full_disk_says_the_agent_was_not_saved(tiny_disk, tmp_path):
    """The agent (replay memory and all) does not fit in 64 KiB: one line that it was not saved and why, no
    temporary file left, no traceback."""
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    proc = ft.cli(["train", "CartPole-v1", "--steps", "2000", "--quiet", "--save", tiny_disk / "agent"], cwd)
    ft.normal_exit(proc)
    assert "Traceback" not in proc.stderr, ft.describe(proc)
    assert proc.returncode in (1, 2), ft.describe(proc)
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("connrl: "), f"not one 'connrl: ' line: {ft.describe(proc)}"
    assert "not saved" in lines[0].lower() and ("space" in lines[0].lower() or "full" in lines[0].lower()), \
        f"the line does not say that the agent was not saved and why: {ft.describe(proc)}"
    left = [p.name for p in tiny_disk.rglob("*") if p.name.endswith(".tmp")]
    assert not left, f"temporary files left behind: {left}"


def test_a_signal_that_meets_a_checkpoint_waits_for_the_save_and_then_stops_training():
    from connrl.own.cli import _uninterrupted

    done = []
    before = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a foreground process
    mask = signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})  # a worker may have blocked them
    with pytest.raises(KeyboardInterrupt):
        with _uninterrupted(deliver=True):
            signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)  # arrives mid-save
            done.append("saved")
    assert done == ["saved"]
    with _uninterrupted(deliver=False):  # the final save: already stopping, nothing more to do
        signal.pthread_kill(threading.main_thread().ident, signal.SIGTERM)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    signal.pthread_sigmask(signal.SIG_SETMASK, mask)
    signal.signal(signal.SIGINT, before)
