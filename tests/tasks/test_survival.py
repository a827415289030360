"""The eight Ch. 4 agents: Table 4.1 wiring, options per framework, action symmetry, stuck detection,
taught-lesson files, determinism."""

import json

import numpy as np
import pytest

from connrl.agents import AHCON, QCON
from connrl.core.exploration import StuckConfig, TemperatureSchedule
from connrl.core.lesson_files import LessonFileError
from connrl.core.rollout import run_trial
from connrl.envs.survival import SurvivalEnv, rotate_observation
from connrl.nets.rotated import RotatedNet
from connrl.tasks.survival import (
    FRAMEWORKS,
    SurvivalAgentParams,
    SurvivalExploration,
    load_survival_lessons,
    make_survival_agent,
    taught_lessons,
)
from connrl.tasks.survival_models import LearnedSurvivalModel, PerfectSurvivalModel


def agent_for(framework, rep="global", model="learned", lr_scale=1.0, seed=0, **more):
    env = SurvivalEnv(rep)
    env.reset(seed=seed)
    return make_survival_agent(SurvivalAgentParams(framework, rep, model, lr_scale, **more), env,
                               np.random.default_rng(seed)), env


@pytest.mark.parametrize("framework", FRAMEWORKS)
def test_table_4_1_and_framework_options(framework):
    agent, _ = agent_for(framework)
    base, _, ext = framework.partition("-")
    assert isinstance(agent, QCON if base == "QCON" else AHCON)
    if base == "QCON":
        assert agent.q.lr == (0.3 if framework == "QCON" else 0.15)
        t0, t_end = agent.explore.schedule(0), agent.explore.schedule(299)
        assert t0 == pytest.approx(1 / 20) and t_end == pytest.approx(1 / 60)
    else:
        assert (agent.v.lr, agent.policy.lr) == ((0.2, 0.4) if framework == "AHCON" else (0.1, 0.2))
        assert agent.explore.schedule(0) == pytest.approx(1 / 2) and agent.explore.schedule(299) == pytest.approx(0.1)
    r = agent.config.replay
    assert (r is not None) == (ext in ("R", "T"))
    if r is not None:
        assert r.capacity == 100 and r.p_threshold == (0.01 if base == "QCON" else 0.2)
        assert r.lessons_per_trial(0) == 12 and r.lessons_per_trial(299) == 4
        assert r.taught_probability(0) == 0.5 and r.taught_probability(299) == pytest.approx(0.1)
        assert r.taught_p_threshold == 0.0
    assert len(agent.book.taught) == (2 if ext == "T" else 0)
    assert (agent.planner is not None) == (ext == "M")
    if ext == "M":
        assert isinstance(agent.planner.model, LearnedSurvivalModel)
        assert agent.planner.config.start_trial == 10 and agent.planner.config.promising == 0.02
    assert agent.config.target_clip == 1.0 and agent.config.gamma == 0.9


def test_study2_doubles_learning_rates_and_uses_one_net_per_action():
    agent, _ = agent_for("AHCON-R", "local", lr_scale=2.0)
    assert (agent.v.lr, agent.policy.lr) == (0.2, 0.4)
    assert agent.policy.n_nets == 4 and not isinstance(agent.policy, RotatedNet)
    q, _ = agent_for("QCON-M", "local", model="perfect", lr_scale=2.0)
    assert q.q.lr == 0.3 and q.q.n_nets == 4
    assert isinstance(q.planner.model, PerfectSurvivalModel) and q.planner.config.start_trial == 0


def test_global_agents_use_one_rotated_net_and_respect_action_symmetry():
    agent, env = agent_for("QCON")
    assert isinstance(agent.q, RotatedNet)
    x, _ = env.reset(seed=4)
    # rotating the world a quarter turn counter-clockwise turns "move east" into "move north", etc.
    np.testing.assert_allclose(agent.q.values(rotate_observation(x, 1)), np.roll(agent.q.values(x), -1), atol=1e-12)
    ahc, _ = agent_for("AHCON")
    assert isinstance(ahc.policy, RotatedNet) and ahc.v.n_nets == 1


def test_global_agents_without_symmetry_have_one_net_per_action():
    agent, env = agent_for("QCON", symmetry=False)
    assert agent.q.n_nets == 4 and not isinstance(agent.q, RotatedNet)
    x, _ = env.reset(seed=4)  # four independent nets: a quarter turn of the world no longer permutes the values
    assert not np.allclose(agent.q.values(rotate_observation(x, 1)), np.roll(agent.q.values(x), -1), atol=1e-6)


