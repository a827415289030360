"""connrl teach: keys drive the environment and the trial becomes a taught lesson file."""

import io

import pytest

from connrl import cli
from connrl.core.lesson_files import load_lessons
from connrl.tasks.teach import TEACH_TARGETS, play


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
