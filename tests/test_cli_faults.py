"""Bad input and faults through the CLI: one clear line, refused before any compute, nothing lost.

Each test asserts the message and that nothing was written or lost; every one of them fails on e172482.
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from connrl import cli
from tests.tiny_runs import run_tiny


def _one_line(exc: SystemExit) -> str:
    text = str(exc.code)
    assert text.startswith("connrl: ") and "\n" not in text and "Traceback" not in text
    return text


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


# ------------------------------------------------------------------------------------------- output folder

@pytest.mark.parametrize("command", [["run", "pole-full", "--profile", "tiny"],
                                     ["sweep", "pole-full", "--set", "max_trials=2", "--seeds", "0:1"]])
def test_an_output_folder_that_is_a_file_is_refused_before_any_run(command, tmp_path, monkeypatch):
    import connrl.experiments.runner as runner

    monkeypatch.setattr(runner, "execute_job", lambda job: pytest.fail("a run started"))
    target = tmp_path / "out.txt"
    target.write_text("keep me")
    for out, reason in ((target, "is a file, not a folder"), (target / "sub", "Not a directory")):
        with pytest.raises(SystemExit) as e:
            cli.main([*command, "--out", str(out), "--quiet", "--workers", "1"])
        assert f"cannot write to {out}: " in _one_line(e.value) and reason in str(e.value.code)
    assert target.read_text() == "keep me" and sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


def test_results_refuses_a_page_it_cannot_write(tmp_path):
    run_tiny("pole-full", tmp_path / "runs")
    (tmp_path / "docs").write_text("a file")
    with pytest.raises(SystemExit) as e:
        cli.main(["results", "--out", str(tmp_path / "runs"), "--doc", str(tmp_path / "docs" / "RESULTS.md")])
    assert f"cannot write to {tmp_path / 'docs'}" in _one_line(e.value)
    assert (tmp_path / "docs").read_text() == "a file"
    (tmp_path / "folder").mkdir()
    with pytest.raises(SystemExit) as e:
        cli.main(["results", "--out", str(tmp_path / "runs"), "--doc", str(tmp_path / "folder")])
    assert "it is a folder; --doc takes a Markdown file" in _one_line(e.value)


@pytest.mark.parametrize("make", [lambda p: None, lambda p: p.mkdir()])
def test_results_without_stored_runs_is_refused(make, tmp_path):
    make(tmp_path / "runs")
    with pytest.raises(SystemExit) as e:
        cli.main(["results", "--out", str(tmp_path / "runs"), "--doc", str(tmp_path / "RESULTS.md")])
    assert f"no stored results in {tmp_path / 'runs'}" in _one_line(e.value)
    assert not (tmp_path / "RESULTS.md").exists()


def test_results_writes_beside_the_runs_unless_asked(tmp_path, capsys):
    out = tmp_path / "runs"
    run_tiny("pole-full", out)
    assert cli.main(["results", "--out", str(out)]) == 0
    assert (out / "RESULTS.md").exists() and capsys.readouterr().out.strip() == str(out / "RESULTS.md")
    assert not Path("docs/RESULTS.md").is_relative_to(out)
    with pytest.raises(SystemExit):
        cli.main(["results", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "by default OUT/RESULTS.md beside the runs" in help_text and "--doc docs/RESULTS.md" in help_text


# ----------------------------------------------------------------------------------------- damaged results

DAMAGE = {"truncated": lambda b: b[: len(b) // 2], "empty": lambda b: b"", "list": lambda b: b"[]",
          "object": lambda b: b"{}", "binary": lambda b: bytes(range(256)),
          "missing key": lambda b: json.dumps({k: v for k, v in json.loads(b).items() if k != "metrics"}).encode()}


@pytest.mark.parametrize("kind", sorted(DAMAGE))
def test_run_redoes_a_damaged_record_and_says_so(kind, tmp_path, capsys):
    out = tmp_path / "runs"
    assert cli.main(["run", "pole-full", "--profile", "tiny", "--out", str(out), "--quiet", "--workers", "1"]) == 0
    record = next(out.rglob("seed-0.json"))
    good = json.loads(record.read_text())
    record.write_bytes(DAMAGE[kind](record.read_bytes()))
    capsys.readouterr()
    assert cli.main(["run", "pole-full", "--profile", "tiny", "--out", str(out), "--quiet", "--workers", "1"]) == 0
    err = capsys.readouterr().err
    assert f"connrl: {record} is damaged (" in err and "redoing that run" in err
    redone = json.loads(record.read_text())
    assert redone["curve_y"] == good["curve_y"] and redone["metrics"] == good["metrics"]


def test_run_redoes_a_record_whose_csv_is_gone(tmp_path, capsys):
    out = tmp_path / "runs"
    cli.main(["run", "pole-full", "--profile", "tiny", "--out", str(out), "--quiet", "--workers", "1"])
    next(out.rglob("seed-0.csv")).unlink()
    capsys.readouterr()
    cli.main(["run", "pole-full", "--profile", "tiny", "--out", str(out), "--quiet", "--workers", "1"])
    assert "its CSV seed-0.csv is gone); redoing that run" in capsys.readouterr().err
    assert next(out.rglob("seed-0.csv")).exists()


@pytest.mark.parametrize("kind", sorted(DAMAGE))
@pytest.mark.parametrize("command", ["show", "plot"])
def test_show_and_plot_name_a_damaged_summary_and_how_to_rebuild_it(kind, command, tmp_path):
    out = tmp_path / "runs"
    run_tiny("pole-full", out)
    summary = out / "pole-full" / "summary.json"
    summary.write_bytes(DAMAGE[kind](summary.read_bytes()) if kind != "missing key" else
                        json.dumps({k: v for k, v in json.loads(summary.read_text()).items() if k != "variants"})
                        .encode())
    before = _files(out)
    with pytest.raises(SystemExit) as e:
        cli.main([command, "pole-full", "--out", str(out)])
    msg = _one_line(e.value)
    assert f"{summary} is damaged (" in msg and "run the `connrl run pole-full` command that made it again" in msg
    assert _files(out) == before


def test_plot_warns_when_it_draws_fewer_runs_than_the_summary_lists(tmp_path, capsys):
    out = tmp_path / "runs"
    assert cli.main(["run", "pole-full", "--profile", "tiny", "--runs", "2", "--out", str(out), "--quiet",
                     "--workers", "1"]) == 0
    next(out.rglob("seed-1.json")).unlink()
    capsys.readouterr()
    assert cli.main(["plot", "pole-full", "--out", str(out)]) == 0
    assert "1 of the 2 runs in pole-full's summary are missing or damaged" in capsys.readouterr().err


def test_one_damaged_summary_leaves_out_its_section_not_the_page(tmp_path, capsys):
    out = tmp_path / "runs"
    run_tiny("pole-full", out)
    run_tiny("cup-task1", out)
    (out / "cup-task1" / "summary.json").write_text("{")
    assert cli.main(["results", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"{out / 'cup-task1' / 'summary.json'} is damaged (not JSON" in err and "left out of the page" in err
    page = (out / "RESULTS.md").read_text()
    assert "### pole-full:" in page and "Task 1: 2-cup collection" not in page


# -------------------------------------------------------------------------------------------- divergence

@pytest.mark.parametrize("value", ["1e400", "-1e400", "NaN"])
def test_a_non_finite_learning_rate_is_refused_before_any_run(value, tmp_path):
    with pytest.raises(SystemExit) as e:
        cli.main(["sweep", "pole-full", "--set", f"lr={value}", "--seeds", "0:1", "--out", str(tmp_path)])
    assert "parameter lr must be a finite number" in _one_line(e.value)
    assert not any(tmp_path.iterdir())


def test_an_exploding_run_is_recorded_as_diverged_not_as_slow(tmp_path, capsys):
    out = tmp_path / "runs"
    assert cli.main(["sweep", "pole-full", "--set", "lr=1e6", "--set", "max_trials=5", "--set", "test_steps=200",
                     "--seeds", "0:1", "--out", str(out), "--quiet", "--workers", "1"]) == 0
    assert "per run: diverged (trial 1)" in capsys.readouterr().out
    record = json.loads(next(out.rglob("seed-0.json")).read_text())
    assert record["diverged"]["trial"] == 1 and "exploding weights" in record["diverged"]["reason"]
    summary = json.loads(next(out.glob("sweep-pole-full-*/summary.json")).read_text())
    assert summary["variants"]["sweep"]["diverged"] == [1]


# ------------------------------------------------------------------------------------------- output text

def test_show_says_which_way_is_better_and_cuts_nothing(tmp_path, capsys):
    out = tmp_path / "runs"
    run_tiny("survival-planning", out)
    capsys.readouterr()
    assert cli.main(["show", "survival-planning", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "hypothetical_per_step_first20 (higher is better)" in text
    assert "hypothetical_per_step_last20 (lower is better)" in text
    assert "tiny profile (not the thesis's protocol: that is --profile full)" in text


def test_meets_thesis_on_a_quick_profile_says_it_is_not_the_protocol(tmp_path, capsys):
    from connrl.report.page import meets, summary_table

    q = {"meets_thesis": True}
    assert meets(q, "full") == "yes" and meets(q, "quick") == "yes (quick profile: not the thesis's protocol)"
    out = tmp_path / "runs"
    run_tiny("pole-full", out)
    table = summary_table(json.loads((out / "pole-full" / "summary.json").read_text()))
    assert "| lower |" in table


def test_numba_compile_time_is_kept_apart_from_a_runs_wall_time():
    from types import SimpleNamespace

    from connrl.experiments.runner import compile_seconds

    def ev(start):
        return SimpleNamespace(is_start=start)

    # an outer compile 0..3 s with a nested one 1..2 s, then another 10..10.5 s: 3.5 s in all
    events = [(0.0, ev(True)), (1.0, ev(True)), (2.0, ev(False)), (3.0, ev(False)), (10.0, ev(True)),
              (10.5, ev(False))]
    assert compile_seconds(events) == pytest.approx(3.5)


def test_gitignore_and_readme_use_a_venv():
    root = Path(__file__).resolve().parents[1]
    assert ".venv/" in (root / ".gitignore").read_text().split()
    readme = (root / "README.md").read_text()
    run_cmd = next(line for line in readme.splitlines() if "connrl run pole-full" in line and "pip" in line)
    test_cmd = next(line for line in readme.splitlines() if "pytest" in line and "pip" in line)
    for cmd in (run_cmd, test_cmd):
        assert cmd.startswith("python3 -m venv .venv && . .venv/bin/activate && ")
    assert test_cmd in (root / ".ci" / "run").read_text()


# ---------------------------------------------------------------------------------------------- orphans

def _children(pid: int) -> list[int]:
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"  # a zombie has exited; only its parent's bookkeeping is left


def _terminal_sigint() -> None:
    """In the child before exec: SIGINT as a terminal leaves it (default action, not blocked), whatever the test
    process's own state (a pytest worker that has run other tests may block or ignore it; both are inherited)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def _signal_state(pid: int) -> str:
    try:
        return " ".join(line.strip() for line in open(f"/proc/{pid}/status") if line.startswith(("SigBlk", "SigIgn",
                                                                                                 "SigCgt", "SigPnd")))
    except OSError:
        return "(no /proc status)"


