"""Three memory architectures for hidden-state tasks (thesis Ch. 7, Fig. 7.1): window-Q, recurrent-Q and
recurrent-model. All follow the agent protocol of ``connrl.agents.base`` and learn a Q-function.

- **Window-Q** (7.3, Fig. 7.1a): QCON whose input is the current sensation, the N latest sensations and the
  N latest actions (a tapped delay line). Lessons store the windowed inputs, so replay is ordinary
  incremental TD(lambda) replay (Fig. 5.1a).
- **Recurrent-Q** (7.3, Fig. 7.1b): a recurrent OAON Q-net (``connrl.nets.recurrent``). Lessons store raw
  sensations; a lesson is replayed in *batch mode* (7.5): the Q-values of the whole trial are computed
  from a zero context with the weights as they are, the TD(lambda) returns are computed backward
  (``connrl.core.replay.batch_targets``, lambda cut at non-policy actions), and one BPTT step is made on the
  trial with the non-policy steps weighted 0 (not replayed, 3.5.1).
- **Recurrent-model** (7.3, Fig. 7.1c): a recurrent OAON *action model* predicts the next sensation and the
  payoff; its context units, together with the current sensation, are the input of a feed-forward OAON
  Q-net. The model is trained in batch mode (BPTT) on lessons drawn from *all* past experience (7.5 fn. 2);
  the Q-net by incremental replay of the latest lessons. Lessons store raw sensations and the contexts are
  recomputed by the current model when a lesson is replayed, because the model's history features change
  as it learns (the instability 7.5.2 describes).

Context units are reset to 0 at the start of every trial, learning and test alike (7.4). Every agent's
``act`` takes ``force=a`` to execute a given action instead of its choice while updating its memory as if it
had chosen it: the interruption of the robustness probe of 7.5.1.

On-line learning: the thesis says the recurrent nets are trained in batch mode "to avoid possible
instability" (7.5); recurrent-Q therefore learns only by replay after each trial. Window-Q and the
recurrent-model's feed-forward Q-net also learn on-line from each step (Fig. 3.4) when ``online`` is set.

Values marked (R) are reconstructions; docs/RECONSTRUCTION.md, "Learners and protocols", gives each with its reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.agents.base import LessonAgent, ReplayConfig
from connrl.agents.qcon import QCON, QCONConfig
from connrl.core.exploration import TemperatureSchedule, boltzmann_select
from connrl.core.lessons import Lesson
from connrl.core.replay import ReplayParams, batch_targets, replay_q, replay_q_lessons
from connrl.nets import OAON, NetConfig
from connrl.nets.recurrent import RecurrentNetConfig, RecurrentOAON, check_sequence

ON, OFF = 0.5, -0.5  # binary input encoding (5.3.2)


def _select(agent, merits: np.ndarray, info, greedy: bool, force: int | None) -> int:
    """Boltzmann choice (3.4); ``force`` overrides the choice (robustness probe) after the same draw."""
    a, agent.last_probabilities = boltzmann_select(merits, agent.temperature(info, greedy), agent.rng)
    if force is not None:
        if not 0 <= int(force) < agent.n_actions:
            raise ValueError(f"force must be an action in [0, {agent.n_actions}), got {force!r}")
        a = int(force)
    return a


def _raw(obs) -> np.ndarray:
    return np.asarray(obs, dtype=np.float64).ravel()


# ------------------------------------------------------------------------------------------- window-Q

def window_input_size(n_sensation: int, n_actions: int, window: int) -> int:
    """Input units of window-Q: current sensation + N sensations + N one-hot actions (7.3)."""
    return n_sensation * (window + 1) + n_actions * window


class SensationWindow:
    """The N latest sensations and actions (7.3), newest first.

    ``encode(s)`` is ``[s, s_{t-1}, .., s_{t-N}, a_{t-1}, .., a_{t-N}]``; an action is one-hot in +-0.5
    (5.3.2). Slots before the start of the trial hold 0 (neither on nor off).
    """

    def __init__(self, n_sensation: int, n_actions: int, window: int):
        if window < 1:
            raise ValueError(f"window size N must be >= 1 (Table B.1: 5 for cups, 1 for the pole), got {window}")
        self.n_sensation, self.n_actions, self.window = n_sensation, n_actions, window
        self.sensations = np.zeros((window, n_sensation))
        self.actions = np.zeros((window, n_actions))

    def reset(self) -> None:
        self.sensations[:] = 0.0
        self.actions[:] = 0.0

    def push(self, sensation: np.ndarray, action: int) -> None:
        """Shift in the sensation just left and the action taken there."""
        self.sensations[1:] = self.sensations[:-1]
        self.actions[1:] = self.actions[:-1]
        self.sensations[0] = sensation
        self.actions[0] = OFF
        self.actions[0, action] = ON

    def encode(self, sensation: np.ndarray) -> np.ndarray:
        return np.concatenate([sensation, self.sensations.ravel(), self.actions.ravel()])


class WindowQ(QCON):
    """Window-Q (7.3, Fig. 7.1a): QCON on the current sensation plus the N latest sensations and actions.

    ``config.net.n_inputs`` must be ``window_input_size(n_sensation, n_actions, window)``.
    """

    def __init__(self, config: QCONConfig, n_actions: int, rng: np.random.Generator, *, n_sensation: int,
                 window: int):
        expected = window_input_size(n_sensation, n_actions, window)
        if config.net.n_inputs != expected:
            raise ValueError(f"window-Q with {n_sensation} sensation bits, {n_actions} actions and N={window} "
                             f"needs net.n_inputs={expected}, got {config.net.n_inputs}")
        super().__init__(config, n_actions, rng)
        self.memory = SensationWindow(n_sensation, n_actions, window)
        self._last_obs: np.ndarray | None = None
        self._last_action: int | None = None

    def encode(self, obs) -> np.ndarray:
        return self.memory.encode(_raw(obs))

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        self.memory.reset()
        self._last_obs, self._last_action = _raw(obs), None
        super().begin_trial(obs, info, trial=trial, learning=learning)

    def act(self, obs, info=None, *, greedy: bool = False, force: int | None = None) -> int:
        if not self.learning:  # no observe() in tests: shift the window here
            if self._last_action is not None:
                self.memory.push(self._last_obs, self._last_action)
            self._x = self.encode(obs)
        a = _select(self, self.q.values(self._x), info, greedy, force)
        self._last_obs, self._last_action = _raw(obs), a
        return a

    def observe(self, action, reward, next_obs, terminated, truncated, info=None) -> None:
        self.memory.push(self._last_obs, int(action))
        self._last_action = None  # already in the window
        super().observe(action, reward, next_obs, terminated, truncated, info)  # encodes next_obs


# ----------------------------------------------------------------------------------------- recurrent-Q

def replay_recurrent_q(net: RecurrentOAON, lesson: Lesson, params: ReplayParams, weights: np.ndarray | None = None,
                       allowed: np.ndarray | None = None, fast: bool = True) -> int:
    """Replay one lesson into a recurrent Q-net: one batch BPTT step; returns the experiences used. ``weights`` and
    ``allowed`` as ``batch_targets``'s (Ch. 8's choice over behaviours). The whole lesson is one compiled call
    (``RecurrentOAON.replay_q_lesson``, the same arithmetic) unless ``fast`` is False: then the readable composition
    below."""
    if fast:
        return net.replay_q_lesson(lesson.inputs, lesson.actions, lesson.rewards, lesson.terminated,
                                   gamma=params.gamma, lam=params.lam, temperature=params.temperature,
                                   p_threshold=params.p_threshold, clip=params.clip, weights=weights, allowed=allowed)
    acts_ext = np.append(lesson.actions, 0)  # the action at x_n does not affect the outputs at x_n
    ys, _ = net.forward_sequence(lesson.inputs, acts_ext)
    targets, policy = batch_targets(ys[:, :, 0], lesson.actions, lesson.rewards, lesson.terminated, params,
                                    weights, allowed)
    if policy.any():  # weight 0: a non-policy action is not replayed
        net.train_sequence(lesson.inputs[:-1], lesson.actions, targets, policy.astype(np.float64))
    return int(policy.sum())


def replay_recurrent_q_lessons(net: RecurrentOAON, lessons: list[Lesson], thresholds: list[float],
                               params: ReplayParams, options) -> int:
    """``replay_recurrent_q`` (compiled) on each of ``lessons`` in turn, lesson k at P_t ``thresholds[k]`` and with
    ``options(lesson)`` = its (weights, allowed), in one compiled call (issue 45)."""
    return net.replay_q_lessons(lessons, thresholds, options, gamma=params.gamma, lam=params.lam,
                                temperature=params.temperature, clip=params.clip)


@dataclass(frozen=True)
class RecurrentQConfig:
    """Recurrent-Q (7.3, Fig. 7.1b); Table B.1 gives the thesis's values."""

    net: RecurrentNetConfig  # recurrent Q-net, n_outputs = 1 (Table B.1: C_q, H_q, eta_q)
    temperature: TemperatureSchedule  # Boltzmann temperature over trials (Table B.1: 1/T 5 -> 30)
    gamma: float = 0.9  # discount factor (App. B)
    lam: float = 0.8  # TD(lambda) recency factor (Table B.1)
    replay: ReplayConfig = ReplayConfig(capacity=70, p_threshold=0.01, p_threshold_oldest=1e-5,
                                        batch=True)  # latest 70 trials, P_l 0.01..0.00001 (7.5, App. B)
    target_clip: float | None = None  # truncate Q targets above this value (4.2.4); unused in Ch. 7

    def __post_init__(self):
        if self.net.n_outputs != 1:
            raise ValueError(f"a recurrent Q-net has one output per action net, got n_outputs={self.net.n_outputs}")
        if not 0 <= self.gamma <= 1 or not 0 <= self.lam <= 1:
            raise ValueError(f"gamma and lam must be in [0, 1], got {self.gamma}, {self.lam}")
        if self.replay is None:
            raise ValueError("recurrent-Q learns only by replay (7.5): replay must be set")


