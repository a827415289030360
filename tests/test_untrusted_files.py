"""Issue 43's attacks: what connrl reads is bounded by what it reads, not by what the file claims, and every output
folder has one writer. Each attack runs the real CLI in a subprocess under a 3 GB memory cap and must end within 30 s
with exit 1 or 2 and one line naming the file, no traceback, nothing written where it should not be."""

from __future__ import annotations

import json
import os
import shutil
import stat
from pathlib import Path

import pytest

import tests.fault_tools as ft

LIMIT = 30  # seconds an attack may take
HAS_DEVICES = Path("/dev/zero").exists() and Path("/dev/urandom").exists()
needs_devices = pytest.mark.skipif(not HAS_DEVICES, reason="this platform has no /dev/zero or /dev/urandom")
needs_fifo = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="this platform has no FIFOs (os.mkfifo)")


def _run(args, cwd) -> object:
    return ft.cli(args, cwd, timeout=LIMIT, memory_cap=True)


@pytest.fixture(scope="module")
def agent_folder(tmp_path_factory) -> Path:
    cwd = tmp_path_factory.mktemp("agent43")
    proc = ft.cli(["train", "CartPole-v1", "--steps", "300", "--quiet", "--save", "agent"], cwd, timeout=300)
    assert proc.returncode == 0, ft.describe(proc)
    return cwd / "agent"


def _special(path: Path, kind: str) -> None:
    """Replace ``path`` by a link to a device, or by a FIFO nobody writes to."""
    path.unlink(missing_ok=True)
    if kind == "fifo":
        os.mkfifo(path)
    else:
        path.symlink_to(f"/dev/{kind}")


def _cwd(tmp_path: Path, agent_folder: Path | None = None) -> Path:
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    if agent_folder is not None:
        shutil.copytree(agent_folder, cwd / "agent")
    return cwd


KINDS = [pytest.param("zero", marks=needs_devices), pytest.param("urandom", marks=needs_devices),
         pytest.param("fifo", marks=needs_fifo)]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("name", ["agent.npz", "agent.json"])
def test_an_agent_file_that_is_not_a_regular_file_is_refused(name, kind, agent_folder, tmp_path):
    cwd = _cwd(tmp_path, agent_folder)
    _special(cwd / "agent" / name, kind)
    ft.assert_refused(_run(["evaluate", "agent", "--episodes", "1"], cwd), name)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("name", ["settings.json", "progress.csv"])
def test_a_resumed_runs_files_that_are_not_regular_files_are_refused(name, kind, agent_folder, tmp_path):
    cwd = _cwd(tmp_path, agent_folder)
    _special(cwd / "agent" / name, kind)
    proc = _run(["train", "CartPole-v1", "--steps", "600", "--quiet", "--save", "agent", "--resume"], cwd)
    ft.assert_refused(proc, name)


@pytest.mark.parametrize("kind", KINDS)
def test_a_lesson_file_or_settings_file_that_is_not_a_regular_file_is_refused(kind, tmp_path):
    cwd = _cwd(tmp_path)
    for flag, name in (("--teach", "lessons.json"), ("--hyperparams", "settings.yml")):
        _special(cwd / name, kind)
        proc = _run(["train", "CartPole-v1", flag, name, "--steps", "100", "--quiet", "--save", "out"], cwd)
        ft.assert_refused(proc, name)
        assert not (cwd / "out" / "agent.json").exists()


def _settings(cwd: Path, text: str | bytes) -> Path:
    path = cwd / "s.yml"
    path.write_bytes(text.encode() if isinstance(text, str) else text)
    return path


LAUGHS = "CartPole-v1:\n  env_kwargs:\n    a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"    {chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, "
    f"*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n" for i in range(9))


@pytest.mark.parametrize("text, words", [
    (LAUGHS, "uses a YAML alias"),
    ("CartPole-v1:\n  env_kwargs: " + "[" * 50_000 + "]" * 50_000 + "\n", "nests more than"),
    (b"CartPole-v1:\n  lr: 0.05 \xff\xfe\n", "is not UTF-8 text"),
    ("CartPole-v1:\n  n_timesteps: 100000000000000000000\n", "n_timesteps must be a whole number from 1 to"),
    ("CartPole-v1:\n  n_timesteps: true\n", "n_timesteps must be a whole number from 1 to"),
    ("CartPole-v1:\n  n_timesteps: 2.5\n", "n_timesteps must be a whole number from 1 to"),
])
def test_a_settings_file_is_plain_bounded_data(text, words, tmp_path):
    cwd = _cwd(tmp_path)
    path = _settings(cwd, text)
    proc = _run(["train", "CartPole-v1", "--hyperparams", path.name, "--quiet", "--save", "out"], cwd)
    line = ft.assert_refused(proc, path.name)
    assert words in line
    assert not (cwd / "out").exists()


