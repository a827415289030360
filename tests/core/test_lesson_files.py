"""Lesson files: round trip, and every way a file can be refused (one line: file, lesson, what is wrong, allowed)."""

import json
from importlib import resources

import numpy as np
import pytest

from connrl.core.lesson_files import LessonFileError, append_lessons, check_lesson_file, load_lessons, save_lessons
from connrl.core.lessons import Lesson


def chain_lesson(n, terminated=True, final_reward=1.0):
    inputs = np.arange(n + 1, dtype=float)[:, None]
    rewards = np.zeros(n)
    rewards[-1] = final_reward
    return Lesson(inputs, np.zeros(n, dtype=int), rewards, terminated=terminated, truncated=not terminated)


def test_lesson_file_round_trip_and_errors(tmp_path):
    p = tmp_path / "l.json"
    lesson = chain_lesson(3)
    save_lessons(p, [lesson], env_id="connrl/X-v0", source="test")
    back = load_lessons(p, env_id="connrl/X-v0", input_dim=1, n_actions=2)[0]
    np.testing.assert_array_equal(back.inputs, lesson.inputs)
    assert back.terminated and back.taught is False
    with pytest.raises(LessonFileError, match="recorded on 'connrl/X-v0'"):
        load_lessons(p, env_id="connrl/Y-v0")
    with pytest.raises(LessonFileError, match="expects 5"):
        load_lessons(p, input_dim=5)
    doc = json.loads(p.read_text())
    doc["version"] = 99
    p.write_text(json.dumps(doc))
    with pytest.raises(LessonFileError, match="version 99"):
        load_lessons(p)
    p.write_text("{not json")
    with pytest.raises(LessonFileError, match="not a JSON"):
        load_lessons(p)
    p.write_text(json.dumps({"format": "connrl-lesson", "version": 1, "lessons": [{"inputs": [[1]]}]}))
    with pytest.raises(LessonFileError, match="lesson 0 is malformed"):
        load_lessons(p)
    with pytest.raises(LessonFileError, match="no such"):
        load_lessons(tmp_path / "missing.json")


def good_doc():
    return {"format": "connrl-lesson", "version": 1, "env_id": "connrl/X-v0", "env_kwargs": {}, "source": "test",
            "lessons": [{"inputs": [[0.0, 0.5], [1.0, 0.5], [2.0, 0.5]], "actions": [0, 1], "rewards": [0.0, 1.0],
                         "terminated": True, "truncated": False, "taught": True, "meta": {}}]}


def _set(key, value, where="lesson"):
    def change(doc):
        (doc["lessons"][0] if where == "lesson" else doc)[key] = value
    return change


def _set_item(key, index, value):
    def change(doc):
        target = doc["lessons"][0][key]
        if isinstance(index, tuple):
            target[index[0]][index[1]] = value
        else:
            target[index] = value
    return change


INPUT_SHAPE = "a list of rows, one per state, each a list of the same number of finite numbers"
NEEDS = "a lesson needs 'inputs', 'actions', 'rewards' and 'terminated'"

