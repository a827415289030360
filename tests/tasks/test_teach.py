"""connrl teach: keys drive the environment and the trial becomes a taught lesson file."""

import io
import json
from importlib import resources

import pytest

from connrl import cli
from connrl.core.lesson_files import LessonFileError, load_lessons
from connrl.tasks.teach import TEACH_TARGETS, play, teach


def test_play_records_steps_and_ends_on_x():
    import gymnasium as gym

    import connrl.envs  # noqa: F401

    env = gym.make("connrl/PoleBalancing-v0")
    keys = iter(["l", "?", "r", "x"])
    messages = []
    steps, saved = play(env, {"l": 0, "r": 1}, lambda: next(keys), lambda e, info: messages.append(info), seed=0)
    assert saved and [s[1] for s in steps] == [0, 1] and steps[-1][5] is True
    assert any("unknown key" in str(m.get("message", "")) for m in messages if m)


def test_quit_saves_nothing():
    import gymnasium as gym

    env = gym.make("CartPole-v1")
    steps, saved = play(env, {"l": 0}, lambda: "u", lambda e, info: None)
    assert not saved


def test_cli_teach_survival_writes_a_loadable_lesson(tmp_path, monkeypatch):
    out = tmp_path / "lesson.json"
    monkeypatch.setattr("sys.stdin", io.StringIO("w\nd\nd\nx\n"))
    assert cli.main(["teach", "survival", "--out", str(out)]) == 0
    monkeypatch.setattr("sys.stdin", io.StringIO("s\nx\n"))
    assert cli.main(["teach", "survival", "--out", str(out)]) == 0  # appends
    lessons = load_lessons(out, env_id="connrl/Survival-v0", input_dim=145, n_actions=4)
    assert [len(x) for x in lessons] == [3, 1] and all(x.taught for x in lessons)


@pytest.mark.parametrize("target", ["survival", "survival-local", "robot-dp", "robot-dk", "robot-wfl", "robot-wfr"])
def test_targets_exist(target):
    assert target in TEACH_TARGETS


# ------------------------------------------------- teach --out EXISTING: checked before play, never relabelled,
# and a trial played for a file that then cannot take it is saved beside it.

SURVIVAL = "connrl/Survival-v0"
SHIPPED = resources.files("connrl") / "data" / "lessons"


class Keys:
    """Keys for ``play``; ``during`` runs before the first key is read (something happens while a person plays)."""

    def __init__(self, *keys, during=None):
        self.keys, self.read, self.during = list(keys), 0, during

    def __call__(self):
        if self.read == 0 and self.during:
            self.during()
        self.read += 1
        return self.keys[self.read - 1]


def quiet(env, info):
    pass


def shipped_survival(tmp_path, change=None, name="lesson.json"):
    doc = json.loads((SHIPPED / "survival-global.json").read_text())
    if change:
        change(doc)
    out = tmp_path / name
    out.write_text(json.dumps(doc))
    return out


def _set_action(doc):
    doc["lessons"][1]["actions"][2] = 4


REFUSE_BEFORE_PLAY = [
    ("world-options", "survival", lambda d: d["env_kwargs"].update(action_representation="local"),
     "{out}: lessons were recorded with world options action_representation='local' (expected 'global'); "
     "a lesson file holds lessons of one world, all with the same options"),
    ("world-options-local", "survival-local", None,
     "{out}: lessons were recorded with world options action_representation='global' (expected 'local'); "
     "a lesson file holds lessons of one world, all with the same options"),
    ("world", "robot-dp", None, "{out}: lessons were recorded on 'connrl/Survival-v0', expected 'connrl/Robot-DP-v0'"),
    ("input-size", "survival", lambda d: d["lessons"][0].update(inputs=[r[:100] for r in d["lessons"][0]["inputs"]]),
     "{out}: lesson 0 has 100 inputs, the agent expects 145 (every input row must hold 145 numbers)"),
    ("number-of-actions", "survival", _set_action,
     "{out}: lesson 1: action 2 is 4, outside the allowed actions; actions must be integers 0..3"),
    ("non-finite", "survival", lambda d: d["lessons"][0]["rewards"].__setitem__(0, float("nan")),
     "{out}: lesson 0: reward 0 is a number (nan); rewards must be finite numbers"),
    ("lessons-not-a-list", "survival", lambda d: d.update(lessons={"0": d["lessons"][0]}),
     "{out}: 'lessons' is an object of 1 key; it must be a list of lesson objects"),
]


