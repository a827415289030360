"""``Agent.predict`` in Stable-Baselines3's shape: ``(action, state)`` for one observation or a vector env's batch,
greedy by default, Eq. 3.4's draw on its own generator otherwise; memory agents keep one history; SB3's own
``evaluate_policy`` runs a connrl agent where SB3 is installed."""

import gymnasium as gym
import numpy as np
import pytest

import connrl
from connrl.core.exploration import boltzmann_probabilities

from .test_spaces import Cue


@pytest.fixture(scope="module")
def cartpole():
    return connrl.make_agent(gym.make("CartPole-v1"), "QCON-R", seed=3, warmup_steps=100, hidden=4).learn(600)


def test_one_observation_gives_a_0d_action_and_the_state_back(cartpole):
    obs = gym.make("CartPole-v1").reset(seed=0)[0]
    action, state = cartpole.predict(obs)
    assert isinstance(action, np.ndarray) and action.shape == () and state is None
    x = cartpole.scaler.encode(obs)
    assert int(action) == int(np.argmax(cartpole.learner.q.values(x)))  # greedy: the first of the largest values
    assert cartpole.predict(obs, state="kept")[1] == "kept"
    assert gym.make("CartPole-v1").action_space.contains(action)


def _greedy(agent, obs) -> int:  # the first of the largest Q-values of the net itself
    q = agent.learner.q.values(agent.scaler.encode(obs))
    return int(np.flatnonzero(q == q.max())[0])


def test_a_vector_envs_batch_is_each_observation_predicted(cartpole):
    envs = gym.vector.SyncVectorEnv([lambda: gym.make("CartPole-v1")] * 3)
    obs, _ = envs.reset(seed=5)
    for _ in range(20):
        actions, _ = cartpole.predict(obs, episode_start=np.zeros(3, bool))
        assert actions.shape == (3,) and actions.tolist() == [_greedy(cartpole, o) for o in obs]
        obs, *_ = envs.step(actions)


def test_a_batch_of_discrete_observations():
    env = gym.make("FrozenLake-v1")
    agent = connrl.make_agent(env, "QCON-R", seed=0, warmup_steps=50, hidden=4).learn(300)
    got, _ = agent.predict(np.array([0, 5, 10, 15]))
    assert got.tolist() == [_greedy(agent, s) for s in (0, 5, 10, 15)] and agent.predict(3)[0].shape == ()


def test_a_dict_batch_is_split_in_every_part():
    agent = connrl.make_agent(Cue(), "QCON-R", seed=0, warmup_steps=50, hidden=4).learn(400)
    batch = {"cue": np.array([0, 1, 1]), "noise": np.array([[0.1, 0.2], [0.0, -0.5], [0.9, 0.9]], np.float32)}
    got, _ = agent.predict(batch)
    want = [int(agent.predict({"cue": batch["cue"][i], "noise": batch["noise"][i]})[0]) for i in range(3)]
    assert got.tolist() == want
    with pytest.raises(ValueError, match="a batch of them one axis more"):
        agent.predict({"cue": np.zeros((2, 2), int), "noise": np.zeros((2, 2, 2))})


def test_a_stochastic_prediction_draws_eq_3_4_at_the_schedules_temperature(cartpole, tmp_path):
    env = gym.make("CartPole-v1")
    o = cartpole.options  # the temperature the schedule gives at the agent's step, in Q units
    t = (0.05 + (0.005 - 0.05) * min(cartpole.steps_done / o.anneal_steps, 1.0)) * cartpole.value_range
    obs = next(x for x in (env.reset(seed=s)[0] for s in range(50))
               if 0.2 < boltzmann_probabilities(cartpole.learner.q.values(cartpole.scaler.encode(x)), t)[1] < 0.8)
    p1 = boltzmann_probabilities(cartpole.learner.q.values(cartpole.scaler.encode(obs)), t)[1]
    before = cartpole.rng.bit_generator.state
    cartpole.save(tmp_path / "a")
    for agent in (cartpole, connrl.load(tmp_path / "a")):  # a loaded agent draws at the same temperature
        draws = [int(agent.predict(obs, deterministic=False)[0]) for _ in range(4000)]
        assert np.mean(draws) == pytest.approx(p1, abs=4 * np.sqrt(p1 * (1 - p1) / 4000))
    assert cartpole.rng.bit_generator.state == before  # the learner's stream never moved


def test_memory_agents_predict_one_environment_greedily():
    env = gym.make("connrl/CupCollection-v0")
    agent = connrl.make_agent(env, "window-Q", seed=1, warmup_steps=100, hidden=6).learn(300)
    obs = env.reset(seed=0)[0]
    first = agent.predict(obs, episode_start=False)[0]  # after learn(), the first call begins a history anyway
    connrl.evaluate(agent, env, 1)  # evaluate's trial replaces the history: the next call begins one
    assert agent.predict(obs, episode_start=np.array([False]))[0] == first
    with pytest.raises(ValueError, match="one history"):
        agent.predict(np.stack([obs, obs]))
    with pytest.raises(ValueError, match="greedily"):
        agent.predict(obs, deterministic=False)


def test_sb3_evaluate_policy_runs_a_connrl_agent(cartpole):
    evaluation = pytest.importorskip("stable_baselines3.common.evaluation")
    from stable_baselines3.common.vec_env import DummyVecEnv

    venv = DummyVecEnv([lambda: gym.make("CartPole-v1")])
    venv.seed(7)
    rewards, _ = evaluation.evaluate_policy(cartpole, venv, n_eval_episodes=3, return_episode_rewards=True, warn=False)
    env, ours = gym.make("CartPole-v1"), []
    obs = env.reset(seed=7)[0]  # the same episodes played by hand: seeded once, then reset as the vector env resets
    for _ in range(3):
        total, done = 0.0, False
        while not done:
            obs, r, terminated, truncated, _ = env.step(cartpole.predict(obs)[0])
            total, done = total + r, terminated or truncated
        ours.append(total)
        obs = env.reset()[0]
    assert rewards == ours
