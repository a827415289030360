"""Ch. 7 wiring: the cup test measure, the robustness probe against scripted agents, Table B.1's parameters."""

import numpy as np
import pytest

from connrl.envs.cup import LEFT, PICK_UP, RIGHT, CupCollectionEnv
from connrl.experiments.hidden_state import CupParams, PoleHiddenParams
from connrl.tasks import hidden_state as hs


class Oracle:
    """Reads the true state from ``info`` (walk to the nearest remaining cup, pick it up)."""

    n_actions = 3

    def begin_trial(self, obs, info=None, *, trial=0, learning=True):
        self.info = info

    def act(self, obs, info=None, *, greedy=False, force=None):
        pos, cups = info["position"], info["cups"]
        target = min(cups, key=lambda c: abs(c - pos))
        a = PICK_UP if target == pos else (RIGHT if target > pos else LEFT)
        return a if force is None else force

    def observe(self, *args, **kwargs):
        pass

    def end_trial(self):
        pass

    def learn(self):
        pass


class Habit(Oracle):
    """Optimal when undisturbed, but after the first cup it keeps walking the way it last walked: the
    window-Q failure of 7.5.1 ('its policy will choose to continue on the new direction')."""

    def begin_trial(self, obs, info=None, *, trial=0, learning=True):
        self.last_move = None

    def act(self, obs, info=None, *, greedy=False, force=None):
        pos, cups = info["position"], info["cups"]
        if len(cups) == 2 or self.last_move is None or pos in cups:
            a = Oracle.act(self, obs, info)
        else:
            a = self.last_move
        a = a if force is None else force
        if a != PICK_UP:
            self.last_move = a
        return a


def test_test_score_of_the_optimal_policy_is_14():
    assert hs.test_score(CupCollectionEnv(), Oracle()) == hs.OPTIMAL_SCORE == 14


def test_probe_tells_a_state_based_policy_from_a_habit():
    oracle = hs.robustness_probe(Oracle(), 0)
    habit = hs.robustness_probe(Habit(), 0)
    assert len(oracle) == len(habit) == 2 * 4 * 3
    assert all(r["resumed_optimally"] for r in oracle)
    assert not any(r["resumed_optimally"] for r in habit)
    # instance A, one greedy step after the first cup (cell 4), forced 2 steps left: cell 2, 5 steps left
    r = next(r for r in oracle if (r["instance"], r["walk"], r["forced"]) == ("A", 1, 2))
    assert (r["position"], r["optimal"], r["steps"]) == (2, 6, 6)


def test_table_b1_parameters_reach_the_nets():
    rng = np.random.default_rng(0)
    agent = hs.make_agent(CupParams(task=2, arch="recurrent-model"), 6, 3, rng)
    m = agent.model.config
    assert (m.n_hidden, m.n_context, m.n_outputs, m.lr, m.feedback, m.decay) == (26, 18, 7, 0.02, 1.5, 0.9)
    assert (agent.q.config.n_inputs, agent.q.config.n_hidden, agent.q.config.lr) == (24, 11, 0.2)
    agent = hs.make_agent(CupParams(task=3, arch="window-Q", lam=0.0), 4, 3, rng)
    assert (agent.config.net.n_hidden, agent.config.net.lr, agent.config.lam) == (0, 0.01, 0.0)
    assert agent.config.net.n_inputs == 4 * 6 + 3 * 5
    assert agent.config.replay.threshold_for_age(0) == pytest.approx(0.01)
    assert agent.config.replay.threshold_for_age(69) == pytest.approx(1e-5)
    agent = hs.make_agent(PoleHiddenParams(arch="recurrent-Q"), 2, 2, rng)
    assert (agent.net.config.n_context, agent.net.config.n_hidden, agent.config.lam) == (2, 10, 0.7)
    assert agent.explore.schedule(0) == pytest.approx(1 / 20) and agent.explore.schedule(999) == pytest.approx(1 / 50)
    with pytest.raises(ValueError, match="arch must be one of"):
        hs.make_agent(CupParams(arch="lstm"), 4, 3, rng)


class _Recorder:
    """A stand-in for recurrent-model: says every step is wrong (or none), and keeps the walks it is shown."""

    def __init__(self, wrong: bool):
        self.wrong, self.lessons = wrong, []

    def wrong_steps(self, lesson):
        self.lessons.append(lesson)
        return np.full(lesson.actions.size, self.wrong)


def test_model_probe_counts_cups_that_appear_after_ten_unseen_steps():
    from connrl.tasks.hidden_state import model_probe
    always, never = _Recorder(True), _Recorder(False)
    a, b = model_probe(always, 1, seed=3, walks=40), model_probe(never, 1, seed=3, walks=40)
    assert (a["probe_wrong_steps"], b["probe_wrong_steps"]) == (1.0, 0.0)
    assert a["probe_cup_after_unseen_n"] == b["probe_cup_after_unseen_n"] > 0  # same walks from the same seed
    assert (a["probe_cup_after_unseen_wrong"], b["probe_cup_after_unseen_wrong"]) == (1.0, 0.0)
    events = 0  # counted here by scanning each walk's sensations: cup bit on, none in the 10 before
    for lesson in always.lessons:
        seen = [bool(x[0] > 0 or x[1] > 0) for x in lesson.inputs]
        events += sum(1 for i in range(10, len(seen)) if seen[i] and not any(seen[i - 10:i]))
    assert events == a["probe_cup_after_unseen_n"]
    assert len(always.lessons) == 40 and {len(x.actions) for x in always.lessons} <= set(range(1, 31))