@pytest.mark.parametrize("target,change,message", [c[1:] for c in REFUSE_BEFORE_PLAY],
                         ids=[c[0] for c in REFUSE_BEFORE_PLAY])
def test_teach_checks_an_existing_out_file_before_the_person_plays(tmp_path, target, change, message):
    out = shipped_survival(tmp_path, change)
    before = out.read_bytes()
    keys = Keys("w", "x")
    with pytest.raises(LessonFileError) as err:
        teach(target, out=out, read_key=keys, show=quiet)
    assert str(err.value) == (message.format(out=out) + f"; `connrl teach {target}` will not add its lesson to "
                              f"this file (choose another --out file)")
    assert "\n" not in str(err.value)
    assert keys.read == 0  # refused before any play
    assert out.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["lesson.json"]


def test_teach_refuses_a_damaged_out_file_or_folder_before_the_person_plays(tmp_path):
    out = tmp_path / "lesson.json"
    out.write_text("{half a fi")
    keys = Keys("w", "x")
    with pytest.raises(LessonFileError) as err:
        teach("survival", out=out, read_key=keys, show=quiet)
    assert str(err.value).startswith(f"{out}: not a JSON lesson file (")
    assert str(err.value).endswith("; `connrl teach survival` will not add its lesson to this file "
                                   "(choose another --out file)")
    (tmp_path / "folder").write_text("a file")
    with pytest.raises(LessonFileError) as err:
        teach("survival", out=tmp_path / "folder" / "l.json", read_key=keys, show=quiet)
    assert str(err.value) == (f"{tmp_path / 'folder' / 'l.json'}: {tmp_path / 'folder'} is not a directory; "
                              f"--out must be a file in a directory")
    assert keys.read == 0 and out.read_text() == "{half a fi" and (tmp_path / "folder").read_text() == "a file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder", "lesson.json"]


@pytest.mark.parametrize("target,shipped,env_kwargs", [
    ("survival", "survival-global", {}),  # a file left at the default representation stays unlabelled
    ("survival", "survival-global", {"action_representation": "global"}),
    ("survival-local", "survival-local", {"action_representation": "local"}),
    ("robot-dp", "robot-dp", {}),
])
def test_teach_appends_keeping_the_file_metadata_and_lessons(tmp_path, target, shipped, env_kwargs):
    doc = json.loads((SHIPPED / f"{shipped}.json").read_text())
    doc.update(env_kwargs=env_kwargs, note="kept as it is")
    out = tmp_path / "lesson.json"
    out.write_text(json.dumps(doc))
    key = next(iter(TEACH_TARGETS[target].keymap))
    assert teach(target, out=out, read_key=Keys(key, "x"), show=quiet) == 0
    after = json.loads(out.read_text())
    assert {k: v for k, v in after.items() if k != "lessons"} == {k: v for k, v in doc.items() if k != "lessons"}
    assert after["lessons"][:-1] == doc["lessons"]
    new = load_lessons(out, env_id=doc["env_id"])[-1]
    assert len(new) == 1 and new.taught and new.truncated and new.meta["made_by"] == "person (connrl teach)"
    assert [p.name for p in tmp_path.iterdir()] == ["lesson.json"]


