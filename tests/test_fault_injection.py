"""Fault injection (issue 24): damaged copies of every file connrl reads, read by the real CLI in a subprocess.

For each format a deterministic fuzzer (seeded numpy Generators, fixed mutation lists) makes damaged copies --
truncated, bytes flipped, NaN / inf, out-of-range integers, wrong types, 100000-deep JSON, huge sizes -- and each
case asserts: exit code 1 or 2 (never a signal), stderr exactly one non-empty line starting "connrl: " that names
the damaged file, no traceback, and the damaged file unchanged afterwards. Stored runs may instead be redone (or
left out) with a one-line notice; a summary written afterwards must be strict JSON.

Where the CLI cannot be pointed at another copy of a file (the behaviour library, layouts), a small script in a
subprocess calls the reader and prints ``connrl: <message>`` on ValueError as the CLI does. The shipped files are
only ever copied, never changed.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from tests import fault_tools as ft

SEED = 24  # issue 24: every mutation below is drawn from generators seeded from it


# ============================================================================================ agent folder

@pytest.fixture(scope="session")
def good_agent(tmp_path_factory) -> Path:
    """A good agent folder, trained once per session (and xdist worker) by the real CLI."""
    cwd = tmp_path_factory.mktemp("agent-src")
    proc = ft.cli(["train", "CartPole-v1", "--steps", "2000", "--quiet", "--save", "agent"], cwd)
    assert proc.returncode == 0, ft.describe(proc)
    folder = cwd / "agent"
    assert (folder / "agent.json").is_file() and (folder / "agent.npz").is_file()
    return folder


def _copy_agent(good: Path, tmp_path: Path) -> Path:
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    shutil.copytree(good, cwd / "agent")
    return cwd


def _lesson_count(arrays: dict) -> int:
    return len([k for k in arrays if k.startswith("lesson") and k.endswith("_actions")])


def _shift_actions(delta):
    def change(a):
        k = int(np.random.default_rng(SEED).integers(_lesson_count(a)))  # a seeded lesson K
        a[f"lesson{k}_actions"] = a[f"lesson{k}_actions"] + np.int64(delta)
    return change


def _set(key, index, value):
    def change(a):
        arr = np.array(a[key], dtype=np.float64)
        arr[index] = value
        a[key] = arr
    return change


def _first_lesson(field, value, dtype=None):
    def change(a):
        arr = np.array(a[f"lesson0_{field}"], dtype=dtype or a[f"lesson0_{field}"].dtype)
        arr.flat[0] = value
        a[f"lesson0_{field}"] = arr
    return change


def _replace(key, make):
    def change(a):
        a[key] = make(a[key])
    return change


def _drop(key):
    def change(a):
        del a[key]
    return change


NPZ_ARRAYS = {  # case id -> change(arrays) on agent.npz
    "lesson-actions-plus-7": _shift_actions(7),
    "lesson-actions-plus-1e6": _shift_actions(10**6),
    "lesson-actions-minus-5": _shift_actions(-5),
    "lesson-actions-float": _replace("lesson0_actions", lambda x: x.astype(float) + 0.5),
    "lesson-inputs-nan": _first_lesson("inputs", np.nan),
    "lesson-rewards-inf": _first_lesson("rewards", np.inf),
    "w1-nan": _set("w1", (0, 0, 0), np.nan),
    "w2-inf": _set("w2", (1, 3), np.inf),
    "momentum-d1-nan": _set("d1", (0, 1, 1), np.nan),
    "w1-wrong-shape": _replace("w1", lambda x: x[..., :-1]),
    "w1-strings": _replace("w1", lambda x: x.astype(str)),
    "w1-missing": _drop("w1"),
    "lesson-actions-missing": _drop("lesson0_actions"),
}


def _npz_bytes(transform, resign: bool = True):
    def mutate(folder: Path) -> Path:
        p = folder / "agent.npz"
        p.write_bytes(transform(p.read_bytes()))
        if resign:
            ft.resign_agent(folder)
        return p
    return mutate


def _npz_arrays(change):
    def mutate(folder: Path) -> Path:
        ft.rewrite_npz(folder / "agent.npz", change)
        ft.resign_agent(folder)
        return folder / "agent.npz"
    return mutate


def _npz_object_array(folder: Path) -> Path:
    import io

    with np.load(folder / "agent.npz", allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["w1"] = np.array([{"a": 1}, None], dtype=object)
    buf = io.BytesIO()
    np.savez(buf, **arrays)  # pickled member
    (folder / "agent.npz").write_bytes(buf.getvalue())
    ft.resign_agent(folder)
    return folder / "agent.npz"


def _json_text(transform):
    def mutate(folder: Path) -> Path:
        p = folder / "agent.json"
        p.write_bytes(transform(p.read_bytes()))
        return p
    return mutate


def _json_doc(change):
    """Edit the parsed agent.json; written back with NaN / Infinity as bare tokens (not strict JSON)."""
    def mutate(folder: Path) -> Path:
        p = folder / "agent.json"
        doc = json.loads(p.read_text())
        change(doc)
        p.write_text(json.dumps(doc, indent=1, allow_nan=True))
        return p
    return mutate


def _json_field_text(key, raw: str):
    """Put raw JSON text in place of a top-level field's value."""
    def mutate(folder: Path) -> Path:
        p = folder / "agent.json"
        doc = json.loads(p.read_text())
        doc[key] = "@@PLACEHOLDER@@"
        p.write_text(json.dumps(doc).replace('"@@PLACEHOLDER@@"', raw))
        return p
    return mutate