# (case, change to a good document, load kwargs, message after "<path>: ")
REFUSED = [
    ("lessons-dict", _set("lessons", {"a": 1}, "doc"), {},
     "'lessons' is an object of 1 key; it must be a list of lesson objects"),
    ("lessons-string", _set("lessons", "abc", "doc"), {},
     "'lessons' is a string (\"abc\"); it must be a list of lesson objects"),
    ("lessons-missing", lambda d: d.pop("lessons"), {},
     "the file has no 'lessons'; it must hold a list of lesson objects"),
    ("lessons-empty", _set("lessons", [], "doc"), {}, "the file holds no lessons"),
    ("entry-not-object", lambda d: d["lessons"].append(5), {},
     f"lesson 1 is an integer (5); each lesson must be a JSON object ({NEEDS})"),
    ("missing-terminated", lambda d: d["lessons"][0].pop("terminated"), {},
     f"lesson 0 is malformed: it has no 'terminated'; {NEEDS}"),
    ("nan-input", _set_item("inputs", (1, 0), float("nan")), {},
     "lesson 0: input row 1, column 0 is a number (nan); inputs must be finite numbers"),
    ("inf-input", _set_item("inputs", (2, 1), float("-inf")), {},
     "lesson 0: input row 2, column 1 is a number (-inf); inputs must be finite numbers"),
    ("string-input", _set_item("inputs", (0, 1), "0.5"), {},
     "lesson 0: input row 0, column 1 is a string (\"0.5\"); inputs must be finite numbers"),
    ("bool-input", _set_item("inputs", (0, 0), True), {},
     "lesson 0: input row 0, column 0 is a boolean (true); inputs must be finite numbers"),
    ("inf-reward", _set_item("rewards", 1, float("inf")), {},
     "lesson 0: reward 1 is a number (inf); rewards must be finite numbers"),
    ("nan-reward", _set_item("rewards", 0, float("nan")), {},
     "lesson 0: reward 0 is a number (nan); rewards must be finite numbers"),
    ("bool-reward", _set_item("rewards", 0, False), {},
     "lesson 0: reward 0 is a boolean (false); rewards must be finite numbers"),
    ("rewards-not-list", _set("rewards", 1.0), {},
     "lesson 0: 'rewards' is a number (1.0); it must be a list of finite numbers"),
    ("float-action", _set_item("actions", 1, 1.5), {"n_actions": 2},
     "lesson 0: action 1 is a number (1.5); actions must be integers 0..1"),
    ("whole-float-action", _set_item("actions", 1, 1.0), {"n_actions": 2},
     "lesson 0: action 1 is a number (1.0); actions must be integers 0..1"),
    ("bool-action", _set_item("actions", 0, True), {"n_actions": 2},
     "lesson 0: action 0 is a boolean (true); actions must be integers 0..1"),
    ("string-action", _set_item("actions", 0, "1"), {},
     "lesson 0: action 0 is a string (\"1\"); actions must be non-negative integers"),
    ("action-too-big", _set_item("actions", 1, 5), {"n_actions": 2},
     "lesson 0: action 1 is 5, outside the allowed actions; actions must be integers 0..1"),
    ("negative-action", _set_item("actions", 0, -1), {},
     "lesson 0: action 0 is -1, outside the allowed actions; actions must be non-negative integers"),
    ("no-actions", lambda d: d["lessons"][0].update(inputs=[[0.0, 0.5]], actions=[], rewards=[]), {},
     "lesson 0: 'actions' is a list of 0 items; it must be a non-empty list of non-negative integers"),
    ("int-terminated", _set("terminated", 1), {},
     "lesson 0: 'terminated' is an integer (1); it must be true or false"),
    ("string-truncated", _set("truncated", "false"), {},
     "lesson 0: 'truncated' is a string (\"false\"); it must be true or false"),
    ("null-taught", _set("taught", None), {}, "lesson 0: 'taught' is null; it must be true or false"),
    ("meta-list", _set("meta", [["a", 1]]), {}, "lesson 0: 'meta' is a list of 1 item; it must be a JSON object"),
    ("inputs-1d", _set("inputs", [0.0, 1.0, 2.0]), {},
     f"lesson 0: input row 0 is a number (0.0); 'inputs' must be {INPUT_SHAPE}"),
    ("inputs-3d", _set("inputs", [[[0.0]], [[1.0]], [[2.0]]]), {},
     "lesson 0: input row 0, column 0 is a list of 1 item; inputs must be finite numbers"),
    ("inputs-ragged", _set_item("inputs", 1, [1.0]), {},
     f"lesson 0: input row 1 has 1 numbers, row 0 has 2; 'inputs' must be {INPUT_SHAPE}"),
    ("inputs-empty-rows", _set("inputs", [[], [], []]), {},
     f"lesson 0: input row 0 is a list of 0 items; 'inputs' must be {INPUT_SHAPE}"),
    ("inputs-rows", lambda d: d["lessons"][0]["inputs"].pop(), {},
     "lesson 0: 'inputs' has 2 rows for 2 actions; it must have one row per state, 3 (actions + 1)"),
    ("rewards-length", lambda d: d["lessons"][0]["rewards"].append(0.0), {},
     "lesson 0: 'rewards' has 3 values for 2 actions; it must have one reward per action"),
    ("input-width", lambda d: None, {"input_dim": 5},
     "lesson 0 has 2 inputs, the agent expects 5 (every input row must hold 5 numbers)"),
    ("env-kwargs-list", _set("env_kwargs", ["local"], "doc"), {},
     "'env_kwargs' is a list of 1 item; it must be a JSON object of world options"),
]


