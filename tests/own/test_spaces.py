"""Which environments the own-task API takes (connrl.own.spaces): a vector env is refused first in one line;
Dict / Tuple / MultiDiscrete / MultiBinary / image-shaped Box observations are encoded by hand-checkable rules, learn,
and round-trip through agent.json; a damaged space description is refused in one line."""

import json

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import connrl
from connrl.own.api import InputScaler


class Cue(gym.Env):
    """Reward +1 for the action the cue names, -1 otherwise; 8 steps. The cue is a Discrete part of a Dict beside a
    Box of noise (``multi=False``) or the first entry of a MultiDiscrete (``multi=True``)."""

    action_space = spaces.Discrete(2)

    def __init__(self, multi=False):
        self.multi = multi
        self.observation_space = spaces.MultiDiscrete([2, 3]) if multi else spaces.Dict(
            {"cue": spaces.Discrete(2), "noise": spaces.Box(-1, 1, (2,), np.float32)})

    def _obs(self):
        self.cue = int(self.np_random.integers(2))
        if self.multi:
            return np.array([self.cue, self.np_random.integers(3)])
        return {"cue": self.cue, "noise": self.np_random.uniform(-1, 1, 2).astype(np.float32)}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return self._obs(), {}

    def step(self, a):
        r = 1.0 if a == self.cue else -1.0
        self.t += 1
        return self._obs(), r, False, self.t >= 8, {}


def _one_line(call, *parts):
    with pytest.raises(ValueError) as e:
        call()
    msg = str(e.value)
    assert "\n" not in msg and all(p in msg for p in parts), msg


VECTOR = "connrl agents learn from one environment at a time"


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    path = tmp_path_factory.mktemp("cue") / "agent"
    agent = connrl.make_agent(Cue(), "QCON-R", seed=0, warmup_steps=50, hidden=4).learn(800)
    agent.save(path)
    return agent, path


@pytest.mark.parametrize("vec", [lambda: gym.make_vec("CartPole-v1", 2, vectorization_mode="sync"),
                                 lambda: gym.make_vec("CartPole-v1", 2)])
def test_a_vector_env_is_refused_first_everywhere(trained, vec):
    agent, path = trained
    for call in (lambda: connrl.make_agent(vec()), lambda: connrl.load(path, vec()),
                 lambda: agent.learn(10, env=vec()), lambda: connrl.evaluate(agent, vec()),
                 lambda: connrl.record_lessons(vec(), lambda obs: 0, 1, "never-written.json")):
        _one_line(call, VECTOR, "2 copies", "gym.make(id) instead of gym.make_vec(id, n)")


def test_anything_with_num_envs_is_a_vector_env():
    class SB3Style(Cue):
        num_envs = 4
    _one_line(lambda: connrl.make_agent(SB3Style()), VECTOR, "4 copies")


@pytest.mark.parametrize("obs", [spaces.Text(5), spaces.Graph(spaces.Box(0, 1, (2,)), None),
                                 spaces.Sequence(spaces.Discrete(2)),
                                 spaces.Dict({"a": spaces.Discrete(2), "b": spaces.Text(3)})])
def test_graph_text_and_sequence_observations_are_refused_naming_what_works(obs):
    env = Cue()
    env.observation_space = obs
    _one_line(lambda: connrl.make_agent(env), "connrl agents need a Box (any shape), Discrete, MultiDiscrete or "
              "MultiBinary observation space, or a Dict / Tuple of them")


def test_a_continuous_action_space_is_still_refused():
    _one_line(lambda: connrl.make_agent(gym.make("Pendulum-v1")), "connrl agents need a Discrete action space")


def test_the_code_of_composite_observations_by_hand():
    space = spaces.Dict({"v": spaces.Box(np.array([-2.0, -np.inf]), np.array([2.0, np.inf]), dtype=np.float64),
                         "pos": spaces.Discrete(3, start=1),
                         "t": spaces.Tuple([spaces.MultiDiscrete([2, 3]), spaces.MultiBinary(2)])})
    # flatten order: keys sorted (pos, t, v); the unbounded Box entry has samples 1, 3: mean 2, std 1 -> scale 2
    samples = [space.sample() | {"v": np.array([0.0, y])} for y in (1.0, 3.0)]
    s = InputScaler.fit(space, samples)
    obs = {"pos": 2, "t": (np.array([1, 0]), np.array([1, 0], np.int8)), "v": np.array([1.0, 6.0])}
    want = [-0.5, 0.5, -0.5,  # pos 2 of 1..3
            -0.5, 0.5, 0.5, -0.5, -0.5,  # MultiDiscrete [1, 0] of [2, 3]
            0.5, -0.5,  # MultiBinary [1, 0]
            0.5, 2.0]  # v: 1 of [-2, 2]; (6 - 2) / 2
    np.testing.assert_allclose(s.encode(obs), want)
    image = InputScaler.fit(spaces.Box(0, 255, (2, 2, 1), np.uint8), [np.zeros((2, 2, 1))])
    np.testing.assert_allclose(image.encode(np.array([[[0], [255]], [[51], [255]]])), [-1, 1, -0.6, 1])