def _scaler(field, values):
    def change(doc):
        doc["scaler"][field] = values(doc["scaler"][field])
    return change


def _top(key, value):
    def change(doc):
        doc[key] = value
    return change


def _space(which, key, value):
    def change(doc):
        doc[which][key] = value
    return change


AGENT_CASES = {  # case id -> mutate(folder) -> the damaged file
    **{f"npz-truncate-{f}": _npz_bytes(lambda b, f=f: ft.truncate(b, f)) for f in (0.0, 0.5, 0.99)},
    **{f"npz-flip-seed{s}": _npz_bytes(lambda b, s=s: ft.flip_npz(b, SEED + s)) for s in range(3)},
    "npz-object-array": _npz_object_array,
    "npz-changed-after-save": _npz_bytes(lambda b: ft.flip_npz(b, SEED), resign=False),  # the digest tells it
    **{f"npz-{name}": _npz_arrays(change) for name, change in NPZ_ARRAYS.items()},
    **{f"json-truncate-{f}": _json_text(lambda b, f=f: ft.truncate(b, f)) for f in (0.0, 0.5)},
    **{f"json-flip-seed{s}": _json_text(lambda b, s=s: ft.flip_text(b, SEED + s)) for s in range(2)},
    "json-deep-100000": _json_text(lambda b: ft.deep_json().encode()),
    "json-deep-options": _json_field_text("options", ft.deep_value()),
    "json-not-object": _json_text(lambda b: b"[1, 2, 3]"),
    "scaler-scale-nan": _json_doc(_scaler("scale", lambda v: [math.nan] + v[1:])),
    "scaler-scale-zero": _json_doc(_scaler("scale", lambda v: [0.0 for _ in v])),
    "scaler-scale-inf": _json_doc(_scaler("scale", lambda v: v[:-1] + [math.inf])),
    "scaler-n-huge": _json_doc(_scaler("n", lambda v: 10**12)),
    "scaler-scale-string": _json_doc(_scaler("scale", lambda v: "wide")),
    "value-range-nan": _json_doc(_top("value_range", math.nan)),
    "value-range-negative": _json_doc(_top("value_range", -5.0)),
    "steps-done-string": _json_doc(_top("steps_done", "many")),
    "steps-done-huge": _json_field_text("steps_done", "1" + "0" * 5000),
    "rng-wrong-type": _json_doc(_top("rng", [1, 2])),
    "action-space-n-huge": _json_doc(_space("action_space", "n", 10**12)),
    "action-space-n-zero": _json_doc(_space("action_space", "n", 0)),
    "observation-shape-huge": _json_doc(_space("observation_space", "shape", [10**12])),
    "lesson-ends-huge": _json_doc(_top("lesson_ends", [[False, True]] * 100_000)),
}