class RecurrentQ(LessonAgent):
    """Recurrent-Q: the Q-function is a recurrent OAON; learning is batch replay after each trial (7.5)."""

    def __init__(self, config: RecurrentQConfig, n_actions: int, rng: np.random.Generator, *,
                 merit_scale: float = 1.0):
        super().__init__(config, n_actions, rng, merit_scale=merit_scale, batch=True)  # batch replay only (7.5)
        self.net = RecurrentOAON(config.net, n_actions, rng)

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        self.net.reset()
        super().begin_trial(obs, info, trial=trial, learning=learning)

    def act(self, obs, info=None, *, greedy: bool = False, force: int | None = None) -> int:
        self._x = _raw(obs)
        q = self.net.values(self._x)
        a = _select(self, q, info, greedy, force)
        self.net.advance(a)  # the taken action's net makes the next context (7.4)
        return a

    def observe(self, action, reward, next_obs, terminated, truncated, info=None) -> None:
        self.book.recorder.add(self._x, int(action), float(reward), _raw(next_obs))
        self.book.ended = (bool(terminated), bool(truncated))

    def replay_lesson(self, lesson: Lesson, p_threshold: float) -> None:
        replay_recurrent_q(self.net, lesson, self.replay_params(p_threshold))

    one_call_reproduces = (replay_lesson,)  # replay_lessons' one call does its work

    def replay_in_one_call(self, lessons: list[Lesson], thresholds: list[float], params: ReplayParams) -> None:
        replay_recurrent_q_lessons(self.net, lessons, thresholds, params, self.lesson_options)