@pytest.mark.parametrize("change,kwargs,message", [c[1:] for c in REFUSED], ids=[c[0] for c in REFUSED])
def test_load_refuses_with_one_line_naming_file_lesson_problem_and_what_is_allowed(tmp_path, change, kwargs,
                                                                                    message):
    p = tmp_path / "l.json"
    p.write_text(json.dumps(good_doc()))
    assert len(load_lessons(p, input_dim=2, n_actions=2)) == 1  # the unchanged document loads
    doc = good_doc()
    change(doc)
    p.write_text(json.dumps(doc))
    before = p.read_bytes()
    with pytest.raises(LessonFileError) as err:
        load_lessons(p, **kwargs)
    assert str(err.value) == f"{p}: {message}"
    assert "\n" not in str(err.value)
    assert p.read_bytes() == before and [x.name for x in tmp_path.iterdir()] == ["l.json"]  # nothing written


def test_load_refuses_a_directory_with_one_line(tmp_path):
    with pytest.raises(LessonFileError) as err:
        load_lessons(tmp_path)
    assert str(err.value) == f"{tmp_path}: is a folder; a lesson file was expected"
    assert list(tmp_path.iterdir()) == []


def test_save_refuses_a_lesson_it_could_not_load_and_writes_nothing(tmp_path):
    p = tmp_path / "l.json"
    bad = chain_lesson(2)
    bad.rewards[0] = np.nan
    with pytest.raises(LessonFileError) as err:
        save_lessons(p, [chain_lesson(1), bad], env_id="connrl/X-v0")
    assert str(err.value) == f"{p}: lesson 1 (not written): reward 0 is a number (nan); rewards must be finite numbers"
    assert list(tmp_path.iterdir()) == []


def test_save_then_load_gives_identical_lessons(tmp_path):
    rng = np.random.default_rng(0)
    lessons = [Lesson(rng.normal(size=(n + 1, 3)), rng.integers(0, 4, n), rng.normal(size=n), terminated=n % 2 == 0,
                      truncated=n % 2 == 1, taught=n != 2, meta={"n": n, "note": "x"}) for n in (1, 2, 5)]
    p = tmp_path / "l.json"
    save_lessons(p, lessons, env_id="connrl/X-v0", env_kwargs={"k": 1}, source="s")
    back = load_lessons(p, env_id="connrl/X-v0", input_dim=3, n_actions=4)
    for a, b in zip(lessons, back, strict=True):
        for field in ("inputs", "actions", "rewards"):
            x, y = getattr(a, field), getattr(b, field)
            assert x.dtype == y.dtype and np.array_equal(x, y)
        assert (a.terminated, a.truncated, a.taught, a.meta) == (b.terminated, b.truncated, b.taught, b.meta)


@pytest.mark.parametrize("name", ["robot-dk", "robot-dp", "robot-wfl", "survival-global", "survival-local"])
def test_shipped_lesson_files_load_exactly_their_json(name):
    src = resources.files("connrl") / "data" / "lessons" / f"{name}.json"
    raw = json.loads(src.read_text())
    lessons = load_lessons(src, env_id=raw["env_id"])
    assert len(lessons) == len(raw["lessons"])
    for lesson, r in zip(lessons, raw["lessons"], strict=True):
        assert lesson.inputs.dtype == np.float64 and np.array_equal(lesson.inputs, np.array(r["inputs"]))
        assert lesson.actions.dtype == np.int64 and lesson.actions.tolist() == r["actions"]
        assert lesson.rewards.tolist() == r["rewards"]
        assert (lesson.terminated, lesson.truncated, lesson.taught, lesson.meta) == (
            r["terminated"], r["truncated"], r["taught"], r["meta"])