@pytest.mark.parametrize("case", sorted(AGENT_CASES))
def test_evaluate_refuses_a_damaged_agent_in_one_line(case, good_agent, tmp_path):
    cwd = _copy_agent(good_agent, tmp_path)
    damaged = AGENT_CASES[case](cwd / "agent")
    before = ft.snapshot(damaged)
    proc = ft.cli(["evaluate", "agent", "--episodes", "1"], cwd, timeout=60)
    ft.assert_refused(proc, damaged.name)
    assert ft.snapshot(damaged) == before, "the damaged file was changed"


LEARN = """\
import sys
import gymnasium as gym
import connrl
try:
    agent = connrl.load(sys.argv[1], gym.make("CartPole-v1"))
    agent.learn(500)
except ValueError as exc:
    print(f"connrl: {exc}", file=sys.stderr)
    sys.exit(1)
print("learnt")
"""


@pytest.mark.parametrize("case", ["lesson-actions-plus-7", "lesson-actions-plus-1e6", "lesson-actions-minus-5",
                                  "w1-nan", "lesson-inputs-nan"])
def test_load_then_learn_refuses_a_damaged_agent_at_load(case, good_agent, tmp_path):
    """The learn path (replay of the stored lessons): a ValueError at load, never a segfault or abort."""
    cwd = _copy_agent(good_agent, tmp_path)
    ft.rewrite_npz(cwd / "agent" / "agent.npz", NPZ_ARRAYS[case])
    before = ft.snapshot(cwd / "agent")
    proc = ft.script(LEARN, [cwd / "agent"], cwd, timeout=90)
    ft.normal_exit(proc)
    assert "Traceback" not in proc.stderr, ft.describe(proc)
    assert proc.returncode == 1 and "learnt" not in proc.stdout, f"the damaged agent was used: {ft.describe(proc)}"
    lines = ft.stderr_lines(proc)
    assert lines and lines[-1].startswith("connrl: ") and "agent.npz" in lines[-1], ft.describe(proc)
    assert ft.snapshot(cwd / "agent") == before


EVILMOD = """\
from pathlib import Path
Path(__file__).with_name("EVIL-MARKER").write_text("imported")
"""

ENTRY = """\
import sys
from connrl.cli import main
sys.exit(main())
"""


@pytest.mark.parametrize("launcher", ["python-m", "entry-script"])
def test_an_agent_env_id_naming_a_module_is_not_imported(launcher, good_agent, tmp_path):
    """agent.json's env_id "evilmod:Evil-v0" would make gym import evilmod.py from the cwd: refused, never run."""
    cwd = _copy_agent(good_agent, tmp_path)
    doc = json.loads((cwd / "agent" / "agent.json").read_text())
    doc["env_id"] = "evilmod:Evil-v0"
    (cwd / "agent" / "agent.json").write_text(json.dumps(doc, indent=1))
    (cwd / "evilmod.py").write_text(EVILMOD)
    before = ft.snapshot(cwd / "agent")
    if launcher == "python-m":  # the cwd is on sys.path
        proc = ft.cli(["evaluate", "agent", "--episodes", "1"], cwd)
    else:  # as the installed `connrl` console script runs: the script's own folder on sys.path
        bin_dir = tmp_path / "bin"
        bin_dir.mkdir()
        (bin_dir / "connrl_entry.py").write_text(ENTRY)
        import subprocess

        proc = subprocess.run([ft.PY, str(bin_dir / "connrl_entry.py"), "evaluate", "agent", "--episodes", "1"],
                              cwd=cwd, env=ft.env(), capture_output=True, text=True, timeout=60)
    assert not (cwd / "EVIL-MARKER").exists(), f"evilmod.py was imported: {ft.describe(proc)}"
    ft.assert_refused(proc, "agent.json")
    assert ft.snapshot(cwd / "agent") == before


