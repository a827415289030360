"""connrl on your own task, in the Stable-Baselines3 shape: ``make_agent``, ``learn``, ``save``, ``load``, ``evaluate``.

    import gymnasium as gym, connrl
    env = gym.make("CartPole-v1")
    agent = connrl.make_agent(env, "QCON-R", seed=0).learn(50_000)
    agent.save("cartpole-agent"); agent = connrl.load("cartpole-agent", env)
    print(connrl.evaluate(agent, env, episodes=10))

Any single (not vectorised) Gymnasium environment with a ``Discrete`` action space and a ``Box`` (any shape),
``Discrete``, ``MultiDiscrete`` or ``MultiBinary`` observation, or a ``Dict`` / ``Tuple`` of them, works without
hand-tuning the scales the thesis's tasks set by hand (``Graph``, ``Text`` and ``Sequence`` observations are refused):

- **Inputs** (``InputScaler``): a bounded ``Box`` dimension is mapped affinely onto [-1, 1]; an unbounded one by the
  mean and spread of the observations a random policy sees in the first ``warmup_steps`` steps (frozen then, so learning
  sees one fixed input code), and so is a bounded one with ``input_scale="spread"``; a ``Discrete`` observation is
  one-hot (+-0.5, the thesis's binary code, 5.3.2), a ``MultiDiscrete`` one its one-hots side by side, a
  ``MultiBinary`` bit +-0.5; a ``Dict`` / ``Tuple`` is its parts' codes in ``gymnasium.spaces.flatten`` order
  (connrl.own.spaces).
- **Values**: the nets' outputs span +-``value_range``, by default the largest |discounted return| the warm-up's rewards
  allow: max |reward| / (1 - gamma) for rewards that can recur every step, but only |reward| for one that ends the
  episode (a goal's +1 gives 1, not 100); until a non-zero reward is seen the range is provisional and the first ones
  set it, and larger rewards seen later grow it, the Q-values kept (connrl.own.value_scale). The temperature acts on
  Q / value_range, so the scale does not change exploration; AHC's merits get a hotter one than Q-learning's, as in
  the thesis (connrl.own.options.TEMPERATURES).
- **Schedules** run over environment steps (``anneal_steps``), not trials: a user states a budget in steps.

Frameworks by the thesis's names: ``"QCON"`` (on-line Q-learning, Fig. 3.4), ``"QCON-R"`` (with backward TD(lambda)
experience replay after each trial, 3.5 and 5.1), ``"QCON-T"`` (QCON-R that also replays a teacher's lessons after
every trial, 3.7: ``make_agent(env, "QCON-T", lessons="file.json")``, a file ``record_lessons`` writes), the
adaptive heuristic critic ``"AHCON"`` / ``"AHCON-R"`` / ``"AHCON-T"`` (a V-net and policy nets, Fig. 3.2, with
replay and teaching likewise), and for tasks with hidden state Ch. 7's ``"window-Q"`` (the ``window`` latest
observations and actions as input) and ``"recurrent-Q"`` (recurrent Q-nets, batch BPTT replay).
Files are ``agent.json`` and ``agent.npz`` (no pickle; connrl.own.files).
"""

from __future__ import annotations

import warnings
from contextlib import nullcontext
from dataclasses import asdict
from pathlib import Path

import numpy as np
from gymnasium import spaces

