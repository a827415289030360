"""Pole balancing wiring (App. C, 7.5.4): the worlds of a parameter set and Table B.1's memoryless agents."""

from types import SimpleNamespace

import numpy as np
import pytest

from connrl.agents import AHCON, QCON
from connrl.experiments.pole import PoleParams
from connrl.experiments.spec import as_dict
from connrl.tasks.pole import make_agent, make_envs


def test_envs_follow_the_parameters():
    p = PoleParams(train_max_steps=123, test_steps=456, start_x=0.5, start_theta=0.01)
    train, test = make_envs(p, "full")
    assert (train.max_steps, train.start_x, train.start_theta) == (123, 0.5, 0.01)
    assert test.max_steps == 456 and train.observation_space.shape == (4,)
    assert make_envs(p, "x_theta")[0].observation_space.shape == (2,)


def test_agents_have_table_b1_task_4_parameters():
    q = make_agent(PoleParams(), 4, np.random.default_rng(0))
    assert isinstance(q, QCON)
    c = q.config
    assert (c.net.n_inputs, c.net.n_hidden, c.net.lr, c.net.momentum, c.gamma, c.lam) == (4, 6, 0.25, 0.9, 0.9, 0.7)
    assert c.temperature(0) == pytest.approx(1 / 20) and c.temperature(999) == pytest.approx(1 / 50)
    assert c.replay.capacity == 70 and c.replay.threshold_for_age(0) == pytest.approx(1e-4)
    assert c.replay.threshold_for_age(69) == pytest.approx(1e-7)
    a = make_agent(PoleParams(agent="ahcon", hidden=0), 4, np.random.default_rng(0))
    assert isinstance(a, AHCON) and a.config.v_net.momentum == 0.0  # perceptrons: no momentum
    with pytest.raises(ValueError, match="parameter agent must be one of 'qcon', 'ahcon', got 'sarsa'"):
        PoleParams(agent="sarsa")  # refused when the parameters are built, before any run
    loose = SimpleNamespace(**{**as_dict(PoleParams()), "agent": "sarsa"})  # builders take any attribute object
    with pytest.raises(ValueError, match="agent must be 'qcon' or 'ahcon'"):
        make_agent(loose, 4, np.random.default_rng(0))