# ------------------------------------------------------------------------------------- recurrent-model

def model_targets(lesson: Lesson, payoff_scale: float) -> np.ndarray:
    """(n, d+1) targets of the action model on a lesson: the next sensation and the scaled payoff (7.3)."""
    return np.hstack([lesson.inputs[1:], payoff_scale * lesson.rewards[:, None]])


@dataclass(frozen=True)
class RecurrentModelConfig:
    """Recurrent-model (7.3, Fig. 7.1c); Table B.1 gives the thesis's values."""

    model: RecurrentNetConfig  # action model, n_outputs = sensation + 1 payoff (Table B.1: C_m, H_m, eta_m)
    q_net: NetConfig  # feed-forward Q-nets on [sensation, context], n_inputs = sensation + C_m (H_q, eta_q)
    temperature: TemperatureSchedule  # Boltzmann temperature over trials (Table B.1: 1/T 5 -> 30)
    gamma: float = 0.9  # discount factor (App. B)
    lam: float = 0.8  # TD(lambda) recency factor (Table B.1)
    online: bool = True  # the feed-forward Q-net also learns from each step (Fig. 3.4)
    replay: ReplayConfig = ReplayConfig(capacity=70, p_threshold=0.01,
                                        p_threshold_oldest=1e-5)  # Q replay: latest 70 trials (7.5, App. B)
    model_lessons_per_trial: int = 20  # model BPTT passes per trial, lessons from all past trials (7.5 fn. 2) (R)
    payoff_scale: float = 0.5  # the model's payoff output is trained on payoff_scale * r (fits +-0.5 bits) (R)
    target_clip: float | None = None  # truncate Q targets above this value (4.2.4); unused in Ch. 7

    def __post_init__(self):
        n_sens = self.model.n_outputs - 1
        if n_sens < 1 or self.model.n_inputs != n_sens:
            raise ValueError(f"the action model maps a sensation of {self.model.n_inputs} units to the next "
                             f"sensation + payoff: n_outputs must be {self.model.n_inputs + 1}, "
                             f"got {self.model.n_outputs}")
        if self.q_net.n_inputs != self.model.n_inputs + self.model.n_context:
            raise ValueError(f"the Q-net input is sensation + context: n_inputs must be "
                             f"{self.model.n_inputs + self.model.n_context}, got {self.q_net.n_inputs}")
        if not 0 <= self.gamma <= 1 or not 0 <= self.lam <= 1:
            raise ValueError(f"gamma and lam must be in [0, 1], got {self.gamma}, {self.lam}")
        if self.model_lessons_per_trial < 0:
            raise ValueError(f"model_lessons_per_trial must be >= 0, got {self.model_lessons_per_trial}")