def _run_with_two_workers(out: Path) -> tuple[subprocess.Popen, list[int]]:
    """``connrl run`` of a long experiment (pole-full-ahc never solves: every run takes 1000 trials) in its own
    process group, once both worker processes run."""
    parent = subprocess.Popen([sys.executable, "-m", "connrl.cli", "run", "pole-full-ahc", "--profile", "full",
                               "--out", str(out), "--workers", "2", "--quiet"], stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, start_new_session=True, preexec_fn=_terminal_sigint,
                              env={**os.environ, "PYTHONFAULTHANDLER": "1"})  # SIGABRT dumps its stacks
    deadline = time.time() + 120
    workers: list[int] = []
    while time.time() < deadline and len(workers) < 2:
        time.sleep(0.2)
        workers = [c for c in _children(parent.pid) if _alive(c)]
    if len(workers) < 2:
        os.killpg(parent.pid, signal.SIGKILL)
        pytest.fail("the workers did not start")
    time.sleep(1.0)
    return parent, workers


@pytest.mark.skipif(not Path("/proc").exists(), reason="needs /proc")
def test_workers_exit_when_the_parent_is_killed(tmp_path):
    out = tmp_path / "runs"
    parent, workers = _run_with_two_workers(out)
    try:
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait()
        deadline = time.time() + 5
        while time.time() < deadline and any(_alive(w) for w in workers):
            time.sleep(0.1)
        assert not any(_alive(w) for w in workers), "workers outlived their parent"
        written = _files(out) if out.exists() else {}
        time.sleep(1.5)
        assert (_files(out) if out.exists() else {}) == written, "files were written after the workers should be gone"
    finally:
        if parent.poll() is None:
            os.killpg(parent.pid, signal.SIGKILL)
        shutil.rmtree(out, ignore_errors=True)


