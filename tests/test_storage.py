"""connrl.storage: atomic writes that never follow a planted link and leave nothing behind when they fail, and the
checked readers (bounded size and nesting, no NaN, no pickle) every file format builds on."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from connrl import storage
from connrl.storage import (
    FileError,
    atomic_save_npz,
    atomic_write_files,
    atomic_write_text,
    check_array,
    check_number,
    max_depth,
    read_json,
    read_npz,
    strict_json,
)


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def test_a_link_planted_at_a_temporary_name_is_never_followed(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    target = tmp_path / "summary.json"
    # the names the old writer used (".NAME.PID.tmp") and a few guesses around them
    for name in (f".{target.name}.{os.getpid()}.tmp", f".{target.name}.tmp", f"{target.name}.tmp"):
        (tmp_path / name).symlink_to(victim)
    atomic_write_text(target, "new")
    assert victim.read_text() == "precious" and target.read_text() == "new"


def test_a_new_file_gets_the_permissions_open_would_give(tmp_path):
    atomic_write_text(tmp_path / "a.json", "{}")
    plain = tmp_path / "b.json"
    plain.write_text("{}")
    assert (tmp_path / "a.json").stat().st_mode & 0o777 == plain.stat().st_mode & 0o777


@pytest.mark.parametrize("fail_at", ["fsync", "replace"])
def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary_file(tmp_path, monkeypatch, fail_at):
    target = tmp_path / "record.json"
    target.write_text("old")

    def disk_full(*args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(storage.os, fail_at, disk_full)
    with pytest.raises(OSError, match="No space left"):
        atomic_write_text(target, "new")
    monkeypatch.undo()
    assert target.read_text() == "old" and _leftovers(tmp_path) == []


def test_files_written_as_one_are_all_old_or_all_new(tmp_path, monkeypatch):
    a, b = tmp_path / "agent.npz", tmp_path / "agent.json"
    a.write_text("old a")
    b.write_text("old b")
    writes = []
    real = storage.os.fdopen

    def second_write_fails(fd, mode):
        writes.append(fd)
        if len(writes) == 2:
            raise OSError(28, "No space left on device")
        return real(fd, mode)

    monkeypatch.setattr(storage.os, "fdopen", second_write_fails)
    with pytest.raises(OSError):
        atomic_write_files({a: b"new a", b: b"new b"})
    monkeypatch.undo()
    os.close(writes[1])  # the descriptor the failed fdopen was handed
    assert (a.read_text(), b.read_text()) == ("old a", "old b") and _leftovers(tmp_path) == []
    atomic_write_files({a: b"new a", b: b"new b"})
    assert (a.read_text(), b.read_text()) == ("new a", "new b")


def test_strict_json_writes_nothing_a_json_parser_refuses():
    text = strict_json({"x": [1.0, float("nan"), np.float64("inf"), np.array([2.0, -np.inf])], "y": 3})

    def refuse(name):
        raise AssertionError(name)

    assert json.loads(text, parse_constant=refuse) == {"x": [1.0, None, None, [2.0, None]], "y": 3}


@pytest.mark.parametrize("content, message", [
    (b"", "is empty"),
    (b"\xff\xfe{", "is not text"),
    (b'{"a": ', "is not JSON (Expecting value at line 1, column 7)"),
    (b'{"a": "open', "is not JSON (Unterminated string at line 1, column 7)"),  # never "starting at at"
    (b'{"a": NaN}', "NaN is not JSON"),
    (b'{"a": -Infinity}', "-Infinity is not JSON"),
    (b'{"a": 1e400}', "the number 1e400 is too large for a float"),
    (b"[" * 100_000 + b"]" * 100_000, "nests 100000 levels deep; a test file nests at most 32"),
    (b'{"a": ' + b"[" * 33 + b"]" * 33 + b"}", "nests 34 levels deep"),
])
def test_read_json_refuses_in_one_line_naming_the_file(tmp_path, content, message):
    path = tmp_path / "f.json"
    path.write_bytes(content)
    with pytest.raises(FileError) as e:
        read_json(path, "test file")
    text = str(e.value)
    assert text.startswith(f"{path}: ") and message in text and "\n" not in text
    assert path.read_bytes() == content


def test_read_json_bounds_size_and_tells_a_folder_and_a_missing_file(tmp_path):
    (tmp_path / "big.json").write_text(json.dumps(list(range(1000))))
    with pytest.raises(FileError, match="big.json: is 4890 bytes; a test file is at most 100"):
        read_json(tmp_path / "big.json", "test file", max_bytes=100)
    with pytest.raises(FileError, match="is a folder; a test file was expected"):
        read_json(tmp_path, "test file")
    with pytest.raises(FileError, match="no such test file"):
        read_json(tmp_path / "none.json", "test file")
    (tmp_path / "old.json").write_text('{"high": Infinity}')  # files written before strict JSON
    assert read_json(tmp_path / "old.json", constants=True) == {"high": float("inf")}


def test_nesting_is_counted_outside_strings_only():
    assert max_depth(b'{"a": "[[[[{{{{", "b": [1, [2]], "c": "\\"]]]"}') == 3
    assert max_depth(b"[]") == 1 and max_depth(b"3") == 0


def test_read_npz_never_unpickles_and_names_the_file(tmp_path):
    atomic_save_npz(tmp_path / "ok.npz", w=np.arange(3.0))
    assert read_npz(tmp_path / "ok.npz")["w"].tolist() == [0.0, 1.0, 2.0]
    np.savez(tmp_path / "obj.npz", w=np.array([{"code": 1}], dtype=object))
    np.save(tmp_path / "one.npy", np.zeros(2))
    (tmp_path / "trunc.npz").write_bytes((tmp_path / "ok.npz").read_bytes()[:40])
    (tmp_path / "noise.npz").write_bytes(np.random.default_rng(0).bytes(4096))
    for name, message in (("obj.npz", "holds object data (Python objects"), ("one.npy", "is a single .npy array"),
                          ("trunc.npz", "is not a readable array file"), ("none.npz", "no such array file"),
                          ("noise.npz", "is not an .npz archive")):
        with pytest.raises(FileError) as e:
            read_npz(tmp_path / name)
        assert str(e.value).startswith(f"{tmp_path / name}: ") and message in str(e.value)
        assert "pickle=" not in str(e.value) and "\n" not in str(e.value)  # not NumPy's advice to unpickle


@pytest.mark.parametrize("value, kwargs, message", [
    (True, {}, "is True; it must be a finite number"),
    (float("nan"), {}, "is nan; it must be a finite number"),
    (2.5, {"integer": True}, "it must be a whole number"),
    (10**30, {"high": 100}, "it must be a finite number <= 100"),
    (0, {"low": 0, "low_open": True}, "it must be a finite number > 0"),
    ("3", {}, "is '3'; it must be a finite number"),
])
def test_check_number_bounds_every_value(value, kwargs, message):
    with pytest.raises(FileError) as e:
        check_number("f.json", "field", value, **kwargs)
    assert str(e.value).startswith("f.json: field: ") and message in str(e.value)
    assert check_number("f.json", "field", 3, 0, 3, integer=True) == 3


def test_check_array_bounds_shape_type_and_values():
    assert check_array("f", "a", np.array([0, 1, 2]), (-1,), low=0, high=2, integer=True).dtype == np.int64
    for a, kwargs, message in (
            (np.array([0, 7]), {"low": 0, "high": 1, "integer": True},
             "holds values in [0, 7]; they must lie in [0, 1]"),
            (np.array([0.0, 1.0]), {"integer": True}, "holds float64 data; it must hold integers"),
            (np.array(["a"]), {}, "holds <U1 data; it must hold numbers"),
            (np.zeros((2, 3)), {"shape": (2, 4)}, "has shape (2, 3); it must have shape (2, 4)"),
            (np.array([1.0, np.nan]), {}, "holds NaN or infinite values")):
        with pytest.raises(FileError) as e:
            check_array("f.npz", "a", a, **kwargs)
        assert str(e.value) == f"f.npz: a: {message}" or message in str(e.value)


# ------------------------------------------------------------------ run records (connrl.experiments.store)

def _record(**change) -> dict:
    rec = {"experiment": "e", "variant": "v", "seed": 0, "params": {}, "metrics": {"m": None},
           "curve_x": [0, 10], "curve_y": [0.5, None], "wall_time_s": 1.0}
    return {**rec, **change}


def test_a_record_is_written_as_strict_json_and_a_missing_test_value_reads_back_as_null(tmp_path):
    from connrl.experiments.store import load_record, write_run_records

    write_run_records(tmp_path / "seed-0", _record(curve_y=[0.5, float("nan")], metrics={"m": float("inf")}), [])
    text = (tmp_path / "seed-0.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    rec, damage = load_record(tmp_path / "seed-0")
    assert damage is None and rec["curve_y"] == [0.5, None] and rec["metrics"] == {"m": None}


@pytest.mark.parametrize("old, new", [('"m": null', '"m": NaN'), ('"m": null', '"m": 1e400'),
                                      ("0.5", "Infinity"), ('"curve_x": [', '"curve_x": [null, ')])
def test_a_record_with_a_non_finite_or_missing_number_is_damaged(tmp_path, old, new):
    from connrl.experiments.store import load_record, write_run_records

    write_run_records(tmp_path / "seed-0", _record(), [])
    path = tmp_path / "seed-0.json"
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    rec, damage = load_record(tmp_path / "seed-0")
    assert rec is None and damage


def test_a_file_error_raised_in_a_worker_reaches_the_parent_as_the_same_line():
    import pickle

    from connrl.experiments.store import DamagedFile

    for exc in (FileError("a/b.json", "is 3; it must be <= 2", "x"), DamagedFile("a/s.json", "empty", "run again")):
        back = pickle.loads(pickle.dumps(exc))
        assert type(back) is type(exc) and str(back) == str(exc)
