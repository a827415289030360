"""Lesson files: round trip, and every way a file can be refused."""

import json

import numpy as np
import pytest

from connrl.core.lesson_files import LessonFileError, load_lessons, save_lessons
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