def _rescued(folder):
    found = list(folder.glob("lesson.rescued-*.json"))
    assert len(found) == 1, found
    lessons = load_lessons(found[0], env_id=SURVIVAL, input_dim=145, n_actions=4)
    assert len(lessons) == 1 and lessons[0].actions.tolist() == [0, 1] and lessons[0].taught
    assert json.loads(found[0].read_text())["env_kwargs"] == {"action_representation": "global"}
    return found[0]


def test_a_file_damaged_during_play_keeps_the_trial_beside_it(tmp_path, capsys):
    out = shipped_survival(tmp_path)
    assert teach("survival", out=out, read_key=Keys("w", "d", "x", during=lambda: out.write_text("{oops")),
                 show=quiet) == 1
    assert out.read_text() == "{oops"  # not touched after the damage
    rescued = _rescued(tmp_path)
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith(f"connrl: the played lesson was not saved: {out}: not a JSON lesson file (")
    assert err[1] == f"connrl: the played trial (2 steps) is saved in {rescued} instead"


def test_a_file_changed_to_another_world_during_play_keeps_the_trial_beside_it(tmp_path, capsys):
    out = shipped_survival(tmp_path)
    local = (SHIPPED / "survival-local.json").read_bytes()
    assert teach("survival", out=out, read_key=Keys("w", "d", "x", during=lambda: out.write_bytes(local)),
                 show=quiet) == 1
    assert out.read_bytes() == local  # never relabelled
    rescued = _rescued(tmp_path)
    err = capsys.readouterr().err.splitlines()
    assert err == [f"connrl: the played lesson was not saved: {out}: lessons were recorded with world options "
                   f"action_representation='local' (expected 'global'); a lesson file holds lessons of one world, "
                   f"all with the same options",
                   f"connrl: the played trial (2 steps) is saved in {rescued} instead"]


def test_an_unwritable_out_keeps_the_trial_in_the_working_directory(tmp_path, capsys, monkeypatch):
    folder, cwd = tmp_path / "lessons", tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    out = folder / "lesson.json"

    def folder_becomes_a_file():
        folder.write_text("not a folder")

    assert teach("survival", out=out, read_key=Keys("w", "d", "x", during=folder_becomes_a_file), show=quiet) == 1
    assert folder.read_text() == "not a folder"
    rescued = _rescued(cwd)
    err = capsys.readouterr().err.splitlines()
    assert err[0] == (f"connrl: the played lesson was not saved: {out}: cannot write the file (File exists: "
                      f"{folder})")
    assert err[1] == f"connrl: the played trial (2 steps) is saved in {rescued} instead"


def test_the_rescue_never_overwrites_a_file(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("connrl.tasks.teach.time.strftime", lambda fmt: "T")
    out = shipped_survival(tmp_path)
    taken = tmp_path / "lesson.rescued-T.json"
    taken.write_text("someone else's")
    assert teach("survival", out=out, read_key=Keys("w", "d", "x", during=lambda: out.write_text("[]")),
                 show=quiet) == 1
    assert taken.read_text() == "someone else's" and out.read_text() == "[]"
    rescued = tmp_path / "lesson.rescued-T-1.json"
    assert len(load_lessons(rescued, env_id=SURVIVAL)) == 1
    last = capsys.readouterr().err.splitlines()[-1]
    assert last == f"connrl: the played trial (2 steps) is saved in {rescued} instead"


def test_when_nothing_can_be_written_the_trial_is_printed_as_a_lesson_file(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("connrl.tasks.teach._reserve", lambda folder, stem: None)  # no folder takes a file
    out = shipped_survival(tmp_path)
    assert teach("survival", out=out, read_key=Keys("w", "d", "x", during=lambda: out.write_text("[]")),
                 show=quiet) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[1] == "connrl: could not write the played trial anywhere; here is its lesson file:"
    printed = tmp_path / "printed.json"
    printed.write_text(err[2])
    lessons = load_lessons(printed, env_id=SURVIVAL, input_dim=145, n_actions=4)
    assert [x.actions.tolist() for x in lessons] == [[0, 1]] and out.read_text() == "[]"