def test_the_results_page_shows_a_diverged_run(tmp_path):
    from connrl.report.page import write_results

    out = tmp_path / "runs"
    run_tiny("pole-full", out)
    path = out / "pole-full" / "summary.json"
    summary = json.loads(path.read_text())
    summary["variants"]["QCON-R"]["diverged"] = [2]
    path.write_text(json.dumps(summary))
    page = write_results(out, tmp_path / "RESULTS.md").read_text()
    assert "**Diverged:** `pole-full`, QCON-R, seed 0: the networks diverged after training trial 2" in page


# --------------------------------------------------------------------- found by the independent audit

def test_a_path_in_the_way_below_out_is_refused_before_any_run(tmp_path, monkeypatch):
    import connrl.experiments.runner as runner

    monkeypatch.setattr(runner, "execute_job", lambda job: pytest.fail("a run started"))
    (tmp_path / "pole-full").write_text("x")
    with pytest.raises(SystemExit) as e:
        cli.main(["run", "pole-full", "--profile", "tiny", "--out", str(tmp_path), "--quiet", "--workers", "1"])
    assert f"cannot write to {tmp_path / 'pole-full'}" in _one_line(e.value)
    (tmp_path / "pole-full").unlink()
    (tmp_path / "pole-full" / "summary.json").mkdir(parents=True)
    with pytest.raises(SystemExit) as e:
        cli.main(["run", "pole-full", "--profile", "tiny", "--out", str(tmp_path), "--quiet", "--workers", "1"])
    assert "summary.json: a folder is in the way" in _one_line(e.value)