def test_spread_scales_bounded_units_by_the_warm_ups_samples_too():
    box = spaces.Box(np.array([-10.0, -np.inf, 0.0]), np.array([10.0, np.inf, 1.0]), dtype=np.float64)
    samples = np.array([[0.5, 1.0, 0.0], [1.5, 3.0, 0.0]])  # mean 1, 2, 0; std 0.5, 1, 0
    np.testing.assert_allclose(InputScaler.fit(box, samples).encode([2.0, 6.0, 1.0]), [0.2, 2.0, 1.0])
    # by the spread: (2 - 1) / (2 * 0.5); (6 - 2) / 2; a unit the samples never moved is left as it is
    np.testing.assert_allclose(InputScaler.fit(box, samples, "spread").encode([2.0, 6.0, 1.0]), [1.0, 2.0, 1.0])
    both = spaces.Dict({"b": spaces.MultiBinary(1), "v": box})  # a composite space's Box entries likewise; bits not
    s = InputScaler.fit(both, [{"b": np.array([k % 2], np.int8), "v": x} for k, x in enumerate(samples)], "spread")
    np.testing.assert_allclose(s.encode({"b": np.array([1], np.int8), "v": np.array([2.0, 6.0, 1.0])}),
                               [0.5, 1.0, 2.0, 1.0])
    _one_line(lambda: connrl.make_agent(gym.make("CartPole-v1"), input_scale="warmup"),
              "option input_scale must be one of bounds, spread, got 'warmup'")


class Blink(gym.Env):
    """Observation 0 at reset and 2 after the one step of an episode, inside bounds of +-100."""

    observation_space = spaces.Box(-100.0, 100.0, (1,), np.float64)
    action_space = spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return np.zeros(1), {}

    def step(self, a):
        return np.full(1, 2.0), 1.0, True, False, {}


def test_make_agent_scales_by_the_spread_when_asked_and_the_saved_agent_keeps_it(tmp_path):
    # a warm-up of 50 steps sees 0, then 2 and 0 again for each one-step episode: 101 observations
    seen = np.array([0.0] + [2.0, 0.0] * 50)
    want = (2.0 - seen.mean()) / (2 * seen.std())
    agent = connrl.make_agent(Blink(), "QCON-R", seed=0, warmup_steps=50, input_scale="spread")
    assert agent.scaler.encode(np.full(1, 2.0))[0] == pytest.approx(want, rel=1e-12)
    assert connrl.make_agent(Blink(), "QCON-R", seed=0, warmup_steps=50).scaler.encode(np.full(1, 2.0))[0] == 0.02
    agent.save(tmp_path / "a")
    assert connrl.load(tmp_path / "a", Blink()).scaler.to_json() == agent.scaler.to_json()


@pytest.mark.parametrize("multi", [False, True])
def test_dict_and_multidiscrete_observations_learn_and_round_trip(trained, tmp_path, multi):
    if multi:
        agent, path = connrl.make_agent(Cue(True), "QCON-R", seed=0, warmup_steps=50, hidden=4).learn(800), tmp_path
        agent.save(path)
        observations = [np.array([c, k]) for c in (0, 1) for k in range(3)]
    else:
        agent, path = trained
        observations = [{"cue": c, "noise": np.array([x, -x], np.float32)} for c in (0, 1) for x in (-0.9, 0.0, 0.7)]
    cues = [int(o[0]) if multi else o["cue"] for o in observations]
    assert [int(agent.predict(o)[0]) for o in observations] == cues  # follows the cue: learnt, not guessed
    loaded = connrl.load(path, Cue(multi))
    assert [int(loaded.predict(o)[0]) for o in observations] == cues
    assert connrl.evaluate(loaded, Cue(multi), 3) == connrl.evaluate(agent, Cue(multi), 3) == [8.0] * 3


def test_another_dict_space_is_refused_by_the_loaded_agent(trained):
    env = Cue()
    env.observation_space = spaces.Dict({"cue": spaces.Discrete(3), "noise": spaces.Box(-1, 1, (2,))})
    _one_line(lambda: connrl.load(trained[1], env), "this agent was made for another environment",
              "observation_space")


@pytest.mark.parametrize("edit, message", [
    (lambda o: o.__setitem__("spaces", {"cue": o["spaces"][0][1]}), "observation_space.spaces: must be a non-empty"),
    (lambda o: o["spaces"][1].__setitem__(0, "cue"), "must be a list of [key, space] pairs with distinct string keys"),
    (lambda o: o["spaces"][0][1].__setitem__("n", -2), "observation_space.spaces[0].n: is -2"),
    (lambda o: o["spaces"][1][1].__setitem__("type", "Text"), "observation_space.spaces[1]: must be an object with"),
    (lambda o: o["spaces"][1][1].__setitem__("code", "import os"), "observation_space.spaces[1]: must be an object"),
    (lambda o: o["spaces"][0].__setitem__(1, {"type": "MultiDiscrete", "shape": [1], "nvec": [3], "start": [0]}),
     "scaler.n: is 4; it must be 5"),
])
def test_a_damaged_space_description_is_refused_in_one_line(trained, tmp_path, edit, message):
    _, saved = trained
    path = tmp_path / "agent"
    path.mkdir()
    (path / "agent.npz").write_bytes((saved / "agent.npz").read_bytes())
    m = json.loads((saved / "agent.json").read_text())
    edit(m["observation_space"])
    (path / "agent.json").write_text(json.dumps(m))
    _one_line(lambda: connrl.load(path), f"{path / 'agent.json'}: ", message)


def test_a_teacher_on_a_dict_task_and_a_damaged_lesson_row(tmp_path):
    file = tmp_path / "teacher.json"
    connrl.record_lessons(Cue(), lambda obs: int(obs["cue"]), episodes=2, path=file)
    agent = connrl.make_agent(Cue(), "QCON-T", seed=0, warmup_steps=20, lessons=file)
    assert len(agent.learner.book.taught) == 2
    d = json.loads(file.read_text())
    rows = d["lessons"][0]["inputs"]
    rows[0][:2] = [1.0, 1.0]  # the cue's one-hot with two ones
    file.write_text(json.dumps(d))
    _one_line(lambda: connrl.make_agent(Cue(), "QCON-T", lessons=file), "lesson 0 holds rows that are not "
              "observations of Dict")