class RecurrentModelQ(LessonAgent):
    """Recurrent-model: a recurrent action model supplies history features to a feed-forward Q-net."""

    def __init__(self, config: RecurrentModelConfig, n_actions: int, rng: np.random.Generator):
        super().__init__(config, n_actions, rng)  # the book keeps raw lessons; the latest 70 go to the Q-net
        self.model = RecurrentOAON(config.model, n_actions, rng)
        self.q = OAON(config.q_net, n_actions, rng)
        self.history: list[Lesson] = []  # all past lessons: the model trains on them (7.5 fn. 2)
        self.freeze_model = False  # 7.5.2: "I fixed the model at some point of learning"
        self.track_model_error = False  # measure the model on each new lesson (7.5.1; off: it costs a pass)
        self.last_model_error: dict[str, float] | None = None  # on the latest lesson, before training on it
        self._checked: dict[int, tuple] = {}  # id(lesson) -> the lesson and its arrays as the kernels take them
        self._packed: dict = {"lessons": [], "rows": 0, "arrays": None, "starts": [0]}  # _packed_history's
        self._xq: np.ndarray | None = None

    def q_input(self, sensation: np.ndarray) -> np.ndarray:
        """Q-net input: the current sensation and the model's context units (Fig. 7.1c)."""
        return np.concatenate([sensation, self.model.context])

    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = True) -> None:
        self.model.reset()
        super().begin_trial(obs, info, trial=trial, learning=learning)

    def act(self, obs, info=None, *, greedy: bool = False, force: int | None = None) -> int:
        self._x = _raw(obs)
        self._xq = self.q_input(self._x)
        q = self.q.values(self._xq)
        a = _select(self, q, info, greedy, force)
        self.model.step(self._x, a)  # the model is told the action and moves its context on
        return a

    def observe(self, action, reward, next_obs, terminated, truncated, info=None) -> None:
        y = _raw(next_obs)
        if self.config.online:  # Fig. 3.4 steps 4-5
            u = 0.0 if terminated else float(self.q.values(self.q_input(y)).max())
            self.q.update(self._xq, int(action), self.online_target(reward, u))
        self.book.recorder.add(self._x, int(action), float(reward), y)
        self.book.ended = (bool(terminated), bool(truncated))

    def end_trial(self) -> Lesson | None:
        lesson = super().end_trial()
        if lesson is not None:
            self.history.append(lesson)
        return lesson

    def train_model(self) -> float:
        """BPTT passes on lessons from all past trials: the latest, then uniform draws; returns mean loss."""
        k = self.config.model_lessons_per_trial
        if not self.history or k == 0 or self.freeze_model:
            return 0.0
        picks = [len(self.history) - 1] + list(self.rng.integers(0, len(self.history), k - 1))
        return self.model.train_lessons(self._packed_history(), picks) / len(picks)

    def _packed_history(self) -> tuple[np.ndarray, ...]:
        """The past lessons laid end to end as ``RecurrentOAON.train_lessons`` takes them, extended as lessons are
        added (built anew if the history was replaced)."""
        packed, history, n = self._packed, self.history, len(self._packed["lessons"])
        if n > len(history) or any(a is not b for a, b in zip(packed["lessons"], history[:n], strict=True)):
            packed = self._packed = {"lessons": [], "rows": 0, "arrays": None, "starts": [0]}
        for lesson in history[len(packed["lessons"]):]:
            parts, rows = self._arrays(lesson)[:4], len(lesson)
            if packed["arrays"] is None or packed["rows"] + rows > len(packed["arrays"][0]):  # room for twice as many
                size = 2 * (packed["rows"] + rows)
                grown = tuple(np.empty((size, *a.shape[1:]), a.dtype) for a in parts)
                for new, old in zip(grown, packed["arrays"] or (), strict=False):
                    new[:packed["rows"]] = old[:packed["rows"]]
                packed["arrays"] = grown
            for buffer, a in zip(packed["arrays"], parts, strict=True):
                buffer[packed["rows"]:packed["rows"] + rows] = a
            packed["rows"] += rows
            packed["lessons"].append(lesson)
            packed["starts"].append(packed["rows"])
        return (*packed["arrays"], np.array(packed["starts"], dtype=np.int64))

    def _arrays(self, lesson: Lesson) -> tuple[np.ndarray, ...]:
        """A past lesson as the model's kernels take it, checked and computed once (it is replayed many times):
        (x_0..x_{n-1}, actions, model targets, ones, x_0..x_n, the actions and a last 0)."""
        got = self._checked.get(id(lesson))
        if got is None or got[0] is not lesson:
            c = self.config.model
            xs, acts, targets, ones = check_sequence(lesson.inputs[:-1], lesson.actions,
                                                     model_targets(lesson, self.config.payoff_scale), None,
                                                     c.n_inputs, self.model.n_nets, c.n_outputs)
            whole, acts_ext, _, _ = check_sequence(lesson.inputs, np.append(lesson.actions, 0), None, None, c.n_inputs,
                                                   self.model.n_nets, c.n_outputs)
            got = self._checked[id(lesson)] = (lesson, xs, acts, targets, ones, whole, acts_ext)
        return got[1:]

    def q_lesson(self, lesson: Lesson) -> Lesson:
        """The lesson with Q-net inputs ``[x_t, c_t]``, contexts recomputed by the current model."""
        _, cs = self.model.forward_checked(*self._arrays(lesson)[4:])
        return Lesson(np.concatenate((lesson.inputs, cs[:-1]), axis=1), lesson.actions, lesson.rewards,
                      terminated=lesson.terminated, truncated=lesson.truncated, taught=lesson.taught)

    def _predictions(self, lesson: Lesson) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(the taken action's model outputs, their targets, which sensation bits are wrong) per step."""
        ys, _ = self.model.forward_sequence(lesson.inputs[:-1], lesson.actions)
        pred = ys[np.arange(lesson.actions.size), lesson.actions]
        target = model_targets(lesson, self.config.payoff_scale)
        return pred, target, (pred[:, :-1] > 0) != (target[:, :-1] > 0)

    def wrong_steps(self, lesson: Lesson) -> np.ndarray:
        """Per step, whether the model gets some bit of the next sensation wrong (no training)."""
        return self._predictions(lesson)[2].any(axis=1)

    def model_error(self, lesson: Lesson) -> dict[str, float]:
        """How well the model predicts a lesson (7.5.1), measured without training: the share of steps whose
        next sensation it gets wrong in any bit (sign of the output against the +-0.5 bit), the share of wrong
        bits, and the mean absolute payoff error."""
        pred, target, wrong = self._predictions(lesson)
        return {"model_wrong_steps": float(wrong.any(axis=1).mean()), "model_wrong_bits": float(wrong.mean()),
                "model_payoff_error": float(np.abs(pred[:, -1] - target[:, -1]).mean() / self.config.payoff_scale)}

    def learn(self) -> None:
        """After a trial: train the model, then replay the latest lessons into the Q-net (7.5). With
        ``track_model_error``, the model's error on the new lesson, before it learns from it, is kept in
        ``last_model_error``."""
        if not self.learning:
            return
        if self.track_model_error and self.history:
            self.last_model_error = self.model_error(self.history[-1])
        self.train_model()
        super().learn()

    def replay_lesson(self, lesson: Lesson, p_threshold: float) -> None:
        replay_q(self.q, self.q_lesson(lesson), self.replay_params(p_threshold))

    one_call_reproduces = (replay_lesson,)  # replay_lessons' one call does its work

    def replay_in_one_call(self, lessons: list[Lesson], thresholds: list[float], params: ReplayParams) -> None:
        """One pass of the model over each distinct lesson: the model does not change while the Q-net replays, so a
        lesson drawn twice has the same Q-net inputs both times."""
        made: dict[int, Lesson] = {}
        for lesson in lessons:
            if id(lesson) not in made:
                made[id(lesson)] = self.q_lesson(lesson)
        replay_q_lessons(self.q, [made[id(x)] for x in lessons], thresholds, params, self.lesson_options)
