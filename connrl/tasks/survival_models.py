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

    def _step_from(self, state: dict, a: int):
        self.scratch.set_state(state)
        y, r, terminated, _, info = self.scratch.step(int(a))
        return y, r, terminated, info

    def simulate(self, x: np.ndarray, actions) -> list[tuple[np.ndarray, float, bool]]:
        state = self.env.get_state()
        out = []
        for a in actions:
            y, r, terminated, _ = self._step_from(state, a)
            out.append((y, float(r), bool(terminated)))
        return out


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
        self.errors = self._no_errors()  # prediction errors before training

    @staticmethod
    def _no_errors() -> dict:
        return {"reward_abs": 0.0, "reward_sq": 0.0, "enemy_bits": 0.0, "n": 0}

    def _net(self, a: int) -> int:
        return 0 if self.global_ else int(a)

    def predict(self, x: np.ndarray, a: int) -> tuple[float, np.ndarray]:
        """(predicted r, predicted enemy units of y) for action a from input x."""
        xr = np.ascontiguousarray(x[self.perms[a]])
        m = self._net(a)
        _single_layer(self.w_r[m], xr, 0, xr.shape[0], self._out_r)
        _single_layer(self.w_e[m], xr, self.MAPS[0], self.MAPS[1], self._out_e)
        enemy = np.empty(32)
        # the nets work in the rotated frame; unit i of the rotated map is unit perms[a][52 + i] of y
        enemy[self.perms[a][52:84] - 52] = np.where(self._out_e > 0, 0.5, -0.5)
        return 2.0 * float(self._out_r[0]), enemy

    def simulate(self, x: np.ndarray, actions) -> list[tuple[np.ndarray, float, bool]]:
        state = self.sim.env.get_state()
        out = []
        for a in actions:
            y, _, _, info = self.sim._step_from(state, a)
            r, enemy = self.predict(x, int(a))
            y = y.copy()
            y[self.ENEMY] = enemy
            terminal = r < self.config.death_threshold or info["outcome"] == "all_food"
            out.append((y, r, bool(terminal)))
        return out

    def _train(self, row: np.ndarray) -> None:
        n_in = (row.shape[0] - 2) // 2
        x, y, a, r = row[:n_in], row[n_in:2 * n_in], int(row[-2]), row[-1]
        perm = self.perms[a]
        xr, yr = np.ascontiguousarray(x[perm]), y[perm]
        m, c = self._net(a), self.config
        _single_layer_train(self.w_r[m], self.d_r[m], xr, 0, n_in, np.array([r]), 2.0, c.lr, c.momentum,
                            self._out_r)
        _single_layer_train(self.w_e[m], self.d_e[m], xr, self.MAPS[0], self.MAPS[1],
                            np.ascontiguousarray(yr[52:84]), 1.0, c.lr, c.momentum, self._out_e)

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
        return abs(pr - r), float(np.mean(enemy != y[self.ENEMY]))

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