from connrl.agents import LinearSchedule, QCONConfig, ReplayConfig
from connrl.agents.build import make_learner
from connrl.agents.memory import RecurrentQ, RecurrentQConfig, WindowQ, window_input_size
from connrl.core.divergence import network_problem
from connrl.core.exploration import boltzmann_select
from connrl.core.lessons import Lesson
from connrl.core.rollout import MAX_EPISODE_STEPS, episode_cap, run_trial  # noqa: F401  (MAX_EPISODE_STEPS: API)
from connrl.core.training import as_callback, train
from connrl.nets import NetConfig
from connrl.nets.recurrent import RecurrentNetConfig
from connrl.own.averaging import WeightAverage
from connrl.own.files import (
    check_arrays,
    check_evaluation,
    read_agent,
    read_taught,
    record_lessons,
    write_agent,
)
from connrl.own.options import MAX_NET_WEIGHTS, MAX_VALUE_RANGE, AgentOptions, options_from, temperatures
from connrl.own.scaling import InputScaler, ScaledEnv, warmup
from connrl.own.spaces import check_observation_space, check_single, space_from, space_json, split_batch
from connrl.own.value_scale import PROVISIONAL, range_for, rescale, reward_sizes
from connrl.storage import FileError

KINDS = ("QCON", "QCON-R", "QCON-T", "AHCON", "AHCON-R", "AHCON-T", "window-Q", "recurrent-Q")
MEMORY_KINDS = ("window-Q", "recurrent-Q")  # act on a history: predict() needs one, evaluate() keeps it
TAUGHT_KINDS = ("QCON-T", "AHCON-T")  # need a lesson file: make_agent(..., lessons=path)
__all__ = ["Agent", "AgentOptions", "InputScaler", "evaluate", "load", "make_agent", "record_lessons"]


def check_spaces(env) -> None:
    """Refuse, in one line, an environment connrl's agents cannot act in (a vector env first: its batched spaces
    would be refused as if they were the task's)."""
    check_single(env)
    if not isinstance(env.action_space, spaces.Discrete):
        raise ValueError(f"connrl agents need a Discrete action space, got {env.action_space}")
    if int(env.action_space.start) != 0:  # the nets number their actions 0..n-1
        raise ValueError(f"connrl agents need a Discrete action space that starts at 0, got {env.action_space}")
    check_observation_space(env.observation_space)