INSIDE = {"quantity not an object": lambda s: s["variants"]["QCON-R"]["quantities"].update(trials_to_satisfactory="x"),
          "per_run a number": lambda s: s["variants"]["QCON-R"]["quantities"]["trials_to_satisfactory"].update(
              per_run=5),
          "per_run text": lambda s: s["variants"]["QCON-R"]["quantities"]["trials_to_satisfactory"].update(
              per_run=["abc"]),
          "mean missing": lambda s: s["variants"]["QCON-R"]["quantities"]["trials_to_satisfactory"].pop("mean"),
          "meets_thesis text": lambda s: s["variants"]["QCON-R"]["quantities"]["trials_to_satisfactory"].update(
              meets_thesis="maybe"),
          "diverged a number": lambda s: s["variants"]["QCON-R"].update(diverged=5),
          "timing empty": lambda s: s.update(timing={}),
          "git_commit a number": lambda s: s["environment"].update(git_commit=5),
          "another experiment": lambda s: s.update(experiment="pole-hidden"),
          "huge run count": lambda s: s.update(runs_per_variant=10**8)}


@pytest.mark.parametrize("kind", sorted(INSIDE))
def test_wrong_types_inside_a_summary_are_named_not_a_traceback(kind, tmp_path, capsys):
    out = tmp_path / "runs"
    run_tiny("pole-full", out)
    path = out / "pole-full" / "summary.json"
    summary = json.loads(path.read_text())
    INSIDE[kind](summary)
    path.write_text(json.dumps(summary))
    for command in ("show", "plot"):
        with pytest.raises(SystemExit) as e:
            cli.main([command, "pole-full", "--out", str(out)])
        assert f"{path} is damaged (" in _one_line(e.value)
    assert cli.main(["results", "--out", str(out)]) == 0
    assert "left out of the page" in capsys.readouterr().err


