"""Lessons (3.5): the recorder, the shape check, the memory of the latest lessons and App. A.2's recency rule."""

import math

import numpy as np
import pytest

from connrl.core.lessons import Lesson, LessonMemory, LessonRecorder, recency_index


def chain_lesson(n, terminated=True, final_reward=1.0):
    inputs = np.arange(n + 1, dtype=float)[:, None]
    rewards = np.zeros(n)
    rewards[-1] = final_reward
    return Lesson(inputs, np.zeros(n, dtype=int), rewards, terminated=terminated, truncated=not terminated)


def test_recorder_builds_a_lesson():
    rec = LessonRecorder()
    rec.add(np.zeros(2), 1, 0.5, np.ones(2))
    rec.add(np.ones(2), 0, -1.0, 2 * np.ones(2))
    lesson = rec.finish(terminated=True, truncated=False)
    assert len(lesson) == 2 and lesson.inputs.shape == (3, 2) and lesson.terminated
    assert rec.finish(False, False) is None


def test_lesson_shape_is_checked():
    with pytest.raises(ValueError, match="input rows"):
        Lesson(np.zeros((3, 2)), np.zeros(3, dtype=int), np.zeros(3), terminated=True)


def test_lesson_memory_keeps_the_latest():
    mem = LessonMemory(3)
    for i in range(5):
        mem.add(chain_lesson(1 + i))
    assert [len(x) for x in mem.lessons] == [3, 4, 5]
    age, lesson = mem.sample(np.random.default_rng(0))
    assert mem.lessons[len(mem) - 1 - age] is lesson


def test_recency_index_formula():
    n = 100
    w = min(3, 1 + 0.02 * n)
    for r in (0.0, 0.1, 0.5, 0.9, 0.999):
        assert recency_index(n, r) == math.floor(n * math.log(1 + r * (math.exp(w) - 1)) / w)
    assert recency_index(1, 0.7) == 0
    # recent lessons are favoured: the mean index is well above the middle
    rng = np.random.default_rng(0)
    ks = [recency_index(100, rng.random()) for _ in range(20000)]
    assert 0 <= min(ks) and max(ks) <= 99
    assert np.mean(ks) > 60