class Agent:
    """A thesis learner bound to one environment's spaces, with its scales (``make_agent`` builds it)."""

    def __init__(self, kind: str, options: AgentOptions, observation_space, action_space, scaler: InputScaler,
                 value_range: float | None, seed: int, env_id: str | None):
        if kind not in KINDS:
            raise ValueError(f"unknown agent {kind!r}; available: {', '.join(KINDS)}")
        # value_range None: provisional until the first non-zero reward sets it (connrl.own.value_scale)
        self.range_set = value_range is not None
        self.kind, self.options, self.scaler = kind, options, scaler
        self.value_range = float(value_range) if self.range_set else PROVISIONAL
        self.observation_space, self.action_space = observation_space, action_space
        self.env_id, self.seed = env_id, seed
        self.rng = np.random.default_rng(seed)
        self._predict_rng, self._history = None, False  # predict()'s own draws; its memory agents' history begun
        self.evaluation = None  # its latest greedy evaluation, as EvalCallback records it: saved and loaded with it
        self.steps_done, self.trials_done = 0, 0
        self._env = None  # the environment make_agent / load was given: learn() trains in it by default
        self._range_warned = False
        o, n = options, int(action_space.n)
        width = window_input_size(scaler.n_inputs, n, o.window) if kind == "window-Q" else scaler.n_inputs
        if width * (max(o.hidden, 1) + 1) * n > MAX_NET_WEIGHTS:
            raise ValueError(f"{width} inputs x {o.hidden} hidden units x {n} actions is more than "
                             f"{MAX_NET_WEIGHTS:,} weights; use fewer hidden units or a smaller observation")
        self.learner = _learner(kind, o, scaler.n_inputs, n, self.value_range, self.temperature, self.rng)
        # the greedy policy's weights: the live ones, or their moving average (connrl.own.averaging)
        self.average = WeightAverage(self.nets, o.average_steps) if o.average_steps is not None else None

    @property
    def nets(self):
        """The learner's networks (``state_dict`` / ``load_state_dict``; AHCON's V-net and policy nets as one)."""
        if self.kind.startswith("AHCON"):
            return _NetPair(self.learner.v, self.learner.policy)
        return self.learner.net if self.kind == "recurrent-Q" else self.learner.q

    def temperature(self, trial: int) -> float:
        """T in Q units at the current step: linear on Q / value_range from t_start to t_end over anneal_steps."""
        o = self.options
        frac = min(self.steps_done / o.anneal_steps, 1.0)
        t_start, t_end = temperatures(o, self.kind)  # None: the framework's (AHC's hotter: api_options.TEMPERATURES)
        return (t_start + (t_end - t_start) * frac) * self.value_range

    def learning_rate(self) -> float:
        """The learning rate at the current step: lr, or linear from lr to lr_end over anneal_steps."""
        o = self.options
        if o.lr_end is None:
            return o.lr
        return o.lr + (o.lr_end - o.lr) * min(self.steps_done / o.anneal_steps, 1.0)

    def _set_learning_rate(self) -> None:
        """Set the schedule's rate on every net; without a schedule a rate set by hand is left as it is."""
        if self.options.lr_end is None:
            return
        for net in _all_nets(self):
            net.lr = self.learning_rate()

    def learn(self, total_steps: int, callback=None, progress: bool = False, env=None,
              max_trial_steps: int | None = None) -> Agent:
        """Train for exactly ``total_steps`` environment steps in ``env`` (the one given to ``make_agent`` by
        default). A trial the budget cuts is truncated, not failed, and replayed like any other (replay bootstraps
        through it); so is a trial longer than ``max_trial_steps`` (default: the env's own time limit, else
        ``MAX_EPISODE_STEPS``), so a task without a time limit is still learnt from. ``callback``: a
        connrl.own.callbacks.Callback (evaluation, checkpoints, a log), a list of them, or ``f(agent, trial_return)``
        after each trial; False from it stops training."""
        env = env if env is not None else self._env
        if env is None:
            raise ValueError("learn() needs the environment: make_agent(env, ...) keeps it, load(path, env) too")
        if isinstance(total_steps, bool) or not isinstance(total_steps, int) or total_steps < 1:
            raise ValueError(f"total_steps must be a whole number >= 1, got {total_steps!r}")
        cap = episode_cap(env, max_trial_steps)
        callbacks = as_callback(callback)
        self.check_env(env)
        scaled = ScaledEnv(env, self.scaler)
        scaled.on_sizes = self._check_range
        end = self.steps_done + total_steps

        def play(k, left):
            self._set_learning_rate()  # a trial and its replay learn at the rate of the step it starts at
            try:  # a trial the budget or the cap cuts is a timeout: the learner bootstraps through it
                stats = run_trial(scaled, self.learner, trial=self.trials_done, learning=True,
                                  seed=int(self.rng.integers(2**31)), max_steps=min(cap, left))
            except BaseException:  # Ctrl-C inside a trial: its steps were taken; a lesson still being recorded is
                self.steps_done += scaled.steps  # dropped, so the next learn() starts a trial of its own (one cut
                self.learner.book.recorder.discard()  # in the replay after it is kept, partly replayed)
                if self.average is not None:  # its on-line updates were learnt: the average follows them
                    self.average.update(scaled.steps)
                raise
            self.steps_done += stats.steps
            self.trials_done += 1
            if self.average is not None:
                self.average.update(stats.steps)
            if progress:
                print(f"\rsteps {self.steps_done}/{end}  trial {self.trials_done}  return {stats.total_reward:.1f}",
                      end="", flush=True)
            return stats

        self._history = False  # training begins trials of its own: predict's next call begins a history anew
        train(play, callbacks, agent=self, steps=total_steps)
        if progress:
            print()
        return self

    def evaluate(self, env, episodes: int = 10, seed: int = 0, max_episode_steps: int | None = None) -> list[float]:
        """``connrl.evaluate(agent, ...)``."""
        if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
            raise ValueError(f"episodes must be a whole number >= 1, got {episodes!r}")
        cap = episode_cap(env, max_episode_steps)
        self.check_env(env)
        scaled = ScaledEnv(env, self.scaler)  # the learner's own greedy trial (T = 0, no random draws, nothing learnt)
        self._history = False
        with self.greedy_weights():
            return [run_trial(scaled, self.learner, trial=self.trials_done, learning=False, seed=seed + k,
                              max_steps=cap).total_reward for k in range(episodes)]

    def greedy_weights(self):
        """A context in which the nets hold the greedy policy's weights (the average, with ``average_steps``)."""
        return self.average.acting() if self.average is not None else nullcontext()

    def check_env(self, env) -> None:
        """Refuse, in one line, an environment whose spaces are not the ones this agent was made for."""
        check_single(env)
        for name in ("observation_space", "action_space"):
            mine, theirs = space_json(getattr(self, name)), space_json(getattr(env, name))
            if mine != theirs:
                raise ValueError(f"this agent was made for {self.env_id or 'another environment'} with {name} "
                                 f"{mine}; the given environment has {theirs}")

    def _check_range(self, sizes: tuple[float, float]) -> None:
        """Called when the rewards seen while learning grow (``sizes``: connrl.own.value_scale.reward_sizes). The first
        non-zero ones set a provisional range (the nets rescaled: every target so far was 0); later ones that allow
        returns beyond +-value_range grow it, keeping the Q-values (connrl.own.value_scale.rescale). A range the user
        set is kept, with a warning, once: such targets are cut off and the Q-values stop telling actions apart."""
        bound = range_for(*sizes, self.options.gamma)
        if bound is None or self.range_set and bound <= self.value_range * (1 + 1e-9):
            return
        if self.options.value_range is None:
            if self.average is not None and self.range_set:  # the average's Q-values kept as the live ones are
                self.average.scale_outputs(self.value_range / bound)
            rescale(_all_nets(self), bound, keep_q=self.range_set)
            self.range_set, self.value_range = True, bound
            # the rest of this trial and its replay explore at the new scale, not the old one
            self.learner.explore.base = self.temperature(self.trials_done)
            return
        if not self._range_warned:
            self._range_warned = True
            r_max = sizes[0] if bound > sizes[1] else sizes[1]
            warnings.warn(f"a reward of {r_max:.3g} allows returns up to {bound:.3g}, beyond value_range "
                          f"+-{self.value_range:.3g}: such targets are cut off; give a larger value_range "
                          "(make_agent(..., value_range=...) or connrl train --option value_range=...)", RuntimeWarning,
                          stacklevel=3)

    def predict(self, observation, state=None, episode_start=None, deterministic: bool = True):
        """Stable-Baselines3's ``predict``: ``(action, state)`` for one observation, or for a batch of them (a vector
        env's, one first axis over its environments), so SB3's ``evaluate_policy`` and RL Zoo's scripts run a connrl
        agent. ``deterministic`` (the default, where SB3's is False: a trained policy is the greedy one here) gives
        the greedy action (T = 0, the first of equal values); False draws from Eq. 3.4 at the temperature the
        schedule gives at the agent's step (``temperature``), with a generator of its own (the learner's random
        stream never moves). Memoryless agents hand ``state`` back as given. Window-Q and recurrent-Q keep their
        history in the agent, for one environment: a true ``episode_start``, the first call, and the first call
        after ``learn`` or ``evaluate`` begin a new one; they act greedily only. With ``average_steps`` every
        prediction reads the averaged weights (``greedy_weights``), as ``evaluate`` does."""
        batch = split_batch(self.observation_space, observation)
        observations = [observation] if batch is None else batch
        if self.kind in MEMORY_KINDS:
            if len(observations) != 1 or not deterministic:
                raise ValueError(f"{self.kind} keeps one history in the agent: predict one environment's observation "
                                 "at a time, greedily (deterministic=True)")
            start = not self._history or (episode_start is not None and bool(np.asarray(episode_start).ravel()[0]))
            with self.greedy_weights():
                actions = [self._history_action(observations[0], start)]
        else:
            with self.greedy_weights():
                actions = [self._action(o, deterministic) for o in observations]
        return (np.array(actions[0]) if batch is None else np.array(actions)), state

    def _action(self, obs, deterministic: bool) -> int:
        x = self.scaler.encode(obs)
        merits = self.learner.policy.values(x) if self.kind.startswith("AHCON") else self.learner.q.values(x)
        if deterministic:
            return int(np.argmax(merits))
        if self._predict_rng is None:
            self._predict_rng = np.random.default_rng(None if self.seed is None else [self.seed, 1])
        return boltzmann_select(merits, self.temperature(self.trials_done), self._predict_rng)[0]

    def _history_action(self, obs, start: bool) -> int:
        x = self.scaler.encode(obs)
        if start:
            self.learner.begin_trial(x, None, trial=self.trials_done, learning=False)
            self._history = True
        return int(self.learner.act(x, None, greedy=True))

    def __repr__(self) -> str:
        """Which agent this is and what its last evaluation said (``connrl.load`` of a run's best shows its score)."""
        e = self.evaluation
        said = "" if e is None else (f"; evaluated at step {e['steps']}: mean return {e['mean']:.2f} over "
                                     f"{e['episodes']} episodes{' (best)' if e['best'] else ''}")
        return f"<connrl Agent {self.kind} on {self.env_id or 'an unnamed env'}, trained {self.steps_done} steps{said}>"

    def divergence(self) -> str | None:
        """What shows that learning diverged (non-finite weights, or weights beyond connrl.core.divergence's limit,
        where every unit is saturated: a learning rate too large for the task), or None. A diverged agent is never
        saved as a good one."""
        return network_problem(self.learner)

    def save(self, path) -> Path:
        """``path/agent.json`` and ``path/agent.npz`` (no pickle; connrl.own.files), written as one (a failed save
        leaves the old pair); returns ``path``. A diverged agent (``divergence()``) is refused with a ValueError."""
        problem = self.divergence()
        if problem:
            raise ValueError(f"the agent diverged after {self.steps_done} steps ({problem}); it is not saved: a "
                             "smaller learning rate (option lr) keeps its weights bounded")
        if self.value_range > MAX_VALUE_RANGE:
            raise ValueError(f"value_range {self.value_range:.3g} is beyond {MAX_VALUE_RANGE:.0e}, which agent files "
                             "hold: scale the task's rewards down")
        path = Path(path)
        memory = self.learner.book.memory
        write_agent(path, {
            "agent": self.kind, "env_id": self.env_id, "observation_space": space_json(self.observation_space),
            "action_space": space_json(self.action_space), "options": asdict(self.options),
            "scaler": self.scaler.to_json(), "value_range": self.value_range, "range_set": self.range_set,
            "seed": self.seed,
            "steps_done": self.steps_done, "trials_done": self.trials_done, "rng": self.rng.bit_generator.state,
            **({"evaluation": self.evaluation} if self.evaluation is not None else {})},
            {**self.nets.state_dict(), **(self.average.state() if self.average is not None else {})},
            memory.lessons if memory is not None else [], self.learner.book.taught)
        return path