def test_ahcon_without_symmetry_has_four_policy_nets_and_one_v_net():
    agent, _ = agent_for("AHCON", symmetry=False)
    assert agent.policy.n_nets == 4 and not isinstance(agent.policy, RotatedNet) and agent.v.n_nets == 1


@pytest.mark.parametrize("bad", [{"symmetry": "no"}, {"symmetry": False, "representation": "local"}])
def test_symmetry_must_be_a_bool_and_global(bad):
    with pytest.raises(ValueError, match="symmetry"):
        SurvivalAgentParams(**{"framework": "QCON", **bad})


def test_stuck_detection_raises_t_until_food_is_eaten():
    exp = SurvivalExploration(TemperatureSchedule.inverse(20, 20, 1), StuckConfig(window=4, radius=1.0, boost=5))
    exp.begin(0)
    ts = [exp.temperature({"position": p, "food_eaten": 0}) for p in [(5, 5), (5, 6), (5, 5), (5, 6)]]
    assert ts[:3] == [0.05] * 3 and ts[3] == pytest.approx(0.25)
    assert exp.temperature({"position": (5, 5), "food_eaten": 1}) == 0.05  # eating clears the history
    far = [exp.temperature({"position": (5, c), "food_eaten": 1}) for c in range(6, 12)]
    assert far[-1] == 0.05  # moving on: not stuck


@pytest.mark.parametrize("rep", ["global", "local"])
def test_shipped_taught_lessons_are_complete_plays(rep):
    lessons = taught_lessons(rep)
    assert len(lessons) == 2
    for lesson in lessons:
        assert lesson.taught and lesson.terminated and lesson.inputs.shape[1] == 145
        assert lesson.meta["outcome"] == "all_food" and lesson.meta["action_representation"] == rep
        assert np.isclose(lesson.rewards, 0.4).sum() == 15  # all 15 pieces eaten


def test_mismatched_or_malformed_survival_lesson_files_are_rejected(tmp_path):
    from importlib import resources

    src = resources.files("connrl") / "data" / "lessons" / "survival-global.json"
    with pytest.raises(LessonFileError, match="action_representation='global'.*'local'"):
        load_survival_lessons(src, "local")
    doc = json.loads(src.read_text())
    wrong = tmp_path / "pole.json"
    wrong.write_text(json.dumps({**doc, "env_id": "connrl/PoleBalancing-v0"}))
    with pytest.raises(LessonFileError, match="recorded on 'connrl/PoleBalancing-v0'"):
        load_survival_lessons(wrong, "global")
    short = tmp_path / "short.json"
    doc["lessons"][0]["inputs"] = [row[:100] for row in doc["lessons"][0]["inputs"]]
    short.write_text(json.dumps(doc))
    with pytest.raises(LessonFileError, match="100 inputs, the agent expects 145"):
        load_survival_lessons(short, "global")
    broken = tmp_path / "broken.json"
    broken.write_text('{"format": "connrl-lesson", "version": 1, "lessons": [{"inputs": [[0.5]]}]}')
    with pytest.raises(LessonFileError, match="malformed"):
        load_survival_lessons(broken, "global")


@pytest.mark.parametrize("framework,model", [("QCON-T", "learned"), ("AHCON-M", "perfect"), ("QCON-M", "learned")])
def test_same_seed_same_numbers(framework, model):
    def play():
        agent, env = agent_for(framework, "local", model=model, seed=3)
        agent_trial = [run_trial(env, agent, trial=k + 10, learning=True, options={"layout_seed": k}).steps
                       for k in range(2)]
        test = run_trial(env, agent, trial=0, learning=False, seed=9, options={"layout_seed": 9})
        return agent_trial, test.steps, test.info["food_eaten"], agent.v.values(np.zeros(145)).tolist() \
            if hasattr(agent, "v") else agent.q.values(np.zeros(145)).tolist()

    assert play() == play()


def test_ahcon_test_plays_act_on_the_current_observation():
    agent, env = agent_for("AHCON", "local")
    obs, info = env.reset(seed=0)
    agent.begin_trial(obs, info, learning=False)
    agent.act(obs, info, greedy=True)
    obs2, *_ = env.step(0)
    agent.act(obs2, info, greedy=True)
    np.testing.assert_array_equal(agent._x, obs2)
