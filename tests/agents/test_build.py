"""``connrl.agents.build.make_learner``, the one QCON / AHCON builder of the thesis's wiring and the own-task API: the
learner its arguments describe, with the weights the direct construction draws from the same generator."""

import numpy as np

from connrl.agents import AHCON, QCON, AHCONConfig, LinearSchedule, QCONConfig, ReplayConfig
from connrl.agents.build import make_learner
from connrl.core.exploration import TemperatureSchedule
from connrl.nets import NetConfig


def test_make_learner_is_the_direct_construction():
    net = NetConfig(5, 4, value_range=1.0, init_range=0.5, lr=0.2, momentum=0.9)
    temp = TemperatureSchedule.inverse(20.0, 50.0, 100)
    replay = ReplayConfig(capacity=70, lessons_per_trial=LinearSchedule(70, 70), p_threshold=1e-4)
    q = make_learner(False, net, 2, np.random.default_rng(1), temperature=temp, gamma=0.9, lam=0.7, replay=replay,
                     online=False)
    want = QCON(QCONConfig(net=net, temperature=temp, gamma=0.9, lam=0.7, online=False, replay=replay), 2,
                np.random.default_rng(1))
    assert type(q) is QCON and q.config == want.config
    np.testing.assert_array_equal(q.q.w1, want.q.w1)
    a = make_learner(True, net, 3, np.random.default_rng(2), temperature=temp, gamma=0.95, lam=0.0, replay=None)
    want = AHCON(AHCONConfig(v_net=net, policy_net=net, temperature=temp, gamma=0.95, lam=0.0, replay=None), 3,
                 np.random.default_rng(2))
    assert type(a) is AHCON and a.config == want.config and a.config.online
    np.testing.assert_array_equal(a.policy.w2, want.policy.w2)
    np.testing.assert_array_equal(a.v.w2, want.v.w2)