@pytest.mark.parametrize("kind", ["other experiment", "other seed", "text curve", "text metric", "csv bytes",
                                  "deep nesting"])
def test_a_record_that_is_not_this_runs_is_redone(kind, tmp_path, capsys):
    out = tmp_path / "runs"
    args = ["run", "pole-full", "--profile", "tiny", "--runs", "2", "--out", str(out), "--quiet", "--workers", "1"]
    cli.main(args)
    record = next(out.rglob("seed-1.json"))
    good = record.read_bytes()
    rec = json.loads(good)
    if kind == "csv bytes":
        record.with_suffix(".csv").write_bytes(bytes(range(256)))
    elif kind == "deep nesting":
        record.write_text("[" * 100_000 + "]" * 100_000)
    else:
        change = {"other experiment": {"experiment": "pole-full-ahc"}, "other seed": {"seed": 2},
                  "text curve": {"curve_y": ["a"] * len(rec["curve_y"])},
                  "text metric": {"metrics": {"trials_to_satisfactory": "7"}}}[kind]
        record.write_text(json.dumps({**rec, **change}))
    capsys.readouterr()
    assert cli.main(args) == 0
    assert f"{record} is damaged (" in capsys.readouterr().err
    assert json.loads(record.read_text())["curve_y"] == rec["curve_y"]


def test_huge_run_counts_are_refused_before_any_run(tmp_path, capsys):
    with pytest.raises(SystemExit):
        cli.main(["run", "pole-full", "--runs", "100000000", "--out", str(tmp_path)])
    assert "must be at most 10000 runs per variant" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        cli.main(["sweep", "pole-full", "--seeds", "0:100000000", "--out", str(tmp_path)])
    assert "at most 10000" in _one_line(e.value)
    assert not any(tmp_path.iterdir())


def test_meets_thesis_says_when_fewer_runs_than_the_protocol():
    from connrl.report.page import meets

    q = {"meets_thesis": True}
    assert meets(q, "full", True, 1, 10) == "yes (1 run(s); the protocol has 10)"
    assert meets(q, "full", True, 10, 10) == "yes"


def test_a_diverged_survival_run_does_not_block_the_page(tmp_path, capsys):
    out = tmp_path / "runs"
    run_tiny("survival-study1", out)
    record = next(out.rglob("seed-0.json"))
    rec = json.loads(record.read_text())
    rec.update(metrics={}, curve_x=[], curve_y=[], diverged={"trial": 3, "reason": "exploding weights"})
    record.write_text(json.dumps(rec))
    cli.main(["run", "survival-study1", "--profile", "tiny", "--out", str(out), "--quiet", "--workers", "1"])
    assert cli.main(["results", "--out", str(out)]) == 0
    page = (out / "RESULTS.md").read_text()
    assert f"**Diverged:** `survival-study1`, {rec['variant']}, seed 0" in page and "## Chapter 4" in page


