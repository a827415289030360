"""Ch. 4 experiments: the specs, and every one runs on the tiny profile, reproducibly."""

import json

import pytest

from connrl.experiments.survival import EXPERIMENTS
from tests.tiny_runs import run_tiny

NAMES = [s.name for s in EXPERIMENTS]


def test_nine_experiments_cover_chapter_4():
    assert NAMES == ["survival-study1", "survival-study2", "survival-study1-fresh", "survival-study2-fresh",
                     "survival-planning", "survival-speedup", "survival-eval", "survival-tuning", "survival-food"]
    s1, s2 = EXPERIMENTS[0], EXPERIMENTS[1]
    for study, fresh in ((s1, EXPERIMENTS[2]), (s2, EXPERIMENTS[3])):  # the check reruns a study, only on new seeds
        assert (fresh.params, fresh.variants, fresh.seed, study.seed) == (study.params, study.variants, 2000, 0)
    assert len(s1.variants) == len(s2.variants) == 10  # 8 frameworks, -M with both models
    assert s1.params.representation == "global" and s2.params.representation == "local"
    assert s2.params.lr_scale == 2.0 and s1.params.lr_scale == 1.0
    full = s1.resolve("full")[0]
    assert (full.train_plays, full.test_envs, full.test_every, s1.resolve("full")[1]) == (300, 50, 20, 7)
    assert {s.name: s for s in EXPERIMENTS}["survival-eval"].resolve("full")[0].eval_envs == 8000


@pytest.fixture
def tiny_out(tiny_runs):
    return tiny_runs(*NAMES)


def test_tiny_runs_write_summaries(tiny_out):
    for name in NAMES:
        summary = json.loads((tiny_out / name / "summary.json").read_text())
        assert summary["profile"] == "tiny"
        assert (tiny_out / name / "curve.png").exists()
    s = json.loads((tiny_out / "survival-study1" / "summary.json").read_text())
    q = s["variants"]["QCON-T"]["quantities"]["final_food"]
    assert len(q["per_run"]) == 1 and 0 <= q["mean"] <= 15
    ev = json.loads((tiny_out / "survival-eval" / "summary.json").read_text())["variants"]["QCON-T"]["quantities"]
    assert ev["eval_food"]["thesis"] == 12.1


def test_tiny_runs_are_reproducible(tiny_out, tmp_path):
    run_tiny("survival-speedup", tmp_path)
    a = json.loads((tiny_out / "survival-speedup" / "summary.json").read_text())["variants"]
    b = json.loads((tmp_path / "survival-speedup" / "summary.json").read_text())["variants"]
    assert a == b


def test_the_tuning_experiments_default_thresholds_are_study_1s_runs():
    """Recorded before survival-tuning existed: Study 1's tiny AHCON-R and QCON-R runs (P_t 0.2 and 0.01, 4.2.7)."""
    import json
    from pathlib import Path
    golden = json.loads((Path(__file__).parents[1] / "data" / "tiny_e172482.json").read_text())
    tuning, study1 = golden["survival-tuning"]["per_run"], golden["survival-study1"]["per_run"]
    for label, agent in (("AHCON-R P_t=0.2", "AHCON-R"), ("QCON-R P_t=0.01", "QCON-R")):
        assert tuning[label]["final_food"] == study1[agent]["final_food"]


def test_the_tuning_threshold_reaches_replay():
    import numpy as np

    from connrl.envs.survival import SurvivalEnv
    from connrl.experiments.survival import SurvivalParams, _agent_params
    from connrl.tasks.survival import make_survival_agent
    for fw, pt, expected in (("AHCON-R", 0.4, 0.4), ("QCON-R", 0.0, 0.0), ("AHCON-R", None, 0.2),
                             ("QCON-R", None, 0.01)):  # None: 4.2.7's value for the framework
        agent = make_survival_agent(_agent_params(SurvivalParams(framework=fw, p_threshold=pt)),
                                    SurvivalEnv("global"), np.random.default_rng(0))
        assert agent.config.replay.p_threshold == expected


def test_the_food_reward_experiments_04_is_study_1s_ahcon_and_the_wrapper_maps_only_food():
    import json
    from pathlib import Path

    import gymnasium as gym

    from connrl.tasks.survival import FoodReward
    golden = json.loads((Path(__file__).parents[1] / "data" / "tiny_e172482.json").read_text())
    assert golden["survival-food"]["per_run"]["food reward 0.4"]["final_food"] == \
        golden["survival-study1"]["per_run"]["AHCON"]["final_food"]

    class Fixed(gym.Env):  # hands out the world's three rewards in turn
        observation_space, action_space = gym.spaces.Discrete(1), gym.spaces.Discrete(1)

        def reset(self, *, seed=None, options=None):
            self.k = 0
            return 0, {}

        def step(self, a):
            self.k += 1
            return 0, [0.4, 0.0, -1.0][self.k - 1], self.k == 3, False, {}

    env = FoodReward(Fixed(), 0.8)
    env.reset()
    assert [env.step(0)[1] for _ in range(3)] == [0.8, 0.0, -1.0]


def test_the_new_parameters_at_their_defaults_run_exactly_as_study_1():
    import numpy as np

    from connrl.experiments.survival import SurvivalParams, run_survival
    small = {"train_plays": 6, "test_envs": 3, "test_every": 2}

    def rows(p):
        return run_survival(p, np.random.default_rng(0)).rows
    assert rows(SurvivalParams(framework="AHCON-R", p_threshold=0.2, **small)) == \
        rows(SurvivalParams(framework="AHCON-R", **small))
    assert rows(SurvivalParams(framework="AHCON", food_reward=0.4, **small)) == \
        rows(SurvivalParams(framework="AHCON", **small))
    assert rows(SurvivalParams(framework="QCON-R", p_threshold=0.0, **small)) != \
        rows(SurvivalParams(framework="QCON-R", **small))  # the threshold reaches the runs


def test_a_food_reward_for_a_model_or_taught_agent_is_refused():
    import pytest

    from connrl.experiments.spec import check_combination
    from connrl.experiments.survival import SurvivalParams
    with pytest.raises(ValueError, match="food_reward applies to agents without a model or taught lessons"):
        check_combination(SurvivalParams(framework="AHCON-T", food_reward=0.8))