# ============================================================================================ lesson file

@pytest.fixture(scope="session")
def good_lessons(tmp_path_factory) -> Path:
    import gymnasium as gym

    import connrl

    path = tmp_path_factory.mktemp("lessons-src") / "teach.json"
    env = gym.make("CartPole-v1")
    connrl.record_lessons(env, lambda obs: int(obs[2] + 0.5 * obs[3] > 0), 2, path)
    return path


def _lesson_doc(change):
    def mutate(data: bytes) -> bytes:
        doc = json.loads(data)
        change(doc)
        return json.dumps(doc, allow_nan=True).encode()
    return mutate


def _lesson0(key, value_of):
    def change(doc):
        doc["lessons"][0][key] = value_of(doc["lessons"][0][key])
    return change


def _raw_in_lesson0(key, raw: str):
    """Raw JSON text in place of lesson 0's ``key``."""
    def mutate(data: bytes) -> bytes:
        doc = json.loads(data)
        doc["lessons"][0][key] = "@@PLACEHOLDER@@"
        return json.dumps(doc).replace('"@@PLACEHOLDER@@"', raw).encode()
    return mutate


def _action_at(value):
    def change(actions):
        k = int(np.random.default_rng(SEED).integers(len(actions)))
        return actions[:k] + [value] + actions[k + 1:]
    return change


def _shift_all(delta):
    return lambda actions: [a + delta for a in actions]


LESSON_CASES = {  # case id -> bytes -> damaged bytes
    **{f"truncate-{f}": (lambda b, f=f: ft.truncate(b, f)) for f in (0.0, 0.5)},
    "truncate-last-byte": lambda b: b[:-1],
    **{f"flip-seed{s}": (lambda b, s=s: ft.flip_text(b, SEED + s)) for s in range(2)},
    "deep-100000": lambda b: ft.deep_json().encode(),
    "deep-in-meta": _raw_in_lesson0("meta", '{"x": ' + ft.deep_value() + "}"),
    "input-nan": _lesson_doc(_lesson0("inputs", lambda rows: [[math.nan] + rows[0][1:]] + rows[1:])),
    "input-inf": _lesson_doc(_lesson0("inputs", lambda rows: rows[:-1] + [rows[-1][:-1] + [math.inf]])),
    "reward-nan": _lesson_doc(_lesson0("rewards", lambda r: [math.nan] + r[1:])),
    "reward-1e400": _raw_in_lesson0("rewards", "[1e400]"),
    "actions-plus-7": _lesson_doc(_lesson0("actions", _shift_all(7))),
    "actions-plus-1e6": _lesson_doc(_lesson0("actions", _shift_all(10**6))),
    "actions-minus-5": _lesson_doc(_lesson0("actions", _shift_all(-5))),
    "action-one-huge-int": _lesson_doc(_lesson0("actions", _action_at(10**30))),
    "action-float": _lesson_doc(_lesson0("actions", _action_at(0.5))),
    "action-string": _lesson_doc(_lesson0("actions", _action_at("1"))),
    "input-row-huge": _lesson_doc(_lesson0("inputs", lambda rows: [rows[0] * 25_000] + rows[1:])),
    "lessons-not-list": _lesson_doc(lambda d: d.update(lessons={"0": d["lessons"][0]})),
    "lesson-missing-inputs": _lesson_doc(lambda d: d["lessons"][0].pop("inputs")),
    "version-string": _lesson_doc(lambda d: d.update(version="1")),
    "env-kwargs-list": _lesson_doc(lambda d: d.update(env_kwargs=[1])),
    "not-object": lambda b: b"[1, 2, 3]",
}