@pytest.mark.parametrize("steps, words", [('"lots"', "steps: is 'lots'"), ("1e30", "steps: is 1e+30"),
                                          ("true", "steps: is True"), ("0", "steps: is 0")])
def test_a_resumed_runs_steps_are_checked(steps, words, agent_folder, tmp_path):
    cwd = _cwd(tmp_path, agent_folder)
    settings = cwd / "agent" / "settings.json"
    settings.write_text(settings.read_text().replace(f'"steps": {json.loads(settings.read_text())["steps"]}',
                                                     f'"steps": {steps}'))
    line = ft.assert_refused(_run(["train", "CartPole-v1", "--quiet", "--save", "agent", "--resume"], cwd),
                             "settings.json")
    assert words in line


def test_a_lesson_file_with_a_5000_digit_integer_names_the_file(tmp_path):
    cwd = _cwd(tmp_path)
    doc = {"format": "connrl-lesson", "version": 1, "env_id": "CartPole-v1", "env_kwargs": {}, "lessons": [
        {"inputs": [[0.0, 0.0, 0.0, 0.0]], "actions": ["@@"], "rewards": [1.0]}]}
    (cwd / "l.json").write_text(json.dumps(doc).replace('"@@"', "7" * 5000))
    ft.assert_refused(_run(["train", "CartPole-v1", "--teach", "l.json", "--steps", "100", "--quiet", "--save", "o"],
                           cwd), "l.json")


def _tune(cwd: Path, *extra: str, timeout: float = LIMIT):
    return ft.cli(["tune", "CartPole-v1", "--trials", "1", "--steps", "200", "--seeds", "5", "--eval-episodes", "1",
                   "--space", "lr=0.02,0.05", "--out", "t", *extra], cwd, timeout=timeout, memory_cap=True)


@pytest.fixture(scope="module")
def tuned(tmp_path_factory) -> Path:
    cwd = tmp_path_factory.mktemp("tune43")
    proc = _tune(cwd, timeout=300)  # a fixture trains, so it gets the time a loaded machine needs
    assert proc.returncode == 0, ft.describe(proc)
    return cwd / "t"


@pytest.mark.parametrize("change, words", [
    (lambda rows: rows[1].__setitem__(3, "inf"), "is not the mean of its scores"),
    (lambda rows: rows[1].__setitem__(3, "999"), "is not the mean of its scores"),
    (lambda rows: rows[1].__setitem__(2, '["high"]'), "scores must be a list of numbers within"),
    (lambda rows: rows[1].__setitem__(1, '{"lr": 7}'), "lr = 7 is outside the searched space"),
    (lambda rows: rows[1].__setitem__(4, "soon"), "could not convert"),
])
def test_a_forged_trials_row_is_refused_on_resume(change, words, tuned, tmp_path):
    import csv
    import io

    cwd = _cwd(tmp_path)
    shutil.copytree(tuned, cwd / "t")
    (cwd / "t" / "best.yml").unlink()
    rows = list(csv.reader(io.StringIO((cwd / "t" / "trials.csv").read_text())))
    change(rows)
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    (cwd / "t" / "trials.csv").write_text(buf.getvalue())
    line = ft.assert_refused(_tune(cwd, "--trials", "2"), "trials.csv")
    assert words in line
    assert not (cwd / "t" / "best.yml").exists()


def test_a_deep_study_file_is_refused_in_one_line(tuned, tmp_path):
    cwd = _cwd(tmp_path)
    shutil.copytree(tuned, cwd / "t")
    (cwd / "t" / "study.json").write_text(ft.deep_json())
    ft.assert_refused(_tune(cwd), "study.json")


@pytest.mark.parametrize("command", [["train", "CartPole-v1", "--steps", "100", "--quiet", "--save", "busy"],
                                     ["tune", "CartPole-v1", "--trials", "1", "--steps", "100", "--out", "busy"]])
def test_a_second_writer_into_one_folder_is_refused_before_any_work(command, tmp_path):
    from connrl.experiments.guards import run_lock

    cwd = _cwd(tmp_path)
    (cwd / "busy").mkdir()
    with run_lock(cwd / "busy"):  # the first writer, still at work
        line = ft.assert_refused(_run(command, cwd), "busy")
    assert "another connrl command is writing to" in line
    assert {p.name for p in (cwd / "busy").iterdir()} == {".connrl-run.lock"}


