"""The number of experienced lessons replayed after a trial is the schedule's value rounded to the nearest integer
(4.2.7's n moving from 12 to 4 passes through fractions), not cut down: 4.6 -> 5, 4.4 -> 4, 3.5 -> 4, and 2.5 -> 2
(Python's round-half-even)."""

import numpy as np
import pytest

from connrl.agents import QCON, LinearSchedule, QCONConfig, ReplayConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.nets import NetConfig


def replays_after_one_trial(per_trial):
    cfg = QCONConfig(net=NetConfig(2, 3, lr=0.1, init_range=0.5), temperature=TemperatureSchedule.inverse(10, 30, 50),
                     replay=ReplayConfig(capacity=10, lessons_per_trial=LinearSchedule(per_trial, per_trial),
                                         p_threshold=0.0))
    agent = QCON(cfg, 2, np.random.default_rng(0))
    x = np.zeros(2)
    agent.begin_trial(x, trial=0, learning=True)
    agent.observe(agent.act(x), 1.0, x, True, False)
    agent.end_trial()  # one lesson stored
    calls = []
    agent.replay_lesson = lambda lesson, p_threshold, *args, **kw: calls.append(lesson)
    agent.learn()
    return len(calls)


@pytest.mark.parametrize(("per_trial", "n"), [(4.6, 5), (4.4, 4), (3.5, 4), (2.5, 2), (4.0, 4)])
def test_lessons_per_trial_is_rounded_not_truncated(per_trial, n):
    assert replays_after_one_trial(per_trial) == n
