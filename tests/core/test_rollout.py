"""One trial of the agent protocol (``run_trial``): the order of the agent's calls in training and test trials,
terminated vs truncated, the step cap of tests."""

from connrl.core.rollout import TrialStats, run_trial


class Corridor:
    """Walk right to cell ``goal`` (reward 1, terminated); a time limit of ``limit`` steps truncates."""

    def __init__(self, goal=3, limit=None):
        self.goal, self.limit = goal, limit
        self.resets = []

    def reset(self, *, seed=None, options=None):
        self.resets.append((seed, options))
        self.pos, self.t = 0, 0
        return self.pos, {"pos": self.pos}

    def step(self, a):
        self.pos += 1 if a == 1 else 0
        self.t += 1
        terminated = self.pos == self.goal
        truncated = not terminated and self.limit is not None and self.t >= self.limit
        return self.pos, float(terminated), terminated, truncated, {"pos": self.pos}


class Recorder:
    def __init__(self, action=1):
        self.action, self.log = action, []

    def begin_trial(self, obs, info=None, *, trial=0, learning=True):
        self.log.append(("begin", obs, trial, learning))

    def act(self, obs, info=None, *, greedy=False):
        self.log.append(("act", obs, greedy))
        return self.action

    def observe(self, a, r, next_obs, terminated, truncated, info=None):
        self.log.append(("observe", a, r, next_obs, terminated, truncated))

    def end_trial(self):
        self.log.append(("end",))

    def learn(self):
        self.log.append(("learn",))


def test_a_training_trial_observes_every_step_then_learns():
    env, agent = Corridor(goal=2), Recorder()
    seen = []
    stats = run_trial(env, agent, trial=7, learning=True, seed=11, options={"x": 1}, on_step=seen.append)
    assert env.resets == [(11, {"x": 1})]
    assert agent.log == [("begin", 0, 7, True),
                         ("act", 0, False), ("observe", 1, 0.0, 1, False, False),
                         ("act", 1, False), ("observe", 1, 1.0, 2, True, False),
                         ("end",), ("learn",)]
    assert stats == TrialStats(steps=2, total_reward=1.0, terminated=True, truncated=False, info={"pos": 2})
    assert seen == [{"pos": 1}, {"pos": 2}]


def test_a_test_trial_is_greedy_and_learns_nothing():
    agent = Recorder()
    stats = run_trial(Corridor(goal=2), agent, trial=0, learning=False)
    assert agent.log == [("begin", 0, 0, False), ("act", 0, True), ("act", 1, True), ("end",)]
    assert (stats.steps, stats.terminated, stats.truncated) == (2, True, False)


def test_a_timeout_is_a_truncation_not_a_failure():
    agent = Recorder(action=0)  # never moves
    stats = run_trial(Corridor(goal=2, limit=4), agent, trial=0, learning=True)
    assert (stats.steps, stats.total_reward, stats.terminated, stats.truncated) == (4, 0.0, False, True)
    assert agent.log[-3] == ("observe", 0, 0.0, 0, False, True) and agent.log[-2:] == [("end",), ("learn",)]


def test_max_steps_cuts_a_trial_as_truncated():
    agent = Recorder(action=0)
    stats = run_trial(Corridor(goal=2), agent, trial=0, learning=False, max_steps=5)
    assert (stats.steps, stats.terminated, stats.truncated) == (5, False, True)
    assert sum(e[0] == "act" for e in agent.log) == 5