def test_plot_of_a_folder_without_a_log_says_what_it_draws(tmp_path):
    cwd = _cwd(tmp_path)
    (cwd / "trained").mkdir()
    line = ft.assert_refused(_run(["plot", "trained"], cwd), "trained holds no progress.csv")
    assert "unknown experiment" not in line


def test_a_full_disk_names_the_file_it_could_not_write(tmp_path, monkeypatch):
    import errno

    from connrl.storage import atomic_write_text

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(OSError) as exc:
        atomic_write_text(tmp_path / "summary.json", "{}")
    assert exc.value.filename == str(tmp_path / "summary.json") and exc.value.errno == errno.ENOSPC
    assert list(tmp_path.iterdir()) == []  # nothing half-written, no temporary file


def test_a_killed_writers_temporary_file_is_removed_on_the_next_run(tmp_path):
    from connrl import cli

    out = tmp_path / "runs"
    left = out / "td-depth" / ".summary.json.abc123.tmp"
    left.parent.mkdir(parents=True)
    left.write_text("half")
    assert cli.main(["run", "td-depth", "--profile", "tiny", "--out", str(out), "--workers", "1", "--quiet"]) == 0
    assert not left.exists() and not list(out.rglob("*.tmp"))


def test_a_special_file_is_refused_by_the_reader_itself(tmp_path):
    """connrl.storage.read_limited checks the opened descriptor: a FIFO does not block, a device is not read."""
    from connrl.storage import FileError, read_limited

    if hasattr(os, "mkfifo"):
        os.mkfifo(tmp_path / "pipe")
        with pytest.raises(FileError, match="is not a regular file"):
            read_limited(tmp_path / "pipe", 100)
    if HAS_DEVICES:
        with pytest.raises(FileError, match="is not a regular file"):
            read_limited(Path("/dev/zero"), 100)
    big = tmp_path / "big"
    big.write_bytes(b"x" * 101)
    with pytest.raises(FileError, match="at most 100"):
        read_limited(big, 100)
    assert read_limited(big, 101) == b"x" * 101
    assert stat.S_ISREG(os.stat(big).st_mode)


# ------------------------------------------------------------------------------- the review's attacks (issue 43)

def test_nesting_is_measured_in_linear_time():
    """An unterminated string of escaped quotes once cost O(n^2) to skip (40 KB: 6.7 s)."""
    import time

    from connrl.storage import max_depth

    raw = b'"' + b'\\"' * 500_000
    t0 = time.perf_counter()
    assert max_depth(raw) == 0 and max_depth(b'[{"a": "]]]", "b": [[1]]}]') == 4
    assert time.perf_counter() - t0 < 2.0


def test_an_agent_json_of_escaped_quotes_is_refused_quickly(agent_folder, tmp_path):
    cwd = _cwd(tmp_path, agent_folder)
    (cwd / "agent" / "agent.json").write_bytes(b'"' + b'\\"' * 200_000)
    ft.assert_refused(_run(["evaluate", "agent", "--episodes", "1"], cwd), "agent.json")


def _npz_member(name: str, header: dict, data: bytes) -> tuple[str, bytes]:
    import numpy as np

    buf = __import__("io").BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    return f"{name}.npy", buf.getvalue() + data