def _all_nets(agent: Agent) -> list:
    nets = agent.nets
    return list(nets.parts.values()) if isinstance(nets, _NetPair) else [nets]


class _NetPair:
    """AHCON's V-net and policy nets behind one ``state_dict`` (keys ``v.*`` and ``policy.*``)."""

    def __init__(self, v, policy):
        self.parts = {"v": v, "policy": policy}

    def state_dict(self) -> dict:
        return {f"{name}.{k}": a for name, net in self.parts.items() for k, a in net.state_dict().items()}

    def load_state_dict(self, state: dict) -> None:
        for name, net in self.parts.items():
            net.load_state_dict({k.split(".", 1)[1]: a for k, a in state.items() if k.startswith(name + ".")})


def _learner(kind: str, o: AgentOptions, n_inputs: int, n_actions: int, value_range: float, temperature, rng):
    """The thesis learner ``kind`` on ``n_inputs`` scaled inputs, its Q (or V and merits) in +-value_range."""
    ahc = kind.startswith("AHCON")
    p_threshold = o.p_threshold if o.p_threshold is not None else (0.2 if ahc else 0.01)  # 4.2.7
    replay = None if kind in ("QCON", "AHCON") else ReplayConfig(
        capacity=o.capacity, lessons_per_trial=LinearSchedule(o.lessons_per_trial, o.lessons_per_trial),
        p_threshold=p_threshold, batch=kind == "recurrent-Q")
    if kind == "recurrent-Q":
        if o.shared_hidden:
            raise ValueError("option shared_hidden is for the feed-forward nets; recurrent-Q's nets are one per action")
        net = RecurrentNetConfig(n_inputs, max(o.hidden, 1), min(o.context, max(o.hidden, 1)), value_range=value_range,
                                 init_range=o.init_range, lr=o.lr, momentum=o.momentum)
        return RecurrentQ(RecurrentQConfig(net=net, temperature=temperature, gamma=o.gamma, lam=o.lam, replay=replay),
                          n_actions, rng)
    size = window_input_size(n_inputs, n_actions, o.window) if kind == "window-Q" else n_inputs
    if o.shared_hidden and o.hidden == 0:
        raise ValueError("option shared_hidden needs hidden units (hidden >= 1)")
    net = NetConfig(size, o.hidden, value_range=value_range, init_range=o.init_range, lr=o.lr, momentum=o.momentum,
                    shared_hidden=o.shared_hidden)
    if kind == "window-Q":
        cfg = QCONConfig(net=net, temperature=temperature, gamma=o.gamma, lam=o.lam, replay=replay)
        return WindowQ(cfg, n_actions, rng, n_sensation=n_inputs, window=o.window)
    return make_learner(ahc, net, n_actions, rng, temperature=temperature, gamma=o.gamma, lam=o.lam, replay=replay)