@pytest.mark.parametrize("case", sorted(LESSON_CASES))
def test_train_refuses_a_damaged_lesson_file_in_one_line(case, good_lessons, tmp_path):
    damaged = tmp_path / "teach.json"
    damaged.write_bytes(LESSON_CASES[case](good_lessons.read_bytes()))
    before = ft.snapshot(damaged)
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    proc = ft.cli(["train", "CartPole-v1", "--teach", damaged, "--steps", "1500", "--quiet", "--save", "saved"], cwd)
    ft.assert_refused(proc, damaged.name)
    assert ft.snapshot(damaged) == before, "the damaged file was changed"
    assert not (cwd / "saved" / "agent.npz").exists(), "an agent was trained on the damaged lessons"


# ============================================================================================ behaviour library

LIBRARY_DIR = ft.REPO / "connrl" / "data" / "behaviours"

LOAD_LIBRARY = """\
import sys
from pathlib import Path
import numpy as np
from connrl.envs.robot.tasks import OBS_SIZE
from connrl.tasks.behaviours import load_library
try:
    lib = load_library(Path(sys.argv[1]))
    for task, b in lib.items():  # used as Ch. 6 uses it
        b.applicable(np.zeros(OBS_SIZE[task]))
        b.act(np.ones(OBS_SIZE[task]) * 0.5)
except ValueError as exc:
    print(f"connrl: {exc}", file=sys.stderr)
    sys.exit(1)
print("loaded")
"""


def _file_text(transform):
    def mutate(path: Path) -> None:
        path.write_bytes(transform(path.read_bytes()))
    return mutate


def _file_doc(change):
    def mutate(path: Path) -> None:
        doc = json.loads(path.read_text())
        change(doc)
        path.write_text(json.dumps(doc, indent=1, allow_nan=True))
    return mutate


def _file_raw_field(key, raw):
    def mutate(path: Path) -> None:
        doc = json.loads(path.read_text())
        doc[key] = "@@PLACEHOLDER@@"
        path.write_text(json.dumps(doc).replace('"@@PLACEHOLDER@@"', raw))
    return mutate


def _file_npz(change):
    def mutate(path: Path) -> None:
        ft.rewrite_npz(path, change)
    return mutate


LIBRARY_CASES = {  # case id -> (file in the library folder, mutate(path))
    "dk.json-truncate-0.5": ("dk.json", _file_text(lambda b: ft.truncate(b, 0.5))),
    "dp.json-flip-seed0": ("dp.json", _file_text(lambda b: ft.flip_text(b, SEED))),
    "wfl.json-deep-100000": ("wfl.json", _file_text(lambda b: ft.deep_json().encode())),
    "wfr.json-deep-provenance": ("wfr.json", _file_raw_field("provenance", '{"x": ' + ft.deep_value() + "}")),
    "dp.json-value-range-nan": ("dp.json", _file_doc(lambda d: d.update(value_range=math.nan))),
    "dk.json-hidden-huge": ("dk.json", _file_doc(lambda d: d.update(n_hidden=10**12))),
    "wfl.json-hidden-string": ("wfl.json", _file_doc(lambda d: d.update(n_hidden="16"))),
    "dk.json-task-list": ("dk.json", _file_doc(lambda d: d.update(task=["DK"]))),
    "dk.npz-truncate-0.5": ("dk.npz", _file_text(lambda b: ft.truncate(b, 0.5))),
    "dp.npz-flip-seed1": ("dp.npz", _file_text(lambda b: ft.flip_npz(b, SEED + 1))),
    "wfr.npz-w1-nan": ("wfr.npz", _file_npz(_set("w1", (0, 0, 0), np.nan))),
    "wfl.npz-w2-inf": ("wfl.npz", _file_npz(_set("w2", (5, 0), np.inf))),
    "dp.npz-w1-strings": ("dp.npz", _file_npz(_replace("w1", lambda x: x.astype(str)))),
}


