"""The averaged greedy policy (``average_steps``, connrl.own.averaging): the moving average's arithmetic by hand, the
greedy policy reading it while learning keeps the live weights, and agent files keeping it."""

import hashlib
import json
import math

import gymnasium as gym
import numpy as np
import pytest

import connrl
from connrl.nets import OAON, NetConfig
from connrl.own.averaging import PREFIX, WeightAverage
from connrl.storage import npz_arrays, npz_bytes


def test_the_average_moves_by_one_minus_exp_of_the_trials_steps_over_the_horizon():
    net = OAON(NetConfig(2, 3, value_range=1.0), 2, np.random.default_rng(0))
    w0 = {k: net.state_dict()[k] for k in ("w1", "w2")}
    avg = WeightAverage(net, steps=100)
    w1 = {k: w0[k] + 1.0 for k in w0}  # the live weights after a trial of 50 steps
    net.load_state_dict({**net.state_dict(), **w1})
    avg.update(50)
    a = 1 - math.exp(-0.5)
    for k in w0:  # hand: w0 + a (w1 - w0), then a 200-step trial towards w2
        np.testing.assert_allclose(avg.arrays[k], w0[k] + a, rtol=0, atol=1e-15)
    w2 = {k: w0[k] - 2.0 for k in w0}
    net.load_state_dict({**net.state_dict(), **w2})
    avg.update(200)
    b = 1 - math.exp(-2.0)
    for k in w0:
        np.testing.assert_allclose(avg.arrays[k], (w0[k] + a) + b * (w2[k] - (w0[k] + a)), rtol=0, atol=1e-14)
    assert set(avg.state()) == {PREFIX + "w1", PREFIX + "w2"}  # momentum is not averaged


def test_acting_holds_the_average_and_gives_the_live_weights_back_even_after_an_error():
    net = OAON(NetConfig(2, 3, value_range=1.0), 2, np.random.default_rng(1))
    avg = WeightAverage(net, steps=10)
    avg.arrays["w2"][...] = 0.0  # every output 0 under the average
    live = net.state_dict()
    with avg.acting():
        assert net.values(np.array([0.3, -0.2])).tolist() == [0.0, 0.0]
    with pytest.raises(RuntimeError), avg.acting():
        raise RuntimeError
    for k, a in net.state_dict().items():
        assert np.array_equal(a, live[k])


@pytest.fixture(scope="module")
def averaged():
    return connrl.make_agent(gym.make("CartPole-v1"), "QCON-R", seed=4, warmup_steps=100, hidden=4,
                             average_steps=300).learn(1500)


def _as_plain(agent):
    """An agent without averaging whose live weights are ``agent``'s average: the independent reference."""
    plain = connrl.make_agent(gym.make("CartPole-v1"), "QCON-R", seed=4, warmup_steps=100, hidden=4,
                              value_range=agent.value_range)
    state = agent.nets.state_dict()
    state.update({k[len(PREFIX):]: a for k, a in agent.average.state().items()})
    plain.nets.load_state_dict(state)
    plain.scaler = agent.scaler
    return plain


def test_evaluate_and_predict_act_with_the_average_and_learning_keeps_its_live_weights(averaged):
    live = averaged.nets.state_dict()
    plain = _as_plain(averaged)
    env = gym.make("CartPole-v1")
    assert averaged.evaluate(env, 3, seed=7) == plain.evaluate(env, 3, seed=7)
    obs, seen = env.reset(seed=7)[0], []  # states along the averaged policy's own episode
    for _ in range(60):
        seen.append(obs)
        obs, _, terminated, truncated, _ = env.step(int(plain.predict(obs)[0]))
        if terminated or truncated:
            obs = env.reset()[0]
    x = [averaged.scaler.encode(o) for o in seen]
    live_choice = [int(np.argmax(averaged.learner.q.values(v))) for v in x]  # outside greedy_weights: live
    assert [int(averaged.predict(o)[0]) for o in seen] == [int(plain.predict(o)[0]) for o in seen] != live_choice
    for k, a in averaged.nets.state_dict().items():
        assert np.array_equal(a, live[k])  # nothing learnt or swapped for good


def test_a_saved_agent_keeps_its_average_and_a_file_without_it_is_refused_in_one_line(averaged, tmp_path):
    averaged.save(tmp_path / "a")
    back = connrl.load(tmp_path / "a", gym.make("CartPole-v1"))
    for k, a in averaged.average.arrays.items():
        assert np.array_equal(back.average.arrays[k], a)
    npz = tmp_path / "a" / "agent.npz"  # one of the average's arrays taken out, the digest made to match
    arrays = {k: a for k, a in npz_arrays(npz.read_bytes(), npz, "test").items() if k != PREFIX + "w2"}
    npz.write_bytes(npz_bytes(**arrays))
    m = json.loads((tmp_path / "a" / "agent.json").read_text())
    m["npz_sha256"] = hashlib.sha256(npz.read_bytes()).hexdigest()
    (tmp_path / "a" / "agent.json").write_text(json.dumps(m))
    with pytest.raises(ValueError, match="agent.npz: has no array 'average.w2'"):
        connrl.load(tmp_path / "a")


@pytest.mark.parametrize("bad", [0, -5, 2.5, True, "none"])
def test_average_steps_is_a_whole_number_of_steps_or_none(bad):
    with pytest.raises(ValueError, match=r"option average_steps must be a whole number from 1 to .* or None"):
        connrl.make_agent(gym.make("CartPole-v1"), average_steps=bad)


def test_a_growing_value_range_rescales_the_average_as_the_live_nets():
    agent = connrl.make_agent(gym.make("CartPole-v1"), "QCON-R", seed=2, warmup_steps=50, hidden=4,
                              average_steps=100)
    assert agent.range_set
    x = agent.scaler.encode(gym.make("CartPole-v1").reset(seed=0)[0])
    with agent.greedy_weights():
        before = agent.learner.q.values(x)
    agent._check_range((10.0, 0.0))  # a reward of 10 a step: the range grows from 100 to 1000, Q kept
    assert agent.value_range == pytest.approx(1000.0)
    for k, a in agent.average.arrays.items():  # the average began as the weights and stays them
        assert np.array_equal(a, agent.nets.state_dict()[k])
    with agent.greedy_weights():
        assert np.allclose(agent.learner.q.values(x), before, rtol=0.05)
