"""The survival task's action models for AHCON-M and QCON-M (4.2.5); planning itself is ``connrl.core.planning``.

* :class:`PerfectSurvivalModel` — the "perfect" model of 4.2.5: the simulator itself, stepped from a copy of
  the true state with its own random enemy moves.
* :class:`LearnedSurvivalModel` — the learned model of 4.2.5: single-layer *reinforcement nets* on all 145
  inputs and *enemy nets* on the enemy and obstacle maps that predict each enemy sensor after the move,
  trained on-line from a bounded queue of experiences. As in the thesis, food, obstacle, energy and history
  units are not learned ("quite easy to predict"): they come from the simulator.

Values marked (R) are reconstructions; docs/RECONSTRUCTION.md, "Learners and protocols", gives each with its reason.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba
import numpy as np

from connrl.envs.survival import ACTION_ROTATION, N_INPUTS, ROTATION_PERMUTATIONS, SurvivalEnv, scripted_teacher_action


class PerfectSurvivalModel:
    """The "perfect" model of 4.2.5: a scratch copy of the simulator set to the live env's true state.

    Enemy moves of a simulated step are drawn from the scratch env's own generator, so the model samples
    the real outcome distribution without disturbing the live play's random stream.
    """

    def __init__(self, env, rng: np.random.Generator):
        self.env = env
        self.scratch = SurvivalEnv(action_representation=env.action_representation)
        self.scratch.reset(seed=int(rng.integers(2**31 - 1)))

    def steps_from(self, state: dict, actions):
        """(y, r, terminated, info) of each action taken from ``state``: the state is checked and set once, then
        restored from the scratch env's own arrays before each further action (issue 45: as ``set_state`` leaves
        them, without its checks)."""
        self.scratch.set_state(state)
        snapshot = self.scratch._snapshot()
        for k, a in enumerate(actions):
            if k:
                self.scratch._restore(snapshot)
            y, r, terminated, _, info = self.scratch.step(int(a))
            yield y, r, terminated, info

    def simulate(self, x: np.ndarray, actions) -> list[tuple[np.ndarray, float, bool]]:
        return [(y, float(r), bool(terminated))
                for y, r, terminated, _ in self.steps_from(self.env.get_state(), actions)]


@numba.njit(cache=True, fastmath=True)
def _single_layer(w, x, lo, hi, out):
    """out[k] = f(w[k] . [x[lo:hi], 1]) with the symmetric sigmoid f (range +-0.5)."""
    n = hi - lo
    for k in range(w.shape[0]):
        s = w[k, n]
        for i in range(n):
            s += w[k, i] * x[lo + i]
        out[k] = 1.0 / (1.0 + math.exp(-s)) - 0.5


@numba.njit(cache=True, fastmath=True)
def _single_layer_train(w, d, x, lo, hi, target, scale, lr, momentum, out):
    """One momentum step of every unit toward target/scale (delta rule through f); out gets f before."""
    n = hi - lo
    _single_layer(w, x, lo, hi, out)
    for k in range(w.shape[0]):
        delta = (target[k] / scale - out[k]) * (0.25 - out[k] * out[k])
        for i in range(n):
            s = lr * delta * x[lo + i] + momentum * d[k, i]
            d[k, i] = s
            w[k, i] += s
        s = lr * delta + momentum * d[k, n]
        d[k, n] = s
        w[k, n] += s


@numba.njit(cache=True)
def _predict(w_r, w_e, x, perm, start, lo, hi, xr, out_r, out_e, enemy):
    """``LearnedSurvivalModel.predict`` whole: the input rotated by ``perm`` (4.2.4), the reinforcement net on all of
    it (from ``start``, 0, an argument: as a constant, LLVM would compile the fastmath sum inlined here in another
    order) and the enemy nets on the maps ``lo:hi``; ``enemy`` gets the most likely enemy units of y in the world's
    frame (unit i of the rotated map is unit perm[52 + i] of y). Returns the predicted r (the net's range is +-1)."""
    for i in range(perm.size):
        xr[i] = x[perm[i]]
    _single_layer(w_r, xr, start, xr.shape[0], out_r)
    _single_layer(w_e, xr, lo, hi, out_e)
    for i in range(32):
        enemy[perm[52 + i] - 52] = 0.5 if out_e[i] > 0 else -0.5
    return 2.0 * out_r[0]


@numba.njit(cache=True)
def _train_row(w_r, d_r, w_e, d_e, row, perm, start, lo, hi, lr, momentum, xr, yr, out_r, out_e):
    """``LearnedSurvivalModel._train`` of one queued experience (x, y, a, r): both nets one momentum step toward r
    and the rotated next enemy units (``start`` 0, as ``_predict``'s)."""
    n_in = perm.size
    for i in range(n_in):
        xr[i] = row[perm[i]]
        yr[i] = row[n_in + perm[i]]
    _single_layer_train(w_r, d_r, xr, start, n_in, row[-1:], 2.0, lr, momentum, out_r)
    _single_layer_train(w_e, d_e, xr, lo, hi, yr[52:84], 1.0, lr, momentum, out_e)


@numba.njit(cache=True)
def _wrong_share(enemy, actual):
    """``float(np.mean(enemy != actual))``: the share of enemy units predicted wrong (a count over 32, exact)."""
    wrong = 0
    for i in range(enemy.size):
        wrong += enemy[i] != actual[i]
    return wrong / enemy.size


@dataclass(frozen=True)
class LearnedModelConfig:
    """The learned survival model (4.2.5); the thesis gives its structure, not these constants (R)."""

    lr: float = 0.01  # learning rate of the single-layer nets (R; scripts/ch4/model_probe.py, issue 31: at 0.1 the
    # reinforcement net, 145 inputs of +-0.5 with momentum 0.9, overshoots and predicts worse than 0)
    momentum: float = 0.9  # as every net of Ch. 4 (4.3.1)
    init_range: float = 0.1  # as every net of Ch. 4 (4.3.1)
    queue: int = 2000  # experiences kept for repeated presentation (4.2.5: "a queue of limited length") (R)
    replays: int = 3  # queued experiences presented after each new one (R)
    death_threshold: float = -0.5  # a predicted reinforcement below this ends the simulated play (R)


class LearnedSurvivalModel:
    """The learned action model of 4.2.5 for the survival task.

    * reinforcement nets: single layer, all 145 inputs -> r (range +-1);
    * enemy nets: single layer, the enemy + obstacle maps (72 inputs) -> each of the 32 enemy sensors
      after the move (range +-0.5, the observation's own units); the most likely outcome (sign) is used.

    Under the global representation one reinforcement net and one enemy net (for "north") serve all four
    actions through the input rotations of 4.2.4; under the local one there is one of each per action.
    Food, obstacle, energy and history units of the predicted state come from the simulator stepped from
    the true state, as in the thesis, which did not make the agents learn them.
    """

    ENEMY, MAPS = slice(52, 84), (52, 124)  # enemy units; enemy + obstacle maps (inputs of the enemy nets)

    def __init__(self, env, rng: np.random.Generator, config: LearnedModelConfig = LearnedModelConfig()):
        self.config = config
        self.rng = rng
        self.sim = PerfectSurvivalModel(env, rng)
        self.global_ = env.action_representation == "global"
        if self.global_:
            self.perms = np.stack([ROTATION_PERMUTATIONS[ACTION_ROTATION[a]] for a in range(4)])
        else:
            self.perms = np.tile(np.arange(N_INPUTS), (4, 1))
        n_models = 1 if self.global_ else 4
        r = config.init_range
        self.w_r = rng.uniform(-r, r, (n_models, 1, N_INPUTS + 1))
        self.w_e = rng.uniform(-r, r, (n_models, 32, 72 + 1))
        self.d_r, self.d_e = np.zeros_like(self.w_r), np.zeros_like(self.w_e)
        self._q = np.zeros((config.queue, 2 * N_INPUTS + 2))  # rows: x, y, a, r
        self._n = 0
        self._out_r, self._out_e = np.empty(1), np.empty(32)
        self._xr, self._yr = np.empty(N_INPUTS), np.empty(N_INPUTS)  # an input and a next input, rotated
        self.errors = self._no_errors()  # prediction errors before training

    @staticmethod
    def _no_errors() -> dict:
        return {"reward_abs": 0.0, "reward_sq": 0.0, "enemy_bits": 0.0, "n": 0}

    def _net(self, a: int) -> int:
        return 0 if self.global_ else int(a)

    def predict(self, x: np.ndarray, a: int) -> tuple[float, np.ndarray]:
        """(predicted r, predicted enemy units of y) for action a from input x."""
        m, enemy = self._net(a), np.empty(32)
        r = _predict(self.w_r[m], self.w_e[m], np.ascontiguousarray(x, dtype=np.float64), self.perms[a], 0,
                     self.MAPS[0], self.MAPS[1], self._xr, self._out_r, self._out_e, enemy)
        return r, enemy

    def simulate(self, x: np.ndarray, actions) -> list[tuple[np.ndarray, float, bool]]:
        out = []
        for a, (y, _, _, info) in zip(actions, self.sim.steps_from(self.sim.env.get_state(), actions), strict=True):
            r, enemy = self.predict(x, int(a))
            y = y.copy()
            y[self.ENEMY] = enemy
            terminal = r < self.config.death_threshold or info["outcome"] == "all_food"
            out.append((y, r, bool(terminal)))
        return out

    def _train(self, row: np.ndarray) -> None:
        a, c = int(row[-2]), self.config
        m = self._net(a)
        _train_row(self.w_r[m], self.d_r[m], self.w_e[m], self.d_e[m], row, self.perms[a], 0, self.MAPS[0],
                   self.MAPS[1], c.lr, c.momentum, self._xr, self._yr, self._out_r, self._out_e)

    def learn(self, x, a, r, y, terminated) -> None:
        """Present a real experience, then ``replays`` random ones from the queue (4.2.5)."""
        n_in = x.shape[0]
        row = np.empty(2 * n_in + 2)
        row[:n_in], row[n_in:2 * n_in], row[-2], row[-1] = x, y, a, r
        # prediction error before learning (the model's accuracy over time, 4.4.3)
        reward_abs, enemy_bits = self.prediction_error(x, a, r, y)
        self.errors["reward_abs"] += reward_abs
        self.errors["reward_sq"] += reward_abs ** 2
        self.errors["enemy_bits"] += enemy_bits
        self.errors["n"] += 1
        self._train(row)
        cap = self._q.shape[0]
        self._q[self._n % cap] = row
        self._n += 1
        size = min(self._n, cap)
        for i in self.rng.integers(size, size=self.config.replays):
            self._train(self._q[i])

    def prediction_error(self, x, a, r, y) -> tuple[float, float]:
        """(|predicted r - r|, fraction of the 32 enemy units of y predicted wrong) for one experience."""
        pr, enemy = self.predict(x, int(a))
        return abs(pr - r), _wrong_share(enemy, np.ascontiguousarray(y[self.ENEMY], dtype=np.float64))

    def probe_errors(self, probes) -> dict[str, float]:
        """Mean prediction errors on fixed experiences (``probe_experiences``), without learning from them: the
        model's accuracy on a yardstick that does not move with the agent's behaviour."""
        errs = np.array([self.prediction_error(x, a, r, y) for x, a, r, y in probes])
        return {"probe_reward_abs": float(errs[:, 0].mean()), "probe_reward_sq": float(np.mean(errs[:, 0] ** 2)),
                "probe_enemy_bits": float(errs[:, 1].mean())}

    def pop_errors(self) -> dict[str, float]:
        """Mean prediction errors since the last call (absolute and squared reward error, fraction of wrong enemy
        bits)."""
        n = max(self.errors["n"], 1)
        out = {k: v / n for k, v in self.errors.items() if k != "n"}
        self.errors = self._no_errors()
        return out


@functools.lru_cache(maxsize=4)  # the same yardstick for every run a worker process makes
def probe_experiences(representation: str, seed: int, n: int, random_share: float = 0.5) -> tuple[tuple, ...]:
    """``n`` experiences (x, a, r, y) of a fixed policy: the scripted teacher's action, or with probability
    ``random_share`` a random one (so bad moves and deaths are in it too). Fresh plays on random layouts from
    ``seed`` alone: a yardstick for a learned model that leaves a run's own random stream untouched."""
    env = SurvivalEnv(representation)
    rng = np.random.default_rng(seed)
    x, _ = env.reset(seed=int(rng.integers(2**31 - 1)))
    out = []
    while len(out) < n:
        a = int(rng.integers(4)) if rng.random() < random_share else scripted_teacher_action(env)
        y, r, terminated, truncated, _ = env.step(a)
        out.append((x, a, float(r), y))
        x = env.reset(seed=int(rng.integers(2**31 - 1)))[0] if terminated or truncated else y
    return tuple(out)