def _library_copy(tmp_path: Path) -> Path:
    lib = tmp_path / "library"
    shutil.copytree(LIBRARY_DIR, lib)
    return lib


@pytest.mark.parametrize("case", sorted(LIBRARY_CASES))
def test_a_damaged_behaviour_library_is_refused_in_one_line(case, tmp_path):
    lib = _library_copy(tmp_path)
    name, mutate = LIBRARY_CASES[case]
    mutate(lib / name)
    before = ft.snapshot(lib / name)
    proc = ft.script(LOAD_LIBRARY, [lib], tmp_path)
    ft.assert_refused(proc, name)
    assert ft.snapshot(lib / name) == before


REPORT_LIBRARY = """\
import sys
from pathlib import Path
import connrl.report.recharge as recharge
recharge.LIBRARY_DIR = Path(sys.argv[1])  # the report reads LIBRARY_DIR / library.json
try:
    recharge.results_section(Path(sys.argv[2]), Path(sys.argv[2]) / "RESULTS.md")
except ValueError as exc:
    print(f"connrl: {exc}", file=sys.stderr)
    sys.exit(1)
print("written")
"""


INDEX_CASES = {  # library.json, read by the results page's Ch. 6 section
    "truncate-0.5": _file_text(lambda b: ft.truncate(b, 0.5)),
    "deep-100000": _file_text(lambda b: ft.deep_json().encode()),
    "behaviours-list": _file_doc(lambda d: d.update(behaviours=[])),
    "missing-behaviours": _file_doc(lambda d: d.pop("behaviours")),
    "final-test-string": _file_doc(lambda d: d["behaviours"]["DK"].update(final_test_performance="good")),
    "serve-rate-nan": _file_doc(lambda d: d["behaviours"]["DP"].update(serve_rate=math.nan)),
}


@pytest.mark.parametrize("case", sorted(INDEX_CASES))
def test_a_damaged_library_index_is_refused_in_one_line(case, tmp_path):
    lib = _library_copy(tmp_path)
    INDEX_CASES[case](lib / "library.json")
    before = ft.snapshot(lib / "library.json")
    (tmp_path / "page").mkdir()
    proc = ft.script(REPORT_LIBRARY, [lib, tmp_path / "page"], tmp_path)
    ft.assert_refused(proc, "library.json")
    assert ft.snapshot(lib / "library.json") == before


# ============================================================================================ layouts

LAYOUT_DIR = ft.REPO / "connrl" / "data" / "layouts"

LOAD_LAYOUT = """\
import sys
import numpy as np
from connrl.envs.robot import Layout, RobotSim
try:
    layout = Layout.load(sys.argv[1])  # a path to a .json file
    layout.segments
    w, h = layout.size
    layout.is_free(w / 2, h / 2)
    RobotSim(layout, np.random.default_rng(0), sensor_noise=False, control_noise=False)
except ValueError as exc:
    print(f"connrl: {exc}", file=sys.stderr)
    sys.exit(1)
print("loaded")
"""


def _walls(change):
    def f(d):
        d["walls"] = change(d["walls"])
    return f


