"""The Ch. 6 high-level learner: Eq. 6.6 choices (ruled-out behaviours never chosen, persistence), the weights kept
with each lesson for replay, and a run on a tiny behaviour-level world."""

import numpy as np
import pytest

from connrl.agents import LinearSchedule, QCONConfig, ReplayConfig
from connrl.agents.behaviour_level import BehaviourChoice, BehaviourQCON
from connrl.agents.memory import replay_recurrent_q
from connrl.core.exploration import TemperatureSchedule
from connrl.nets import NetConfig


def agent(persistence=False, seed=0, t=0.05, target_max="all", grouping=None):
    cfg = QCONConfig(net=NetConfig(3, 4, value_range=100.0, init_range=0.5, lr=0.05),
                     temperature=TemperatureSchedule.direct(t, t, 10), gamma=0.99, lam=0.8,
                     replay=ReplayConfig(capacity=10, lessons_per_trial=LinearSchedule(2, 2), p_threshold=0.0,
                                         p_threshold_oldest=0.02, grouping=grouping))
    return BehaviourQCON(cfg, 4, np.random.default_rng(seed),
                         BehaviourChoice(persistence=persistence, target_max=target_max))


def info(app, goal=False):
    return {"applicable": np.array(app, dtype=bool), "behaviour_goal": goal}


def test_inapplicable_behaviours_are_never_chosen():
    a = agent(t=10.0)  # nearly uniform among the allowed ones
    a.begin_trial(np.zeros(3), info([True, False, True, False]), trial=0, learning=True)
    picks = {a.act(np.zeros(3), info([True, False, True, False])) for _ in range(200)}
    assert picks == {0, 2}
    with pytest.raises(ValueError, match="applicable"):
        a.act(np.zeros(3), {})


def test_persistence_keeps_the_active_behaviour_until_its_goal_or_a_new_applicable_one():
    a = agent(persistence=True, t=10.0)  # a hot choice: without persistence the picks would spread
    x = np.zeros(3)
    a.begin_trial(x, info([False, False, True, True]), trial=0, learning=True)
    first = a.act(x, info([False, False, True, True]))
    w = a.choice.weights(info([False, False, True, True]))
    assert w[first] == 100.0 and sorted(w.tolist()) == [0.0, 0.0, 1.0, 100.0]
    assert a.choice.weights(info([False, False, True, True], goal=True)).tolist() == [0, 0, 1, 1]  # its goal
    assert a.choice.weights(info([False, True, True, True])).tolist() == [0, 1, 1, 1]  # DP came into sight
    no = agent(persistence=False)
    no.begin_trial(x, info([False, False, True, True]), trial=0, learning=True)
    no.act(x, info([False, False, True, True]))
    assert no.choice.weights(info([False, False, True, True])).tolist() == [0, 0, 1, 1]  # Exp. 2


@pytest.mark.parametrize("target_max", ["all", "applicable"])
def test_each_lesson_keeps_its_steps_weights_for_replay(monkeypatch, target_max):
    a = agent(persistence=False, target_max=target_max)
    x = np.zeros(3)
    a.begin_trial(x, info([True, True, True, True]), trial=0, learning=True)
    apps = [[False, True, True, True], [True, True, True, True], [True, False, True, False]]
    for k, app in enumerate(apps):
        b = a.act(x, info(app))
        a.observe(b, 0.0, x, False, k == 2, info(app))
    a.end_trial()
    lesson = a.book.memory.lessons[-1]
    np.testing.assert_array_equal(lesson.meta["weights"], np.array(apps, dtype=float))  # Exp. 2's W = applicability
    np.testing.assert_array_equal(lesson.meta["applicable"], [[True] * 4] + apps)  # each state's, start included
    seen = []
    monkeypatch.setattr("connrl.agents.qcon.replay_q",
                        lambda q, lesson, params, weights=None, allowed=None: seen.append((weights, allowed)))
    a.replay_lesson(lesson, 0.01)
    assert seen[0][0] is lesson.meta["weights"]  # replay's non-policy test sees them
    assert seen[0][1] is (lesson.meta["applicable"] if target_max == "applicable" else None)