def test_world_options_are_compared_with_defaults_filled_in(tmp_path):
    p = tmp_path / "l.json"
    save_lessons(p, [chain_lesson(2)], env_id="connrl/X-v0", env_kwargs={"side": "local"})
    before = p.read_bytes()
    with pytest.raises(LessonFileError) as err:
        check_lesson_file(p, env_id="connrl/X-v0", env_kwargs={"side": "global"})
    assert str(err.value) == (f"{p}: lessons were recorded with world options side='local' (expected 'global'); "
                              f"a lesson file holds lessons of one world, all with the same options")
    with pytest.raises(LessonFileError, match=r"side='local' \(expected '\(unset\)'\)"):
        check_lesson_file(p, env_id="connrl/X-v0")
    assert check_lesson_file(p, env_id="connrl/X-v0", option_defaults={"side": "local"})["env_kwargs"] == {
        "side": "local"}
    assert check_lesson_file(p, env_id="connrl/X-v0", env_kwargs={"side": "local", "size": (2, 3)},
                             option_defaults={"size": [2, 3]})["source"] == ""
    assert p.read_bytes() == before


def test_append_keeps_the_file_metadata_and_its_lessons_verbatim(tmp_path):
    p = tmp_path / "l.json"
    doc = good_doc()
    doc.update(env_kwargs={}, source="a person, long ago", note="kept")
    doc["lessons"][0].pop("taught")  # an optional field left out stays left out
    p.write_text(json.dumps(doc))
    played = Lesson(np.array([[3.0, 0.5], [4.0, 0.5]]), np.array([1]), np.array([0.5]), terminated=True, taught=True)
    assert append_lessons(p, [played], env_id="connrl/X-v0", env_kwargs={"side": "global"},
                          option_defaults={"side": "global"}, n_actions=2) == 2
    after = json.loads(p.read_text())
    assert {k: v for k, v in after.items() if k != "lessons"} == {k: v for k, v in doc.items() if k != "lessons"}
    assert after["lessons"][0] == doc["lessons"][0] and len(after["lessons"]) == 2
    assert load_lessons(p)[1].inputs.tolist() == [[3.0, 0.5], [4.0, 0.5]]
    before = p.read_bytes()
    with pytest.raises(LessonFileError) as err:
        append_lessons(p, [played], env_id="connrl/X-v0", input_dim=1)
    assert str(err.value) == f"{p}: lesson 0 has 2 inputs, the agent expects 1 (every input row must hold 1 numbers)"
    with pytest.raises(LessonFileError) as err:  # a lesson of another width never joins the file
        append_lessons(p, [chain_lesson(1)], env_id="connrl/X-v0")
    assert str(err.value) == (f"{p}: lesson 2 (not written) has 1 inputs, the agent expects 2 "
                              f"(every input row must hold 2 numbers)")
    assert p.read_bytes() == before and [x.name for x in tmp_path.iterdir()] == ["l.json"]


@pytest.mark.parametrize("name", ["robot-dk", "robot-dp", "robot-wfl", "survival-global", "survival-local"])
def test_shipped_lesson_files_are_rewritten_byte_for_byte(tmp_path, name):
    src = resources.files("connrl") / "data" / "lessons" / f"{name}.json"
    raw = json.loads(src.read_text())
    p = tmp_path / "again.json"
    save_lessons(p, load_lessons(src), env_id=raw["env_id"], env_kwargs=raw["env_kwargs"], source=raw["source"])
    assert p.read_bytes() == src.read_bytes()


def test_a_boolean_version_is_not_version_1(tmp_path):
    import json

    from connrl.core.lesson_files import LessonFileError, load_lessons

    path = tmp_path / "l.json"
    path.write_text(json.dumps({"format": "connrl-lesson", "version": True, "env_id": "x", "env_kwargs": {},
                                "lessons": []}))
    with pytest.raises(LessonFileError, match="lesson format version True is not supported"):
        load_lessons(path)