def test_an_archive_is_not_believed_about_its_arrays(tmp_path):
    """A header claiming 10^15 elements must not make NumPy allocate them; members that unpack past the limit are
    refused before any is unpacked; object arrays are refused without unpickling."""
    import zipfile

    from connrl.storage import FileError, read_npz

    bomb = tmp_path / "shape.npz"
    with zipfile.ZipFile(bomb, "w") as z:
        z.writestr(*_npz_member("w", {"descr": "<f8", "fortran_order": False, "shape": (10**15,)}, b"\0" * 64))
    with pytest.raises(FileError, match=r"w: its header claims shape \(1000000000000000,\)"):
        read_npz(bomb)
    big = tmp_path / "inflates.npz"
    zeros = b"\0" * 2**20
    with zipfile.ZipFile(big, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        for k in range(2):
            with z.open(f"a{k}.npy", "w", force_zip64=True) as f:
                for _ in range(300):
                    f.write(zeros)
    assert big.stat().st_size < 5 * 2**20
    with pytest.raises(FileError, match="unpacks to 629145600 bytes; a array file unpacks to at most"):
        read_npz(big)


@pytest.mark.parametrize("scores, mean, words", [("[1e308, 1e308]", "inf", "scores must be a list of numbers"),
                                                 ("[1.5e16, 1.0]", "7.5e+15", "scores must be a list of numbers"),
                                                 ("[" + "1" * 401 + "]", "1", "scores must be a list of numbers")])
def test_a_trials_row_cannot_win_by_overflow(scores, mean, words, tuned, tmp_path):
    import csv
    import io

    cwd = _cwd(tmp_path)
    shutil.copytree(tuned, cwd / "t")
    (cwd / "t" / "best.yml").unlink()
    rows = list(csv.reader(io.StringIO((cwd / "t" / "trials.csv").read_text())))
    rows[1][2], rows[1][3] = scores, mean
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    (cwd / "t" / "trials.csv").write_text(buf.getvalue())
    line = ft.assert_refused(_tune(cwd, "--trials", "2"), "trials.csv")
    assert words in line and not (cwd / "t" / "best.yml").exists()


@pytest.mark.parametrize("text, words", [
    ("CartPole-v1:\n  n_timesteps: " + "7" * 5000 + "\n", "holds a value that cannot be read"),
    ("CartPole-v1:\n  n_timesteps: 0x" + "f" * 5000 + "\n", "an integer of"),
    ("CartPole-v1:\n  env_kwargs: {a: 0x" + "f" * 5000 + "}\n", "env_kwargs must be plain values"),
    ("CartPole-v1:\n  lr: 0.05\x00\n", "is not valid YAML"),
    ("CartPole-v1:\n  lr: 100000000000000000000\n", "option lr must be a number > 0 and <= 100"),
])
def test_a_settings_value_python_cannot_use_names_the_file(text, words, tmp_path):
    cwd = _cwd(tmp_path)
    path = _settings(cwd, text)
    line = ft.assert_refused(_run(["train", "CartPole-v1", "--hyperparams", path.name, "--quiet", "--save", "out"],
                                  cwd), path.name)
    assert words in line and not (cwd / "out").exists()


def test_an_option_too_large_for_the_kernels_is_refused_before_training(tmp_path):
    cwd = _cwd(tmp_path)
    line = ft.assert_refused(_run(["train", "CartPole-v1", "--option", "lr=100000000000000000000", "--quiet",
                                   "--save", "out"], cwd), "option lr")
    assert "<= 100" in line and not (cwd / "out").exists()


def test_a_forged_progress_row_is_refused_on_resume(agent_folder, tmp_path):
    cwd = _cwd(tmp_path, agent_folder)
    log = cwd / "agent" / "progress.csv"
    lines = log.read_text().splitlines()
    head = lines[0].split(",")
    cells = lines[1].split(",")
    cells[head.index("return")] = "inf"
    log.write_text("\n".join([lines[0], ",".join(cells), *lines[2:]]) + "\n")
    line = ft.assert_refused(_run(["train", "CartPole-v1", "--steps", "600", "--quiet", "--save", "agent",
                                   "--resume"], cwd), "progress.csv")
    assert "not a finite number" in line


def test_a_resumed_train_takes_the_lock_too(agent_folder, tmp_path):
    from connrl.experiments.guards import run_lock

    cwd = _cwd(tmp_path, agent_folder)
    with run_lock(cwd / "agent"):
        line = ft.assert_refused(_run(["train", "CartPole-v1", "--steps", "600", "--quiet", "--save", "agent",
                                       "--resume"], cwd), "agent")
    assert "another connrl command is writing to" in line and "give another --save" in line


def test_one_bad_run_csv_leaves_out_its_run_not_the_page(tmp_path):
    from connrl import cli

    out = tmp_path / "runs"
    assert cli.main(["run", "pole-full", "--profile", "tiny", "--out", str(out), "--workers", "1", "--quiet"]) == 0
    csv_file = next(out.rglob("seed-0.csv"))
    csv_file.write_bytes(b"\xff\xfe not text")
    assert cli.main(["results", "--out", str(out), "--doc", str(tmp_path / "R.md")]) == 0
    assert (tmp_path / "R.md").exists()


def test_plot_of_an_experiment_is_not_mistaken_for_a_folder(tmp_path, monkeypatch):
    from connrl import cli

    assert cli.main(["run", "td-depth", "--profile", "tiny", "--out", str(tmp_path), "--workers", "1",
                     "--quiet"]) == 0
    monkeypatch.chdir(tmp_path)  # ./td-depth is the stored experiment's folder
    assert cli.main(["plot", "td-depth", "--out", "."]) == 0