def make_agent(env, kind: str = "QCON-R", seed: int = 0, lessons=None, **options) -> Agent:
    """A thesis learner for ``env`` with its input and value scales set from a random-policy warm-up (module
    docstring); ``options`` are ``AgentOptions`` fields; ``lessons`` is the lesson file QCON-T and AHCON-T replay
    (``record_lessons`` writes one)."""
    check_spaces(env)
    if kind not in KINDS:
        raise ValueError(f"unknown agent {kind!r}; available: {', '.join(KINDS)}")
    if (lessons is None) == (kind in TAUGHT_KINDS):
        raise ValueError(f"{kind} needs a lesson file: make_agent(env, {kind!r}, lessons=path)" if lessons is None
                         else f"lessons are replayed by {' and '.join(TAUGHT_KINDS)} only, not by {kind}")
    o = options_from(options)
    rng = np.random.default_rng(seed)
    raw_taught = read_taught(lessons, env) if lessons is not None else []  # a file for another task: refused first
    seen, rewards, episodes = warmup(env, o.warmup_steps, np.random.default_rng(rng.integers(2**63)))
    scaler = InputScaler.fit(env.observation_space, seen, o.input_scale)
    taught = [Lesson(np.array([scaler.encode_row(x) for x in lesson.inputs]), lesson.actions, lesson.rewards,
                     terminated=lesson.terminated, truncated=lesson.truncated, taught=True) for lesson in raw_taught]
    rewards += [(r, x.terminated and k == x.rewards.size - 1) for x in taught for k, r in enumerate(x.rewards)]
    value_range = o.value_range or range_for(*reward_sizes(rewards), o.gamma)  # None: set by the first reward
    spec = getattr(env, "spec", None)
    agent = Agent(kind, o, env.observation_space, env.action_space, scaler, value_range,
                  int(rng.integers(2**31)), spec.id if spec is not None else None)
    agent.learner.add_taught_lessons(taught)
    if agent.learner.book.memory is not None and kind != "window-Q":  # replay the warm-up's episodes too: every
        for obs, acts, rews, terminated in episodes:  # action's net learns from the start, none left as it began
            # (window-Q's lessons hold windows the warm-up did not record)
            agent.learner.book.memory.add(Lesson(np.array([scaler.encode(x) for x in obs]), np.array(acts),
                                                 np.array(rews), terminated=terminated, truncated=not terminated))
    agent._env = env
    return agent