LAYOUT_CASES = {  # case id -> (shipped layout, mutate(path))
    "default-truncate-0.5": ("default", _file_text(lambda b: ft.truncate(b, 0.5))),
    "changed-truncate-0.9": ("changed", _file_text(lambda b: ft.truncate(b, 0.9))),
    "default-flip-seed0": ("default", _file_text(lambda b: ft.flip_text(b, SEED))),
    "default-deep-100000": ("default", _file_text(lambda b: ft.deep_json().encode())),
    "default-size-nan": ("default", _file_doc(lambda d: d.update(size=[math.nan, 420]))),
    "default-size-inf": ("default", _file_doc(lambda d: d.update(size=[360, math.inf]))),
    "default-size-huge": ("default", _file_doc(lambda d: d.update(size=[1e308, 1e308]))),
    "default-wall-nan": ("default", _file_doc(_walls(lambda w: [[math.nan, 0, 360, 0]] + w[1:]))),
    "default-wall-three-numbers": ("default", _file_doc(_walls(lambda w: w[:2] + [w[2][:3]] + w[3:]))),
    "default-wall-string": ("default", _file_doc(_walls(lambda w: [["x", 0, 360, 0]] + w[1:]))),
    "default-rooms-list": ("default", _file_doc(lambda d: d.update(rooms=[[0, 0, 1, 1]]))),
    "default-door-unknown-room": ("default", _file_doc(lambda d: d["doors"]["A"].update(rooms=["A", "Z"]))),
    "default-charger-approach-nan": ("default", _file_doc(lambda d: d["charger"].update(approach=[math.nan, 1]))),
    "default-not-object": ("default", _file_text(lambda b: b"[1, 2]")),
}


@pytest.mark.parametrize("case", sorted(LAYOUT_CASES))
def test_a_damaged_layout_is_refused_in_one_line(case, tmp_path):
    shipped, mutate = LAYOUT_CASES[case]
    path = tmp_path / "layouts" / f"{shipped}.json"
    path.parent.mkdir()
    shutil.copy(LAYOUT_DIR / f"{shipped}.json", path)
    mutate(path)
    before = ft.snapshot(path)
    proc = ft.script(LOAD_LAYOUT, [path], tmp_path)
    ft.assert_refused(proc, path.name)
    assert ft.snapshot(path) == before


# ============================================================================================ run records, summaries

RUN = ["run", "pole-full", "--profile", "tiny", "--out", "OUT", "--workers", "1", "--quiet"]


@pytest.fixture(scope="session")
def tiny_out(tmp_path_factory) -> Path:
    cwd = tmp_path_factory.mktemp("runs-src")
    proc = ft.cli(RUN, cwd)
    assert proc.returncode == 0, ft.describe(proc)
    return cwd / "OUT"


def _copy_out(tiny: Path, tmp_path: Path) -> tuple[Path, Path]:
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    shutil.copytree(tiny, cwd / "OUT")
    return cwd, cwd / "OUT"


def _record(out: Path) -> Path:
    (p,) = sorted((out / "pole-full" / "runs").glob("*/*/seed-0.json"))
    return p


def _raw_sub(old: str, new: str):
    def mutate(path: Path) -> None:
        text = path.read_text()
        assert old in text
        path.write_text(text.replace(old, new, 1))
    return mutate


def _into_folder(path: Path) -> None:
    path.unlink()
    path.mkdir()
    (path / "inside.txt").write_text("a folder where a file should be")


RECORD_CASES = {
    "metric-nan": _raw_sub('"trials_to_satisfactory": null', '"trials_to_satisfactory": NaN'),
    "curve-inf": _raw_sub('"curve_y": [\n  ', '"curve_y": [\n  Infinity, '),
    "truncate-0.5": _file_text(lambda b: ft.truncate(b, 0.5)),
    "deep-100000": _file_text(lambda b: ft.deep_json().encode()),
    "folder": _into_folder,
}


def _check_strict_outputs(out: Path) -> None:
    summary = out / "pole-full" / "summary.json"
    assert summary.is_file(), "no summary.json afterwards"
    ft.strict_json(summary.read_text())
    for rec in (out / "pole-full" / "runs").glob("*/*/seed-*.json"):
        assert rec.is_file(), f"{rec} is not a file after the run"
        ft.strict_json(rec.read_text())


