"""A trial's replays in one compiled call (issue 45): the same lessons, thresholds and order give the nets and the
random stream of one call per lesson, bit for bit, for an OAON (Fig. 5.1a) and a recurrent Q-net (7.5); the agents
use it only where their replays draw nothing."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from connrl.agents import QCON, QCONConfig
from connrl.agents.base import LinearSchedule, ReplayConfig
from connrl.agents.memory import RecurrentModelConfig, RecurrentModelQ, RecurrentQ, RecurrentQConfig
from connrl.core.exploration import TemperatureSchedule
from connrl.core.lessons import Lesson, MixedOptions, pack_lessons
from connrl.core.replay import ReplayParams, replay_q_lessons
from connrl.core.replay_kernel import replay_oaon
from connrl.nets import OAON, NetConfig
from connrl.nets.recurrent import RecurrentNetConfig, RecurrentOAON

D, A = 7, 4


def _lessons(rng, k=5):
    out = []
    for i in range(k):
        n = int(rng.integers(0, 15))
        lesson = Lesson(rng.uniform(-0.5, 1.0, (n + 1, D)), rng.integers(0, A, n), rng.choice([0.0, -1.0, 1.0], n),
                        terminated=i % 2 == 0, truncated=i % 2 == 1)
        lesson.meta["weights"] = rng.choice([0.0, 1.0, 2.0], (n, A))
        lesson.meta["weights"][:, 0] = 1.0  # never all 0 in a row
        lesson.meta["allowed"] = rng.random((n + 1, A)) < 0.7
        out.append(lesson)
    return out


def _picks(rng, lessons, m=12):
    idx = rng.integers(0, len(lessons), m)  # repeats, as App. A.2's draws make them
    return [lessons[i] for i in idx], [float(t) for t in rng.choice([0.0, 0.01, 0.2], m)]


def _with(per_step):
    return (lambda x: (x.meta["weights"], x.meta["allowed"])) if per_step else (lambda x: (None, None))


@pytest.mark.parametrize("hidden", [6, 0])
@pytest.mark.parametrize("per_step", [False, True])
def test_one_call_is_the_replays_one_by_one_for_an_oaon(hidden, per_step):
    rng = np.random.default_rng(hidden + per_step)
    cfg = NetConfig(D, hidden, value_range=1.0, init_range=0.5, lr=0.1, momentum=0.9 if hidden else 0.0)
    one, each = OAON(cfg, A, np.random.default_rng(1)), OAON(cfg, A, np.random.default_rng(1))
    lessons = _lessons(rng)
    picks, thresholds = _picks(rng, lessons)
    params = ReplayParams(gamma=0.9, lam=0.8, temperature=0.1, clip=0.9)
    options = _with(per_step)
    used = replay_q_lessons(one, picks, thresholds, params, options)
    used_each = sum(replay_oaon(each, x, dataclasses.replace(params, p_threshold=p), 0, *options(x))
                    for x, p in zip(picks, thresholds, strict=True))
    assert used == used_each
    for name in ("w1", "w2", "d1", "d2"):
        np.testing.assert_array_equal(getattr(one, name), getattr(each, name))


@pytest.mark.parametrize("per_step", [False, True])
def test_one_call_is_the_replays_one_by_one_for_a_recurrent_net(per_step):
    rng = np.random.default_rng(7 + per_step)
    cfg = RecurrentNetConfig(n_inputs=D, n_hidden=5, n_context=2, lr=0.1, momentum=0.9, decay=0.9)
    one, each = RecurrentOAON(cfg, A, np.random.default_rng(2)), RecurrentOAON(cfg, A, np.random.default_rng(2))
    lessons = [x for x in _lessons(rng) if len(x)]
    picks, thresholds = _picks(rng, lessons)
    options = _with(per_step)
    kw = {"gamma": 0.9, "lam": 0.8, "temperature": 0.1, "clip": None}
    used = one.replay_q_lessons(picks, thresholds, options, **kw)
    used_each = sum(each.replay_q_lesson(x.inputs, x.actions, x.rewards, x.terminated, p_threshold=p, **kw,
                                         weights=options(x)[0], allowed=options(x)[1])
                    for x, p in zip(picks, thresholds, strict=True))
    assert used == used_each
    for name in ("w1", "w2", "d1", "d2"):
        np.testing.assert_array_equal(getattr(one, name), getattr(each, name))


def test_a_pack_holds_each_distinct_lesson_once_in_first_seen_order():
    rng = np.random.default_rng(3)
    a, b = _lessons(rng, 2)
    p = pack_lessons([b, a, b, b], _with(False), A, lambda *_: None)
    assert p.distinct == [b, a] and p.order.tolist() == [0, 1, 0, 0]
    assert p.step_start.tolist() == [0, len(b), len(b) + len(a)]
    assert p.in_start.tolist() == [0, len(b) + 1]
    np.testing.assert_array_equal(p.inputs[p.in_start[1]:p.in_start[1] + len(a) + 1], a.inputs)
    assert p.weights.shape == (0, A) and p.allowed.shape == (0, A)


def test_a_pack_refuses_lessons_with_and_without_options_and_checks_each():
    rng = np.random.default_rng(4)
    a, b = _lessons(rng, 2)
    with pytest.raises(MixedOptions, match="all have per-step weights"):
        pack_lessons([a, b], lambda x: (x.meta["weights"], None) if x is a else (None, None), A, lambda *_: None)
    seen = []
    pack_lessons([a, b, a], _with(True), A, lambda x, w, m: seen.append(x))
    assert seen == [a, b]
    bad = Lesson(np.zeros((3, D)), np.array([0, A]), np.zeros(2), terminated=True)  # action A does not exist
    with pytest.raises(ValueError, match="actions"):
        replay_q_lessons(OAON(NetConfig(D, 3), A, rng), [bad], [0.0], ReplayParams(gamma=0.9), _with(False))


def _trained(agent, rng, trials=6):
    for t in range(trials):
        agent.begin_trial(rng.normal(size=D), trial=t)
        for _ in range(int(rng.integers(2, 9))):
            a = agent.act(rng.normal(size=D))
            agent.observe(a, float(rng.normal()), rng.normal(size=D), False, False)
        agent.end_trial()
        agent.learn()
    return agent


@pytest.mark.parametrize("make", ["qcon", "recurrent", "model"])
def test_an_agents_trial_replays_give_the_same_nets_and_stream_in_one_call(make, monkeypatch):
    replay = ReplayConfig(capacity=4, lessons_per_trial=LinearSchedule(5, 5, 1), p_threshold=0.01,
                          p_threshold_oldest=0.001)

    def agent():
        if make == "qcon":
            cfg = QCONConfig(NetConfig(D, 5, lr=0.1), TemperatureSchedule.direct(0.5, 0.1, 10), lam=0.8,
                             replay=replay)
            return QCON(cfg, A, np.random.default_rng(5))
        if make == "model":
            cfg = RecurrentModelConfig(RecurrentNetConfig(n_inputs=D, n_hidden=6, n_context=3, n_outputs=D + 1),
                                       NetConfig(D + 3, 5, lr=0.1), TemperatureSchedule.direct(0.5, 0.1, 10),
                                       lam=0.8, replay=replay, model_lessons_per_trial=2)
            return RecurrentModelQ(cfg, A, np.random.default_rng(5))
        cfg = RecurrentQConfig(RecurrentNetConfig(n_inputs=D, n_hidden=4, n_context=2, lr=0.1),
                               TemperatureSchedule.direct(0.5, 0.1, 10), replay=dataclasses.replace(replay, batch=True))
        return RecurrentQ(cfg, A, np.random.default_rng(5))

    one = agent()
    assert one.replays_in_one_call()
    _trained(one, np.random.default_rng(6))
    monkeypatch.setattr(type(one), "replays_in_one_call", lambda self: False)
    each = _trained(agent(), np.random.default_rng(6))
    net_one, net_each = (one.net, each.net) if make == "recurrent" else (one.q, each.q)
    for name in ("w1", "w2", "d1", "d2"):
        np.testing.assert_array_equal(getattr(net_one, name), getattr(net_each, name))
    assert one.rng.random() == each.rng.random()  # the lesson draws came in the same order


def test_replays_with_state_grouping_stay_one_by_one():
    cfg = QCONConfig(NetConfig(D, 5), TemperatureSchedule.direct(0.5, 0.1, 10),
                     replay=ReplayConfig(capacity=4, grouping=(0.5, 2.5)))
    assert not QCON(cfg, A, np.random.default_rng(0)).replays_in_one_call()  # grouping draws from the generator


def test_a_behaviour_learner_replays_lessons_with_and_without_options_one_by_one():
    """A behaviour-level trial begun without applicability files a lesson without W: such a mix is refused by one
    call before any replay, and the agent replays one by one, as before."""
    from connrl.agents.behaviour_level import BehaviourQCON

    rng = np.random.default_rng(9)
    a, b = _lessons(rng, 2)
    del b.meta["weights"]
    cfg = QCONConfig(NetConfig(D, 5, value_range=100.0), TemperatureSchedule.direct(0.5, 0.1, 10),
                     replay=ReplayConfig(capacity=4))
    one, each = (BehaviourQCON(cfg, A, np.random.default_rng(0)) for _ in range(2))
    assert one.replays_in_one_call()
    one.replay_lessons([a, b, a], [0.1, 0.2, 0.3])
    for x, p in ((a, 0.1), (b, 0.2), (a, 0.3)):
        each.replay_lesson(x, p)
    for name in ("w1", "w2", "d1", "d2"):
        np.testing.assert_array_equal(getattr(one.q, name), getattr(each.q, name))


def test_the_one_call_refuses_options_of_the_wrong_width():
    rng = np.random.default_rng(10)
    (a,) = _lessons(rng, 1)
    net = OAON(NetConfig(D, 3), A, rng)
    with pytest.raises(ValueError, match="one column per action"):
        replay_q_lessons(net, [a], [0.0], ReplayParams(gamma=0.9), lambda x: (x.meta["weights"][:, :2], None))
    with pytest.raises(ValueError, match="thresholds"):
        RecurrentOAON(RecurrentNetConfig(n_inputs=D, n_hidden=3, n_context=2), A, rng).replay_q_lessons(
            [a], [], _with(False), gamma=0.9, lam=0.0, temperature=0.1)


@pytest.mark.parametrize("repair", ["none", "lower"])
def test_qcon_t_replays_its_experienced_lessons_in_one_call_and_its_taught_ones_after(repair, monkeypatch):
    """QCON-T (5.3.4, 5.4.3): the experienced lessons go in one call, the taught ones (with their repairs and the
    draws of the taught probability) after it, as before."""
    from connrl.agents.teaching import TeachingConfig, TeachingQCON

    replay = ReplayConfig(capacity=4, lessons_per_trial=LinearSchedule(5, 5, 1), p_threshold=0.01,
                          taught_probability=LinearSchedule(0.5, 0.5, 1))

    def agent():
        cfg = QCONConfig(NetConfig(D, 5, value_range=100.0, lr=0.1), TemperatureSchedule.direct(0.5, 0.1, 10),
                         lam=0.8, replay=replay)
        a = TeachingQCON(cfg, A, np.random.default_rng(5), teaching=TeachingConfig(repair=repair))
        a.add_taught_lessons([x for x in _lessons(np.random.default_rng(11), 3) if len(x)])
        return a

    one = agent()
    assert one.replays_in_one_call()
    _trained(one, np.random.default_rng(6))
    monkeypatch.setattr(TeachingQCON, "replays_in_one_call", lambda self: False)
    each = _trained(agent(), np.random.default_rng(6))
    for name in ("w1", "w2", "d1", "d2"):
        np.testing.assert_array_equal(getattr(one.q, name), getattr(each.q, name))
    assert one.rng.random() == each.rng.random()
