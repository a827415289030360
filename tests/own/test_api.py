"""The own-task API (connrl.own.api): input and value scales by hand, refusals in one line, save -> load -> evaluate
identical, determinism, and a short CartPole smoke run."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import connrl
from connrl.own.api import InputScaler, make_agent


class Toy(gym.Env):
    """Two actions; reward 2 for action 1, -1 for action 0; 5 steps; observation [t, t^2] unbounded."""

    observation_space = spaces.Box(-np.inf, np.inf, (2,), np.float64)
    action_space = spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return np.array([0.0, 0.0]), {}

    def step(self, a):
        self.t += 1
        return np.array([self.t, self.t ** 2], float), 2.0 if a == 1 else -1.0, False, self.t >= 5, {}


def test_input_scales_by_hand():
    box = spaces.Box(np.array([-2.0, -np.inf]), np.array([2.0, np.inf]), dtype=np.float64)
    s = InputScaler.fit(box, np.array([[0.0, 1.0], [1.0, 3.0]]))  # second unit: mean 2, std 1 -> scale 2
    np.testing.assert_allclose(s.encode([2.0, 4.0]), [1.0, 1.0])
    np.testing.assert_allclose(s.encode([-1.0, 0.0]), [-0.5, -1.0])
    d = InputScaler.fit(spaces.Discrete(3), np.zeros((1, 1)))
    assert d.encode(2).tolist() == [-0.5, -0.5, 0.5]
    assert InputScaler.from_json(s.to_json()).encode([0.5, 2.0]).tolist() == s.encode([0.5, 2.0]).tolist()


def test_value_range_follows_the_reward_scale_and_gamma():
    agent = make_agent(Toy(), "QCON", seed=0, warmup_steps=50, gamma=0.9)
    assert agent.value_range == pytest.approx(2.0 / 0.1)  # max |reward| / (1 - gamma)
    assert agent.temperature(0) == pytest.approx(0.05 * agent.value_range)  # T acts on Q / value_range
    assert make_agent(Toy(), value_range=7.0).value_range == 7.0


@pytest.mark.parametrize("call, message", [
    (lambda: make_agent(Toy(), "DQN"), "unknown agent 'DQN'; available: QCON, QCON-R"),
    (lambda: make_agent(Toy(), learning_rate=0.1), "unknown option(s) 'learning_rate'; allowed: hidden"),
    (lambda: make_agent(Toy(), gamma=2), "option gamma must be in [0, 1], got 2"),
    (lambda: make_agent(gym.make("Pendulum-v1")), "connrl agents need a Discrete action space"),
    (lambda: make_agent(Toy()).learn(0), "total_steps must be a whole number >= 1"),
    (lambda: make_agent(Toy(), shared_hidden="yes"), "option shared_hidden must be true or false, got 'yes'"),
    (lambda: make_agent(Toy(), shared_hidden=True, hidden=0), "option shared_hidden needs hidden units"),
    (lambda: make_agent(Toy(), "recurrent-Q", shared_hidden=True), "option shared_hidden is for the feed-forward"),
])
def test_bad_input_is_one_clear_line(call, message):
    with pytest.raises(ValueError) as exc:
        call()
    assert message in str(exc.value) and "\n" not in str(exc.value)


def test_learning_is_deterministic_and_save_load_evaluate_gives_the_same_returns(tmp_path):
    a = make_agent(Toy(), "QCON-R", seed=3, warmup_steps=20).learn(200)
    b = make_agent(Toy(), "QCON-R", seed=3, warmup_steps=20).learn(200)
    np.testing.assert_array_equal(a.learner.q.w1, b.learner.q.w1)
    assert connrl.evaluate(a, Toy(), episodes=2) == [10.0, 10.0]  # it has learnt action 1 everywhere
    a.save(tmp_path / "agent")
    c = connrl.load(tmp_path / "agent", Toy())
    assert connrl.evaluate(c, Toy(), 3, seed=5) == connrl.evaluate(a, Toy(), 3, seed=5)
    assert (c.steps_done, c.kind, c.value_range) == (a.steps_done, "QCON-R", a.value_range)
    c.learn(20)  # a loaded agent trains on in the environment it was loaded with


def test_a_file_for_another_environment_or_format_is_refused(tmp_path):
    make_agent(Toy(), "QCON", warmup_steps=10).save(tmp_path / "agent")
    with pytest.raises(ValueError, match="this agent was made for another environment with observation_space"):
        connrl.load(tmp_path / "agent", gym.make("CartPole-v1"))
    meta = tmp_path / "agent" / "agent.json"
    meta.write_text(meta.read_text().replace('"format": 1', '"format": 99'))
    with pytest.raises(ValueError, match="agent file format 99; this connrl reads format 1"):
        connrl.load(tmp_path / "agent")
    with pytest.raises(ValueError, match="no such connrl agent file"):
        connrl.load(tmp_path / "nowhere")


def test_cartpole_smoke():
    env = gym.make("CartPole-v1")
    agent = connrl.make_agent(env, "QCON-R", seed=0).learn(2000)
    assert agent.steps_done >= 2000 and agent.trials_done > 10
    assert all(r >= 8 for r in connrl.evaluate(agent, env, 2))


def test_cli_train_then_evaluate(tmp_path, capsys):
    from connrl import cli
    assert cli.main(["train", "CartPole-v1", "--steps", "300", "--save", str(tmp_path / "a"), "--quiet",
                     "--option", "hidden=4"]) == 0
    assert {p.name for p in (tmp_path / "a").iterdir()} == {"agent.json", "agent.npz", "curve.png", "progress.csv",
                                                              "monitor.csv", "settings.json", ".connrl-run.lock"}
    assert cli.main(["evaluate", str(tmp_path / "a"), "--episodes", "2"]) == 0
    out = capsys.readouterr().out
    assert "CartPole-v1: greedy return over 2 episodes" in out and "QCON-R, trained 300 steps" in out


@pytest.mark.parametrize("args, message", [
    (["train", "Nope-v9", "--steps", "10"], "cannot make environment 'Nope-v9'"),
    (["train", "CartPole-v1", "--steps", "10", "--option", "lr2=1"], "unknown option(s) 'lr2'"),
    (["evaluate", "nowhere"], "nowhere/agent.json: no such connrl agent file"),
])
def test_cli_refuses_bad_input_in_one_line(args, message, tmp_path):
    from connrl import cli
    with pytest.raises(SystemExit) as exc:
        cli.main(args + (["--save", str(tmp_path / "x")] if args[0] == "train" else []))
    assert message in str(exc.value)


def test_the_readme_snippets_run(tmp_path, monkeypatch):
    from pathlib import Path
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    section = readme[readme.index("## Using the techniques on your own task"):readme.index("## Layout")]
    blocks = [b.split("```", 1)[0] for b in section.split("```python\n")[1:]]
    assert len(blocks) == 2 and "connrl.make_agent" in blocks[0] and "connrl.load" in blocks[0]
    assert "record_lessons" in blocks[1] and "QCON-T" in blocks[1]
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for code in blocks:  # the second uses the first's env
        exec(compile(code.replace("50_000", "300").replace("10_000", "300"), "README", "exec"), namespace)
    assert (tmp_path / "cartpole-agent" / "agent.npz").exists() and (tmp_path / "teacher.json").exists()
    assert namespace["agent"].kind == "QCON-T" and len(namespace["agent"].learner.book.taught) == 3


@pytest.mark.parametrize("kind", ["window-Q", "recurrent-Q"])
def test_memory_agents_learn_save_load_and_evaluate_on_a_hidden_state_task(kind, tmp_path):
    env = gym.make("connrl/CupCollection-v0")  # Ch. 7's task: the sensation does not tell the two instances apart
    agent = connrl.make_agent(env, kind, seed=1, warmup_steps=100, hidden=6, context=4).learn(400)
    assert agent.steps_done >= 400
    agent.save(tmp_path / kind)
    again = connrl.load(tmp_path / kind, env)
    assert connrl.evaluate(again, env, 3, seed=2) == connrl.evaluate(agent, env, 3, seed=2)
    obs, start, total = env.reset(seed=2)[0], True, 0.0  # predict keeps the history evaluate's trial keeps
    while True:
        a, _ = agent.predict(obs, episode_start=start)
        obs, r, terminated, truncated, _ = env.step(a)
        start, total = False, total + r
        if terminated or truncated:
            break
    assert total == connrl.evaluate(agent, env, 1, seed=2)[0]


def test_evaluating_does_not_move_the_learners_random_stream():
    a = make_agent(Toy(), "QCON-R", seed=4, warmup_steps=20).learn(60)
    b = make_agent(Toy(), "QCON-R", seed=4, warmup_steps=20).learn(60)
    connrl.evaluate(a, Toy(), 3)  # greedy: no draws
    a.learn(60)
    b.learn(60)
    np.testing.assert_array_equal(a.learner.q.w1, b.learner.q.w1)


def test_a_value_range_too_small_for_the_returns_is_warned_once():
    with pytest.warns(RuntimeWarning, match=r"a reward of 2 allows returns up to 200, beyond value_range \+-1") as w:
        make_agent(Toy(), "QCON-R", seed=0, warmup_steps=20, value_range=1.0).learn(100)
    assert len([x for x in w if "value_range" in str(x.message)]) == 1
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        make_agent(Toy(), "QCON-R", seed=0, warmup_steps=20).learn(100)  # the default range: no warning


_FEED_FORWARD = ["QCON", "QCON-R", "QCON-T", "AHCON", "AHCON-R", "AHCON-T", "window-Q"]


# with one hidden layer for every action too (recurrent-Q refuses it: tested with the other refusals)
@pytest.mark.parametrize("kind, shared", [(k, False) for k in [*_FEED_FORWARD, "recurrent-Q"]]
                         + [(k, True) for k in _FEED_FORWARD])
@pytest.mark.parametrize("average", [None, 40])  # with average_steps, the averaged greedy weights too
def test_a_loaded_agent_learns_on_exactly_as_the_saved_one_would(kind, shared, average, tmp_path):
    taught = {"lessons": _toy_lessons(tmp_path)} if kind.endswith("-T") else {}
    a = make_agent(Toy(), kind, seed=2, warmup_steps=30, hidden=4, context=2, average_steps=average,
                   shared_hidden=shared, **taught).learn(100)
    if shared:
        assert a.nets.state_dict()["w1" if not kind.startswith("AHCON") else "policy.w1"].shape[0] == 1
    a.save(tmp_path / "a")
    b = connrl.load(tmp_path / "a", Toy())
    a.learn(100)
    b.learn(100)
    sa, sb = a.nets.state_dict(), b.nets.state_dict()
    if average is not None:
        sa, sb = {**sa, **a.average.state()}, {**sb, **b.average.state()}
    assert sorted(sa) == sorted(sb) and len(sa) >= (2 if average is None else 4)
    for key in sa:
        np.testing.assert_array_equal(sa[key], sb[key])
    assert connrl.evaluate(a, Toy(), 2, seed=1) == connrl.evaluate(b, Toy(), 2, seed=1)


def test_a_damaged_agent_file_and_the_wrong_environment_are_one_line(tmp_path):
    agent = make_agent(Toy(), "QCON-R", warmup_steps=10).save(tmp_path / "a")
    (agent / "agent.npz").write_bytes(b"")
    with pytest.raises(ValueError, match="agent.npz: is not the file agent.json was saved with"):
        connrl.load(agent)
    (agent / "agent.json").write_text("[1]")
    with pytest.raises(ValueError, match="not a connrl agent file"):
        connrl.load(agent)
    fresh = make_agent(Toy(), "QCON-R", warmup_steps=10)
    with pytest.raises(ValueError, match="this agent was made for"):
        connrl.evaluate(fresh, gym.make("CartPole-v1"))


def test_an_input_without_spread_in_the_warm_up_is_left_as_it_is():
    s = InputScaler.fit(spaces.Box(-np.inf, np.inf, (2,)), np.array([[3.0, 1.0], [3.0, 2.0]]))
    np.testing.assert_allclose(s.encode([4.0, 1.5]), [1.0, 0.0])  # offset 3, scale 1 (no spread); 1.5 - 1.5 = 0


def _toy_lessons(tmp_path):
    connrl.record_lessons(Toy(), lambda obs: 1, 2, tmp_path / "toy.json")
    return tmp_path / "toy.json"


def test_recorded_lessons_hold_the_raw_observations_and_qcon_t_replays_them_scaled(tmp_path):
    import json
    doc = json.loads(_toy_lessons(tmp_path).read_text())
    assert len(doc["lessons"]) == 2
    first = doc["lessons"][0]
    assert first["inputs"] == [[0, 0], [1, 1], [2, 4], [3, 9], [4, 16], [5, 25]]  # [t, t^2], by hand
    assert first["actions"] == [1] * 5 and first["rewards"] == [2.0] * 5
    assert (first["terminated"], first["truncated"], first["taught"]) == (False, True, True)
    agent = make_agent(Toy(), "QCON-T", seed=0, warmup_steps=20, lessons=tmp_path / "toy.json")
    taught = agent.learner.book.taught
    assert len(taught) == 2 and all(x.taught for x in taught)
    s = agent.scaler  # the agent's own input code: (raw - offset) / scale
    np.testing.assert_allclose(taught[0].inputs[3], (np.array([3.0, 9.0]) - s.offset) / s.scale)
    twin = make_agent(Toy(), "QCON-T", seed=0, warmup_steps=20, lessons=tmp_path / "toy.json")
    twin.learner.book.taught.clear()  # the same agent, its taught lessons taken away
    agent.learn(5)  # one trial: the taught lessons are replayed after it
    twin.learn(5)
    assert not np.array_equal(twin.learner.q.values(taught[0].inputs[0]), agent.learner.q.values(taught[0].inputs[0]))


def test_the_cli_offers_the_apis_kinds():
    import argparse

    from connrl.own.api import KINDS
    from connrl.own.cli import add_own_task_commands
    sub = argparse.ArgumentParser().add_subparsers()
    add_own_task_commands(sub)
    assert tuple(sub.choices["train"]._option_string_actions["--agent"].choices) == KINDS
    from connrl.own.api import TAUGHT_KINDS
    from connrl.own.cli_tune import add_tune_command
    add_tune_command(sub)
    assert tuple(sub.choices["tune"]._option_string_actions["--agent"].choices) == tuple(
        k for k in KINDS if k not in TAUGHT_KINDS)


def test_replay_thresholds_follow_the_framework_unless_given():
    assert make_agent(Toy(), "QCON-R", warmup_steps=10).learner.config.replay.p_threshold == 0.01
    assert make_agent(Toy(), "AHCON-R", warmup_steps=10).learner.config.replay.p_threshold == 0.2  # 4.2.7
    assert make_agent(Toy(), "AHCON-R", warmup_steps=10, p_threshold=0.05).learner.config.replay.p_threshold == 0.05


def test_temperatures_follow_the_framework_unless_given():
    """AHC's merits get a hotter default temperature than Q-values (issue 30; Table 4.1's AHC agents too)."""
    q, ahc = make_agent(Toy(), "QCON-R", warmup_steps=10), make_agent(Toy(), "AHCON-R", warmup_steps=10)
    assert q.temperature(0) == pytest.approx(0.05 * q.value_range)
    assert ahc.temperature(0) == pytest.approx(2.0 * ahc.value_range)
    ahc.steps_done = q.steps_done = ahc.options.anneal_steps
    assert q.temperature(0) == pytest.approx(0.005 * q.value_range)
    assert ahc.temperature(0) == pytest.approx(0.1 * ahc.value_range)
    given = make_agent(Toy(), "AHCON-R", warmup_steps=10, t_start=0.05, t_end=0.005)
    assert given.temperature(0) == pytest.approx(0.05 * given.value_range)


def test_ahcon_r_learns_cartpole_not_one_push_for_ever():
    """Issue 30: at Q-learning's temperature AHCON-R's merits favoured one action in every state within 1,000 steps
    (9-step trials, greedy return 9); at the AHC default both actions stay greedy somewhere and it balances."""
    env = gym.make("CartPole-v1")
    agent = make_agent(env, "AHCON-R", seed=0).learn(10_000)
    rng, obs = np.random.default_rng(0), env.reset(seed=0)[0]
    greedy = []
    for _ in range(300):
        greedy.append(int(agent.predict(obs)[0]))
        obs, _, term, trunc, _ = env.step(int(rng.integers(2)))
        if term or trunc:
            obs = env.reset(seed=int(rng.integers(1000)))[0]
    assert 0.1 < np.mean(greedy) < 0.9
    assert np.mean(connrl.evaluate(agent, env, 5, seed=500)) > 100


class Shifted(Toy):
    action_space = spaces.Discrete(2, start=1)


class Lake4(gym.Env):
    """FrozenLake's 4x4 spaces without a registered id (a user's own task)."""

    observation_space, action_space = spaces.Discrete(16), spaces.Discrete(4)


def test_lessons_are_refused_in_one_line_where_they_do_not_fit(tmp_path):
    import json
    path = tmp_path / "cart.json"
    connrl.record_lessons(gym.make("CartPole-v1"), lambda obs: 0, 1, path)
    cases = [(lambda: make_agent(Toy(), "QCON-T"), "QCON-T needs a lesson file"),
             (lambda: make_agent(Toy(), "QCON-R", lessons=path), "lessons are replayed by QCON-T and AHCON-T only"),
             (lambda: make_agent(gym.make("Acrobot-v1"), "QCON-T", lessons=path),
              "lessons were recorded on 'CartPole-v1', expected 'Acrobot-v1'"),
             (lambda: make_agent(Toy(), "AHCON-T", lessons=path), "has 4 inputs, the agent expects 2"),
             (lambda: connrl.record_lessons(Toy(), lambda obs: 5, 1, tmp_path / "x.json"), "the teacher chose 5"),
             (lambda: connrl.record_lessons(Toy(), lambda obs: 0.9, 1, tmp_path / "x.json"), "the teacher chose 0.9"),
             (lambda: make_agent(gym.make("FrozenLake-v1", map_name="4x4"), "QCON-T", lessons=lake),
              "lessons were recorded with world options map_name='8x8'"),
             (lambda: make_agent(Lake4(), "QCON-T", lessons=odd), "lesson 0 holds observations outside Discrete(16)"),
             (lambda: make_agent(Shifted(), "QCON-R"), "a Discrete action space that starts at 0")]
    lake = tmp_path / "lake.json"
    connrl.record_lessons(gym.make("FrozenLake-v1", map_name="8x8"), lambda obs: 1, 1, lake)
    odd = tmp_path / "odd.json"  # a hand-made file for an unregistered task: observation 99 of 16 states
    doc = json.loads(lake.read_text())
    doc.update(env_id="", env_kwargs={})
    doc["lessons"][0]["inputs"][0] = [99]
    odd.write_text(json.dumps(doc))
    for call, message in cases:
        with pytest.raises(ValueError) as exc:
            call()
        assert message in str(exc.value) and "\n" not in str(exc.value)


def test_cli_train_with_a_lesson_file(tmp_path, capsys):
    from connrl import cli
    path = tmp_path / "cart.json"
    connrl.record_lessons(gym.make("CartPole-v1"), lambda obs: int(obs[2] + 0.5 * obs[3] > 0), 1, path)
    assert cli.main(["train", "CartPole-v1", "--steps", "200", "--teach", str(path), "--save", str(tmp_path / "a"),
                     "--quiet", "--option", "hidden=4"]) == 0
    import json
    assert json.loads((tmp_path / "a" / "agent.json").read_text())["agent"] == "QCON-T"  # --teach's default
    base = ["train", "CartPole-v1", "--steps", "10", "--save", str(tmp_path / "b")]
    for args, message in ((["--agent", "QCON-R", "--teach", str(path)], "--teach gives lessons to QCON-T or AHCON-T"),
                          (["--teach", str(tmp_path / "none.json")], "no such lesson file"),
                          (["--agent", "AHCON-T"], "AHCON-T needs --teach FILE")):
        with pytest.raises(SystemExit) as exc:
            cli.main(base + args)
        assert message in str(exc.value)
    with pytest.raises(SystemExit, match="lessons were recorded on 'CartPole-v1', expected 'Acrobot-v1'"):
        cli.main(["train", "Acrobot-v1", "--teach", str(path), "--save", str(tmp_path / "c")])
    assert not (tmp_path / "c").exists()  # refused before any folder or compute


def test_agent_files_are_strict_json_with_infinite_bounds_kept(tmp_path):
    import json
    env = gym.make("CartPole-v1")  # two of its four bounds are infinite
    make_agent(env, "QCON", warmup_steps=10).save(tmp_path / "a")

    def refuse(name):
        raise ValueError(f"non-standard JSON constant {name}")
    meta = json.loads((tmp_path / "a" / "agent.json").read_text(), parse_constant=refuse)
    assert meta["observation_space"]["high"][1] == "inf"
    again = connrl.load(tmp_path / "a", env)  # and the spaces still match the environment's
    assert np.isinf(again.observation_space.high[1])


def test_qcon_t_learns_from_lessons_on_a_task_with_a_discrete_observation(tmp_path):
    env = gym.make("FrozenLake-v1", is_slippery=False)
    path = [2, 2, 1, 1, 1, 2]  # right, right, down, down, down, right: the 4x4 map's safe way to the goal
    steps = iter(path * 10)
    connrl.record_lessons(env, lambda obs: next(steps), episodes=2, path=tmp_path / "t.json")
    agent = make_agent(env, "QCON-T", seed=0, lessons=tmp_path / "t.json")
    first = agent.learner.book.taught[0]
    assert first.inputs.shape == (7, 16) and np.array_equal(first.inputs[0], np.where(np.arange(16) == 0, 0.5, -0.5))
    assert agent.value_range == 1.0  # the taught goal's +1 ends the episode: counted once


def test_an_agent_whose_range_a_file_cannot_hold_is_refused_at_save_in_one_line(tmp_path):
    with pytest.raises(ValueError, match="option value_range must be None or a number > 0 and <= 1e\\+12"):
        make_agent(Toy(), "QCON-R", warmup_steps=10, value_range=2e12)  # refused before any step
    agent = make_agent(Toy(), "QCON-R", warmup_steps=10, value_range=1e12)
    agent.value_range = 2e12  # as rewards seen while learning could grow it
    with pytest.raises(ValueError, match="value_range 2e\\+12 is beyond 1e\\+12"):
        agent.save(tmp_path / "a")


def test_the_learning_rate_goes_linearly_to_lr_end_each_trial_at_the_rate_of_its_first_step(tmp_path):
    agent = make_agent(Toy(), "QCON-R", seed=1, warmup_steps=10, lr=0.1, lr_end=0.01, anneal_steps=20)
    assert agent.learning_rate() == pytest.approx(0.1)
    agent.learn(10)  # two 5-step trials, started at steps 0 and 5
    assert agent.nets.lr == pytest.approx(0.1 + (0.01 - 0.1) * 5 / 20)
    agent.learn(20)
    assert agent.learning_rate() == pytest.approx(0.01) and agent.nets.lr == pytest.approx(0.01)
    again = connrl.load(agent.save(tmp_path / "a"), Toy())
    assert again.options.lr_end == 0.01 and again.nets.lr == pytest.approx(0.01)  # the rate at the saved step
    # lr_end equal to lr is the constant rate: the same weights as without a schedule
    same = [make_agent(Toy(), "QCON-R", seed=2, warmup_steps=10, lr=0.1, **kw).learn(30)
            for kw in ({}, {"lr_end": 0.1})]
    np.testing.assert_array_equal(same[0].nets.w1, same[1].nets.w1)
    slower = make_agent(Toy(), "QCON-R", seed=2, warmup_steps=10, lr=0.1, lr_end=0.001, anneal_steps=5).learn(30)
    assert not np.array_equal(slower.nets.w1, same[0].nets.w1)
    with pytest.raises(ValueError, match="option lr_end must be a number > 0 and <= 100, got 0"):
        make_agent(Toy(), lr_end=0)


def test_ctrl_c_between_a_steps_parts_is_still_ctrl_c_and_learning_goes_on(monkeypatch):
    """A signal after a step's action and reward were recorded but before its next input: the half lesson is
    dropped (building it would fail its own check and turn the Ctrl-C into a ValueError)."""
    from connrl.core.lessons import LessonRecorder

    agent = make_agent(Toy(), "QCON-R", seed=0, warmup_steps=10)
    real_add, calls = LessonRecorder.add, []

    def add(self, x, a, r, y):
        calls.append(1)
        if len(calls) == 7:  # inside the second trial
            self.actions.append(int(a))
            self.rewards.append(float(r))
            raise KeyboardInterrupt
        real_add(self, x, a, r, y)

    monkeypatch.setattr(LessonRecorder, "add", add)
    with pytest.raises(KeyboardInterrupt):
        agent.learn(20)
    assert agent.steps_done == 7 and len(agent.learner.book.recorder) == 0
    monkeypatch.setattr(LessonRecorder, "add", real_add)
    assert agent.learn(5).steps_done == 12