@pytest.mark.skipif(not Path("/proc").exists(), reason="needs /proc")
def test_ctrl_c_stops_the_runs_in_flight_and_keeps_what_finished(tmp_path):
    parent, workers = _run_with_two_workers(tmp_path / "runs")
    try:
        start = time.time()
        parent.send_signal(signal.SIGINT)
        try:
            _, err = parent.communicate(timeout=60)
        except subprocess.TimeoutExpired:  # say where it hangs: faulthandler prints every thread's stack
            state = _signal_state(parent.pid)
            parent.send_signal(signal.SIGABRT)
            _, err = parent.communicate(timeout=30)
            pytest.fail(f"connrl run did not stop within 60 s of Ctrl-C; signals: {state}; its stacks:\n"
                        f"{err.decode()[-4000:]}")
        assert parent.returncode == 130 and time.time() - start < 10
        assert b"finished runs are saved; run the same command again to resume" in err
        deadline = time.time() + 5
        while time.time() < deadline and any(_alive(w) for w in workers):
            time.sleep(0.1)
        assert not any(_alive(w) for w in workers)
    finally:
        if parent.poll() is None:
            os.killpg(parent.pid, signal.SIGKILL)


@pytest.mark.parametrize("name, setting, message", [
    ("pole-full", "gamma=5", "parameter gamma must be in [0, 1], got 5.0"),
    ("pole-full", "lam=-1", "parameter lam must be in [0, 1], got -1.0"),
    ("pole-full", "hidden=-3", "parameter hidden must be >= 0, got -3"),
    ("pole-full", "lr=-0.5", "parameter lr must be > 0, got -0.5"),
    ("pole-full", "capacity=0", "parameter capacity must be >= 1, got 0"),
    ("pole-full", "max_trials=0", "parameter max_trials must be >= 1, got 0"),
    ("cup-task1", "decay=2", "parameter decay must be in [0, 1], got 2.0"),
    ("survival-study1", "test_envs=0", "parameter test_envs must be >= 1, got 0"),
    ("robot-teaching-dp", "lessons=-1", "parameter lessons must be >= 0, got -1"),
    ("robot-teaching-dp", "lessons=201", "parameter lessons must be at most 200"),
    ("robot-teaching-dp", "door_width=-5", "parameter door_width must exceed the robot's diameter (24 in)"),
    ("robot-teaching-dp", "stuck_window=0", "parameter stuck_window must be >= 1, got 0"),
    ("robot-teaching-dp", "dp_heading=270", "parameter dp_heading must be in [0, 180], got 270.0"),
    ("robot-teaching-dp", "edge_jump=0", "parameter edge_jump must be > 0, got 0.0"),
    ("robot-teaching-dp", "dp_far=12", "parameter dp_far must be in [24, 96]"),
    ("robot-teaching-dp", "dp_far=200", "parameter dp_far must be in [24, 96]"),
    ("robot-teaching-dp", "edge_jump=200", "parameter edge_jump must be at most 127"),
    ("robot-teaching-dp", "lesson_starts=foo", "parameter lesson_starts must be one of 'random', 'spread'"),
    ("robot-teaching-dk", "edge_jump=24", "parameter(s) edge_jump apply to task DP only"),
    ("robot-teaching-wfl", "lesson_starts=spread", "parameter(s) lesson_starts apply to task DP only"),
    ("robot-dp-copy", "lessons=0", "parameter lessons must be >= 1 when policy is 'copy'"),
    ("recharge-behaviours", "library=abc", "parameter library must be the shipped behaviour library's digest"),
    ("recharge-behaviours", "hidden=0", "parameter hidden must be >= 1, got 0"),
    ("robot-teaching-dp", "taught_order=first", "parameter taught_order must be one of 'after', 'shuffled'"),
    ("robot-dp-copy", "policy=random", "parameter policy must be one of 'copy', 'teacher'"),
    ("robot-dp-copy", "copy_epochs=-1", "parameter copy_epochs must be >= 0, got -1"),
])
def test_out_of_range_settings_are_refused_before_any_run(name, setting, message, tmp_path, monkeypatch):
    import connrl.experiments.runner as runner

    monkeypatch.setattr(runner, "execute_job", lambda job: pytest.fail("a run started"))
    with pytest.raises(SystemExit) as e:
        cli.main(["sweep", name, "--set", setting, "--seeds", "0:1", "--out", str(tmp_path), "--workers", "1"])
    assert message in _one_line(e.value)
    assert not any(tmp_path.iterdir())


