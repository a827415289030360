"""Replay: lambda-returns by hand (incl. the worked example of Ch. 2.1), Fig. 5.1 order, App. A.2, lesson files."""

import json
import math

import numpy as np
import pytest

from connrl.core.lesson_files import LessonFileError, load_lessons, save_lessons
from connrl.core.lessons import Lesson, LessonMemory, LessonRecorder, recency_index
from connrl.core.replay import ReplayParams, replay_ahc, replay_q
from connrl.core.returns import lambda_returns, td_lambda_target
from connrl.nets import OAON, NetConfig


@pytest.mark.parametrize("lam", [0.0, 0.3, 1.0])
def test_worked_example_of_chapter_2_1(lam):
    # States A, B, C predicted 0.8, 0.3, 0.6; the game is won (outcome 1) after C. gamma = 1.
    # TD(lambda) changes of 2.1: dA = (0.3-0.8) + (0.6-0.3) lam + (1-0.6) lam^2, dB = (0.6-0.3) + (1-0.6) lam,
    # dC = 1 - 0.6.
    returns = lambda_returns([0.0, 0.0, 1.0], [0.3, 0.6, 0.0], gamma=1.0, lam=lam)
    deltas = returns - np.array([0.8, 0.3, 0.6])
    assert deltas[0] == pytest.approx(-0.5 + 0.3 * lam + 0.4 * lam**2)
    assert deltas[1] == pytest.approx(0.3 + 0.4 * lam)
    assert deltas[2] == pytest.approx(0.4)


def test_lambda_returns_by_hand():
    r, u, g = [0.0, 1.0, -1.0], [0.5, 0.2, 0.0], 0.9
    lam = 0.5
    e2 = -1.0
    e1 = 1.0 + g * ((1 - lam) * 0.2 + lam * e2)
    e0 = 0.0 + g * ((1 - lam) * 0.5 + lam * e1)
    np.testing.assert_allclose(lambda_returns(r, u, g, lam), [e0, e1, e2])
    # lambda = 1 with backward replay is the discounted return actually received (5.1)
    np.testing.assert_allclose(lambda_returns(r, u, g, 1.0), [g * 1 + g * g * -1, 1 + g * -1, -1])
    # lambda = 0 is one-step Q-learning / TD(0)
    np.testing.assert_allclose(lambda_returns(r, u, g, 0.0), [g * 0.5, 1 + g * 0.2, -1.0])


def test_lambda_is_zero_at_the_last_step_and_where_asked():
    # the last step never looks at e'_{t+1}; a per-step lambda of 0 cuts the return (non-policy next action)
    out = lambda_returns([0.0, 0.0], [0.4, 0.7], 1.0, [1.0, 1.0])
    assert out[1] == pytest.approx(0.7)
    assert out[0] == pytest.approx(0.7)
    cut = lambda_returns([0.0, 0.0], [0.4, 0.7], 1.0, [0.0, 1.0])
    assert cut[0] == pytest.approx(0.4)


def test_clip_truncates_targets():
    out = lambda_returns([0.4, 0.4, 0.4], [2.0, 2.0, 2.0], 0.9, 0.0, clip=1.0)
    assert out.max() == 1.0
    assert td_lambda_target(1.0, 2.0, 0.0, 0.5, 0.0) == 2.0


class TableQ:
    """A tabular Q-function with an exact update (lr 1) to check the order of Fig. 5.1."""

    def __init__(self, n_states, n_actions, init=0.0):
        self.n_actions = n_actions
        self.table = np.full((n_states, n_actions), init)
        self.updates = []

    def values(self, x):
        return self.table[int(x[0])].copy()

    def update(self, x, a, target):
        before = self.table[int(x[0]), a]
        self.table[int(x[0]), a] = target
        self.updates.append((int(x[0]), a, target))
        return before


def chain_lesson(n, terminated=True, final_reward=1.0):
    inputs = np.arange(n + 1, dtype=float)[:, None]
    rewards = np.zeros(n)
    rewards[-1] = final_reward
    return Lesson(inputs, np.zeros(n, dtype=int), rewards, terminated=terminated, truncated=not terminated)


def test_incremental_backward_replay_propagates_in_one_pass():
    # backward order + incremental mode: the goal reward reaches the first state in one replay (3.5)
    q = TableQ(5, 2)
    replay_q(q, chain_lesson(4), ReplayParams(gamma=0.9, lam=0.0))
    assert [u[0] for u in q.updates] == [3, 2, 1, 0]
    np.testing.assert_allclose(q.table[:4, 0], [0.9**3, 0.9**2, 0.9, 1.0])


def test_truncated_lesson_bootstraps_from_its_last_state():
    q = TableQ(4, 2)
    q.table[3] = [0.5, 0.2]
    replay_q(q, chain_lesson(3, terminated=False, final_reward=0.0), ReplayParams(gamma=0.9))
    assert q.table[2, 0] == pytest.approx(0.9 * 0.5)
    q2 = TableQ(4, 2)
    q2.table[3] = [0.5, 0.2]
    replay_q(q2, chain_lesson(3, terminated=True, final_reward=0.0), ReplayParams(gamma=0.9))
    assert q2.table[2, 0] == 0.0  # a terminal last state is worth 0