def test_online_target_max_ranges_over_the_next_states_applicable_behaviours():
    """Fig. 3.4 step 4 with target_max="applicable": r + gamma * max over the applicable nets of the next state."""
    x, y = np.zeros(3), np.ones(3)
    for target_max in ("all", "applicable"):
        a = agent(target_max=target_max)
        q_y = a.q.values(y)
        app = np.array([True, False, False, False]) if q_y.argmax() != 0 else np.array([False, True, False, False])
        want = 5.0 + 0.99 * (q_y.max() if target_max == "all" else q_y[app].max())
        seen = []
        a.q.update = lambda x, b, target, seen=seen: seen.append(target)
        a.begin_trial(x, info([True] * 4), trial=0, learning=True)
        a.observe(a.act(x, info([True] * 4)), 5.0, y, False, False, info(app))
        assert seen == [pytest.approx(want)]
    with pytest.raises(ValueError, match="target_max must be one of"):
        agent(target_max="some")


def test_grouping_replays_fewer_steps_and_tallies_group_sizes():
    a = agent(grouping=(0.5, 2.5))
    x = np.zeros(3)
    a.begin_trial(x, info([True] * 4), trial=0, learning=True)
    for k in range(30):  # 30 steps of behaviour 2 in three runs of identical inputs: no group spans a jump of 10
        a.act(x, info([True] * 4))
        a.observe(2, 0.0, np.full(3, 10.0 * ((k + 1) // 10)), False, k == 29, info([True] * 4))
    a.end_trial()
    a.replay_lesson(a.book.memory.lessons[-1], 0.0)
    assert a.grouped_steps == 30 and a.groups == 3  # inputs 0 (states 0-9), 10 (10-19), 20 (20-29); 30 is final


def test_persistence_holds_a_hot_choice_and_resets_between_trials():
    x, app = np.zeros(3), [True, True, True, True]
    switches = {}
    for persistence in (False, True):
        a = agent(persistence=persistence, t=10.0, seed=3)  # T = 10 on Q/100: nearly uniform among the allowed
        a.begin_trial(x, info(app), trial=0, learning=True)
        picks = [a.act(x, info(app)) for _ in range(100)]
        switches[persistence] = sum(p != q for p, q in zip(picks[:-1], picks[1:], strict=True))
        a.begin_trial(x, info(app), trial=1, learning=True)  # a new trial forgets the active behaviour
        assert a.choice.weights(info(app)).tolist() == [1, 1, 1, 1]
    assert switches[False] > 50 and switches[True] < 10  # 100 : 1 : 1 : 1 keeps the active one ~97 % of steps


def test_greedy_choice_draws_no_random_numbers():
    a = agent()
    a.begin_trial(np.zeros(3), info([True] * 4), trial=0, learning=False)
    state = a.rng.bit_generator.state
    a.act(np.zeros(3), info([True, False, True, True]), greedy=True)
    assert a.rng.bit_generator.state == state


# ------------------------------------------------------------------- Ch. 8: recurrent-Q over behaviours (8.3)

def recurrent_agent(seed=0, t=0.05, target_max="applicable", persistence=True):
    from connrl.agents.behaviour_level import BehaviourRecurrentQ
    from connrl.agents.memory import RecurrentQConfig
    from connrl.nets.recurrent import RecurrentNetConfig
    cfg = RecurrentQConfig(net=RecurrentNetConfig(3, 5, 2, value_range=100.0, init_range=0.5, lr=0.08),
                           temperature=TemperatureSchedule.direct(t, t, 10), gamma=0.99, lam=0.8,
                           replay=ReplayConfig(capacity=10, lessons_per_trial=LinearSchedule(2, 2), p_threshold=0.0,
                                               p_threshold_oldest=0.02, batch=True))
    return BehaviourRecurrentQ(cfg, 4, np.random.default_rng(seed),
                               BehaviourChoice(persistence=persistence, target_max=target_max))


def test_recurrent_choice_reads_the_context_the_chosen_behaviours_net_made():
    a = recurrent_agent(t=10.0)
    x0, x1 = np.array([0.5, -0.5, 0.1]), np.array([-0.5, 0.5, 0.3])
    a.begin_trial(x0, info([True, True, False, True]), trial=0, learning=True)
    b = a.act(x0, info([True, True, False, True]))
    assert b != 2  # inapplicable: never chosen
    # independent reference: the trial's sequence replayed from a zero context by the same weights
    _, cs = a.net.forward_sequence(np.array([x0, x1]), np.array([b, 0]))
    np.testing.assert_allclose(a.net.context, cs[1])
    assert np.abs(cs[1]).sum() > 0


def test_recurrent_replay_uses_the_kept_weights_and_applicability():
    # W = (1, 0, 1, 1) at step 1 rules out the behaviour taken there, so Eq. 6.6 gives it probability 0 and it is not
    # replayed; applicability (only 0 at x_2) bounds the target's max. Replaying without them must differ.
    import copy

    a = recurrent_agent(target_max="applicable", persistence=False)
    xs = [np.array([0.1 * k, -0.2, 0.3]) for k in range(4)]
    apps = [[True, True, True, True], [True, True, True, True], [True, False, False, False], [True, True, True, True]]
    a.begin_trial(xs[0], info(apps[0]), trial=0, learning=True)
    for k in range(3):
        b = a.act(xs[k], info(apps[k]))
        a.observe(b, 100.0 if k == 2 else 0.0, xs[k + 1], k == 2, False, info(apps[k + 1]))
    a.end_trial()
    lesson = a.book.memory.lessons[-1]
    np.testing.assert_array_equal(lesson.meta["weights"], np.array(apps[:3], dtype=float))
    np.testing.assert_array_equal(lesson.meta["applicable"], np.array(apps))
    lesson.meta["weights"][1] = 1.0
    lesson.meta["weights"][1, lesson.actions[1]] = 0.0  # as if step 1's choice had been ruled out
    plain, kept = copy.deepcopy(a.net), copy.deepcopy(a.net)
    params = a.replay_params(0.01)
    assert replay_recurrent_q(plain, lesson, params) == 3  # without W and the mask: every step replayed
    assert replay_recurrent_q(kept, lesson, params, lesson.meta["weights"], lesson.meta["applicable"]) == 2
    a.replay_lesson(lesson, 0.01)
    np.testing.assert_allclose(a.net.w1, kept.w1)
    assert not np.allclose(a.net.w1, plain.w1)
    with pytest.raises(ValueError, match="kept with each lesson"):
        a.replay_lesson(lesson, 0.0, weights=np.ones((3, 4)))


@pytest.mark.parametrize("memory", ["none", "recurrent"])
def test_replay_from_start_replays_the_full_count_after_the_first_trial(monkeypatch, memory):
    from connrl.core.rollout import run_trial
    from connrl.experiments.integration import IntegrationParams
    from connrl.tasks.integration import make_integration_agent, make_integration_env

    for from_start in (True, False):
        p = IntegrationParams(memory=memory, max_steps=5, replay_from_start=from_start, online=memory == "none")
        agent, env = make_integration_agent(p, np.random.default_rng(0)), make_integration_env(p)
        calls: list = []
        monkeypatch.setattr(agent, "replay_lesson", lambda lesson, *a, calls=calls, **k: calls.append(lesson))
        run_trial(env, agent, trial=0, learning=True, seed=1)
        # one lesson stored: the full count drawn from it, or (5.3.5's reading) no more replays than lessons
        assert len(calls) == (p.lessons_per_trial if from_start else 1) and len({id(c) for c in calls}) == 1