# ------------------------------------------------------------------------- second run, Ray, pages, library

def test_a_second_run_into_the_same_folder_is_refused_at_once(tmp_path, monkeypatch):
    import connrl.experiments.runner as runner

    monkeypatch.setattr(runner, "execute_job", lambda job: pytest.fail("a run started"))
    folder = tmp_path / "pole-full"
    folder.mkdir()
    with runner.run_lock(folder):  # as another connrl run holds it
        with pytest.raises(SystemExit) as exc:
            cli.main(["run", "pole-full", "--profile", "tiny", "--out", str(tmp_path), "--quiet", "--workers", "1"])
    assert "another connrl command is writing to" in _one_line(exc.value)


@pytest.mark.parametrize("address, says", [("127.0.0.1:1", "no Ray cluster answers at 127.0.0.1:1"),
                                           ("nonsense", "--address must be HOST:PORT")])
def test_a_ray_address_that_does_not_answer_is_refused_before_any_run(address, says, tmp_path, monkeypatch):
    pytest.importorskip("ray")
    import connrl.experiments.runner as runner

    monkeypatch.setattr(runner, "run_experiment", lambda *a, **k: pytest.fail("a run started"))
    t0 = time.monotonic()
    with pytest.raises(SystemExit) as exc:
        cli.main(["run", "pole-full", "--profile", "tiny", "--out", str(tmp_path), "--executor", "ray",
                  "--address", address])
    assert says in _one_line(exc.value) and time.monotonic() - t0 < 15


def test_reproduce_refuses_a_doc_it_cannot_write_before_any_run(tmp_path, monkeypatch):
    import connrl.experiments.runner as runner

    monkeypatch.setattr(runner, "run_experiments", lambda *a, **k: pytest.fail("a run started"))
    (tmp_path / "page").mkdir()
    with pytest.raises(SystemExit) as exc:
        cli.main(["reproduce", "--chapters", "4", "--profile", "tiny", "--out", str(tmp_path / "out"),
                  "--doc", str(tmp_path / "page")])
    assert "is a folder" in _one_line(exc.value)
    (tmp_path / "file").write_text("keep me")
    with pytest.raises(SystemExit) as exc:
        cli.main(["reproduce", "--chapters", "4", "--profile", "tiny", "--out", str(tmp_path / "out"),
                  "--doc", str(tmp_path / "file" / "RESULTS.md")])
    assert "cannot write to" in _one_line(exc.value)
    assert (tmp_path / "file").read_text() == "keep me"


def test_train_behaviours_writes_under_runs_unless_told_to_replace_the_shipped_library(tmp_path, monkeypatch):
    import connrl.experiments.behaviours as behaviours

    written = []
    monkeypatch.setattr(behaviours, "train_library", lambda out, **kw: written.append(Path(out)) or {})
    monkeypatch.chdir(tmp_path)
    assert cli.main(["train-behaviours", "--trials", "2"]) == 0
    assert written == [Path("runs/behaviours")]
    with pytest.raises(SystemExit) as exc:
        cli.main(["train-behaviours", "--out", "x", "--replace-shipped"])
    assert "not both" in _one_line(exc.value)


def test_a_plot_is_never_written_through_a_planted_link(tmp_path):
    import matplotlib.pyplot as plt

    from connrl.report.plots import save_figure

    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    (tmp_path / "curve.png").symlink_to(victim)
    fig, _ = plt.subplots()
    save_figure(fig, tmp_path / "curve.png")
    plt.close(fig)
    assert victim.read_text() == "keep me" and not (tmp_path / "curve.png").is_symlink()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