@pytest.mark.parametrize("case", sorted(RECORD_CASES))
def test_run_redoes_a_damaged_record_with_a_notice(case, tiny_out, tmp_path):
    cwd, out = _copy_out(tiny_out, tmp_path)
    rec = _record(out)
    RECORD_CASES[case](rec)
    proc = ft.cli(RUN, cwd)
    ft.assert_noticed_or_refused(proc, rec.name)
    if proc.returncode == 0:
        _check_strict_outputs(out)


@pytest.mark.parametrize("case", ["metric-nan", "folder"])
def test_plot_names_a_damaged_record(case, tiny_out, tmp_path):
    cwd, out = _copy_out(tiny_out, tmp_path)
    rec = _record(out)
    RECORD_CASES[case](rec)
    before = ft.snapshot(rec)
    proc = ft.cli(["plot", "pole-full", "--out", "OUT"], cwd)
    ft.assert_noticed_or_refused(proc, rec.name)
    assert ft.snapshot(rec) == before


def _summary_doc(change):
    def mutate(path: Path) -> None:
        doc = json.loads(path.read_text())
        change(doc)
        path.write_text(json.dumps(doc, indent=1, allow_nan=True))
    return mutate


def _first_quantity(doc) -> dict:
    variant = next(iter(doc["variants"].values()))
    return next(iter(variant["quantities"].values()))


SUMMARY_CASES = {
    "mean-nan": _summary_doc(lambda d: _first_quantity(d).update(mean=math.nan, per_run=[math.nan])),
    "thesis-inf": _summary_doc(lambda d: _first_quantity(d).update(thesis=math.inf)),
    "truncate-0.5": _file_text(lambda b: ft.truncate(b, 0.5)),
    "deep-100000": _file_text(lambda b: ft.deep_json().encode()),
    "folder": _into_folder,
    "runs-string": _summary_doc(lambda d: d.update(runs_per_variant="1")),
    "flip-seed0": _file_text(lambda b: ft.flip_text(b, SEED)),
}


@pytest.mark.parametrize("case", sorted(SUMMARY_CASES))
def test_show_refuses_a_damaged_summary_in_one_line(case, tiny_out, tmp_path):
    cwd, out = _copy_out(tiny_out, tmp_path)
    summary = out / "pole-full" / "summary.json"
    SUMMARY_CASES[case](summary)
    before = ft.snapshot(summary)
    proc = ft.cli(["show", "pole-full", "--out", "OUT"], cwd)
    ft.assert_refused(proc, "summary.json")
    assert ft.snapshot(summary) == before


@pytest.mark.parametrize("case", ["mean-nan", "deep-100000"])
def test_results_names_a_damaged_summary(case, tiny_out, tmp_path):
    cwd, out = _copy_out(tiny_out, tmp_path)
    summary = out / "pole-full" / "summary.json"
    SUMMARY_CASES[case](summary)
    before = ft.snapshot(summary)
    proc = ft.cli(["results", "--out", "OUT", "--doc", "page/RESULTS.md"], cwd)
    ft.assert_noticed_or_refused(proc, "summary.json")
    assert ft.snapshot(summary) == before
    if proc.returncode == 0:
        assert "NaN" not in (cwd / "page" / "RESULTS.md").read_text()


@pytest.mark.parametrize("case", ["mean-nan", "folder"])
def test_run_again_rewrites_a_damaged_summary_as_strict_json(case, tiny_out, tmp_path):
    cwd, out = _copy_out(tiny_out, tmp_path)
    SUMMARY_CASES[case](out / "pole-full" / "summary.json")
    proc = ft.cli(RUN, cwd)
    ft.normal_exit(proc)
    assert "Traceback" not in proc.stderr, ft.describe(proc)
    assert proc.returncode in (0, 1, 2), ft.describe(proc)
    assert all(line.startswith("connrl: ") for line in proc.stderr.splitlines()), ft.describe(proc)
    if proc.returncode == 0:
        _check_strict_outputs(out)
    else:
        ft.assert_refused(proc, "summary.json")
