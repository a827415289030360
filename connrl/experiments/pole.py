"""Pole balancing with memoryless agents (thesis 7.5.4, footnote 4; App. C).

Protocol: train one trial at a time (stochastic actions, learning on); after each training trial test
the greedy policy from the 7 starts of 7.5.4 (theta = 0, +-1, +-2, +-3 degrees); the policy is
satisfactory when every test start balances for more than 5000 steps. A run reports the number of
training trials until then (None if not within ``max_trials``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from connrl.core.rollout import run_trial
from connrl.experiments.protocol import train_and_test
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant
from connrl.tasks.pole import PoleParams, make_agent, make_envs, satisfactory


def train_until_satisfactory(train_env, test_env, agent, max_trials: int, test_steps: int, progress) -> RunResult:
    """The 7.5.4 protocol: a training trial, then the 7-start test, until satisfactory or ``max_trials``.

    The curve is 0 before the run's first satisfactory test and 1 from then on, so its mean over runs is the
    fraction of runs solved by each trial.
    """
    rows, last = [], {}

    def train(k):
        stats = run_trial(train_env, agent, trial=k, learning=True)
        last.update(train_steps=stats.steps, train_failed=stats.terminated)
        return stats

    def test(n):
        ok = satisfactory(test_env, agent, test_steps)
        rows.append({"trial": n, **last, "satisfactory": ok})
        return ok

    trained = train_and_test(max_trials, train, test, stop=bool, progress=progress, agent=agent)
    solved_at = trained if rows and rows[-1]["satisfactory"] else None
    progress(max_trials, max_trials)
    xs = list(range(1, max_trials + 1))
    ys = [float(solved_at is not None and x >= solved_at) for x in xs]
    return RunResult(xs, ys, {"trials_to_satisfactory": solved_at}, rows)


def run_pole(p: PoleParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    train_env, test_env = make_envs(p, p.observe)
    train_env.reset(seed=int(rng.integers(2**31)))
    agent = make_agent(p, train_env.observation_space.shape[0], rng)
    return train_until_satisfactory(train_env, test_env, agent, p.max_trials, p.test_steps, progress)


_QUANTITY = Quantity("trials_to_satisfactory", "training trials until the greedy policy balances > 5000 steps "
                     "from all 7 test starts", "lower", "7.5.4 fn. 4")
_PROFILES = {
    "tiny": {"runs": 1, "max_trials": 3, "test_steps": 200},
    "quick": {"runs": 4, "max_trials": 300},
    "full": {"runs": 10},
}

CHAPTER = 7  # 7.5.4's: Appendix C's task (`connrl reproduce --chapters`)
EXPERIMENTS = [
    ExperimentSpec(
        name="pole-full",
        title="Memoryless QCON-R on full-state pole balancing",
        section="7.5.4 fn. 4",
        run="connrl.experiments.pole:run_pole",
        params=PoleParams(),
        profiles=_PROFILES,
        variants=(Variant("QCON-R", {"agent": "qcon"}, {"trials_to_satisfactory": 119}),),
        quantities=(_QUANTITY,),
        x_label="training trials",
        y_label="fraction of runs with a satisfactory policy",
        x_reference={"thesis: 119 trials": 119},
    ),
    ExperimentSpec(
        name="pole-full-ahc",
        title="Memoryless AHCON-R on full-state pole balancing (no thesis number; compare with pole-full)",
        section="7.5.4 fn. 4, 3.3",
        run="connrl.experiments.pole:run_pole",
        params=replace(PoleParams(), p_threshold=0.2, p_threshold_oldest=None),
        profiles=_PROFILES,
        variants=(Variant("AHCON-R", {"agent": "ahcon"}),),
        quantities=(_QUANTITY,),
        x_label="training trials",
        y_label="fraction of runs with a satisfactory policy",
    ),
]