def test_non_policy_actions_are_not_replayed_and_cut_lambda():
    # state 1's action 0 is clearly worse than action 1: with a high P_t it is a non-policy action
    q = TableQ(4, 2)
    q.table[1] = [0.0, 5.0]
    lesson = chain_lesson(3)
    replay_q(q, lesson, ReplayParams(gamma=1.0, lam=1.0, temperature=1.0, p_threshold=0.2))
    assert (1, 0, pytest.approx(1.0)) not in q.updates
    assert [u[0] for u in q.updates] == [2, 0]
    # x_0's target ignores e'_1 (lambda cut) and uses max Q(x_1) = 5
    assert q.table[0, 0] == pytest.approx(5.0)


def test_batch_mode_equals_lambda_returns_of_the_frozen_values():
    q = TableQ(5, 2)
    q.table[:, 0] = [0.1, 0.2, 0.3, 0.4, 0.5]
    lesson = chain_lesson(4)
    u = np.array([0.2, 0.3, 0.4, 0.0])
    expected = lambda_returns(lesson.rewards, u, 0.9, 0.6)
    replay_q(q, lesson, ReplayParams(gamma=0.9, lam=0.6, batch=True))
    np.testing.assert_allclose(q.table[:4, 0], expected)


def test_incremental_equals_batch_when_nothing_learns():
    rng = np.random.default_rng(0)
    cfg = NetConfig(3, 4, lr=1e-12, momentum=0.0)
    inputs = rng.normal(size=(6, 3))
    lesson = Lesson(inputs, rng.integers(0, 2, 5), rng.normal(size=5), terminated=True)
    a, b = PlainQ(OAON(cfg, 2, np.random.default_rng(1))), PlainQ(OAON(cfg, 2, np.random.default_rng(1)))
    ta, tb = [], []
    a.update = lambda x, act, t, f=a.update: (ta.append(t), f(x, act, t))[1]
    b.update = lambda x, act, t, f=b.update: (tb.append(t), f(x, act, t))[1]
    replay_q(a, lesson, ReplayParams(gamma=0.9, lam=0.7))
    replay_q(b, lesson, ReplayParams(gamma=0.9, lam=0.7, batch=True))
    np.testing.assert_allclose(ta, tb, rtol=1e-9)


def test_replay_ahc_moves_v_toward_the_return_and_policy_by_the_td_error():
    rng = np.random.default_rng(0)
    v = OAON(NetConfig(1, 3, lr=0.5, momentum=0.0), 1, rng)
    pol = OAON(NetConfig(1, 3, lr=0.5, momentum=0.0), 2, rng)
    lesson = Lesson(np.array([[0.5], [-0.5]]), np.array([1]), np.array([1.0]), terminated=True)
    v0, m0, m_other = v.value([0.5], 0), pol.value([0.5], 1), pol.value([0.5], 0)
    assert replay_ahc(v, pol, lesson, ReplayParams(gamma=0.9)) == 1
    assert v.value([0.5], 0) > v0 and pol.value([0.5], 1) > m0  # return 1 beats the prediction
    assert pol.value([0.5], 0) == m_other  # OAON: the other action's net is untouched


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


def test_lesson_memory_keeps_the_latest():
    mem = LessonMemory(3)
    for i in range(5):
        mem.add(chain_lesson(1 + i))
    assert [len(x) for x in mem.lessons] == [3, 4, 5]
    age, lesson = mem.sample(np.random.default_rng(0))
    assert mem.lessons[len(mem) - 1 - age] is lesson


def test_recorder_builds_a_lesson():
    rec = LessonRecorder()
    rec.add(np.zeros(2), 1, 0.5, np.ones(2))
    rec.add(np.ones(2), 0, -1.0, 2 * np.ones(2))
    lesson = rec.finish(terminated=True, truncated=False)
    assert len(lesson) == 2 and lesson.inputs.shape == (3, 2) and lesson.terminated
    assert rec.finish(False, False) is None


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


def test_lesson_shape_is_checked():
    with pytest.raises(ValueError, match="input rows"):
        Lesson(np.zeros((3, 2)), np.zeros(3, dtype=int), np.zeros(3), terminated=True)


class PlainQ:
    """Hides the OAON type so replay_q takes its generic Python path."""

    def __init__(self, net):
        self.net, self.n_actions = net, net.n_nets

    def values(self, x):
        return self.net.values(x)

    def update(self, x, a, t):
        return self.net.update(x, a, t)


@pytest.mark.parametrize("hidden, p_threshold, clip, terminated", [(5, 0.0, None, True), (5, 0.3, 1.0, False),
                                                                    (0, 0.2, None, True)])
def test_compiled_replay_matches_the_python_loop(hidden, p_threshold, clip, terminated):
    rng = np.random.default_rng(5)
    lesson = Lesson(rng.normal(size=(31, 6)), rng.integers(0, 3, 30), rng.normal(size=30), terminated=terminated)
    params = ReplayParams(gamma=0.9, lam=0.7, temperature=0.3, p_threshold=p_threshold, clip=clip)
    cfg = NetConfig(6, hidden, lr=0.1, momentum=0.9 if hidden else 0.0, init_range=0.5)
    fast, slow = OAON(cfg, 3, np.random.default_rng(1)), OAON(cfg, 3, np.random.default_rng(1))
    n_fast = replay_q(fast, lesson, params)
    n_slow = replay_q(PlainQ(slow), lesson, params)
    assert n_fast == n_slow
    np.testing.assert_allclose(fast.w2, slow.w2, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(fast.w1, slow.w1, rtol=1e-9, atol=1e-12)