def load(path, env=None) -> Agent:
    """An agent written by ``Agent.save`` (weights, replay memory, taught lessons, random state: learning goes on as it
    would have); with ``env``, its spaces must be the saved ones. Every field and array is checked before anything
    is built from it (connrl.own.files); a damaged or foreign file is a ValueError in one line naming it."""
    if env is not None:
        check_single(env)
    path = Path(path)
    m, arrays = read_agent(path, KINDS)
    meta = path / "agent.json"
    try:
        options = options_from(m["options"])
    except (ValueError, TypeError) as exc:
        raise FileError(meta, str(exc), "options") from None
    obs_space = space_from(m["observation_space"])
    agent = Agent(m["agent"], options, obs_space, space_from(m["action_space"]),
                  InputScaler.from_json(m["scaler"], obs_space), m["value_range"], m["seed"], m.get("env_id"))
    if m.get("range_set") is False:  # still provisional (files before it was saved: set)
        agent.range_set = False
    nets = agent.nets.state_dict()
    average = agent.average.state() if agent.average is not None else {}  # saved whenever average_steps is set
    state, memory, taught = check_arrays(path, arrays, {**nets, **average}, m, _input_width(agent),
                                         int(agent.action_space.n))
    agent.nets.load_state_dict({k: state[k] for k in nets})
    if agent.average is not None:
        agent.average.load(state)
    for lesson in memory:
        agent.learner.book.memory.add(lesson)
    agent.learner.add_taught_lessons(taught)
    try:
        agent.rng.bit_generator.state = m["rng"]
    except (ValueError, TypeError, KeyError, OverflowError) as exc:
        raise FileError(meta, f"is not a NumPy {type(agent.rng.bit_generator).__name__} state ({exc})", "rng") from None
    agent.steps_done, agent.trials_done = int(m["steps_done"]), int(m["trials_done"])
    agent.evaluation = check_evaluation(meta, m.get("evaluation"), agent.steps_done)
    agent._set_learning_rate()  # the schedule's rate at the saved step, as learn() would set it
    if env is not None:
        try:
            agent.check_env(env)
        except ValueError as exc:
            raise ValueError(f"{meta}: {exc}") from None
    agent._env = env
    return agent


def _input_width(agent: Agent) -> int:
    """The width of the rows an agent's lessons hold: its (Q- or V-) net's inputs."""
    learner = agent.learner
    net = learner.net if agent.kind == "recurrent-Q" else learner.v if agent.kind.startswith("AHCON") else learner.q
    return int(net.config.n_inputs)


def evaluate(agent: Agent, env, episodes: int = 10, seed: int = 0, max_episode_steps: int | None = None) -> list[float]:
    """The greedy policy's return in each of ``episodes`` episodes (seeds ``seed``, ``seed + 1``, ...), each at most
    ``max_episode_steps`` long (default: the env's own time limit, else ``MAX_EPISODE_STEPS``); nothing learnt."""
    return agent.evaluate(env, episodes, seed, max_episode_steps)
