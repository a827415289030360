"""Issue 45's hot paths, before and after, timed in one run: each line times a reference the tests hold the new code
to and the code as it is, on the same inputs, and gives the ratio. The references are the code as it was, except
that the plain loops (replay, ``run_trial``) now call the nets' new values kernel: those lines measure what compiling
the loop adds on top of it.

    python benchmarks/bench_speedups.py [--repeat 3]

- rotated values (Ch. 4): the fastmath loop with a gathered read per input (tests/nets/test_rotated_kernel.py keeps
  it) against ``_rotated_values`` (vector lanes over a permuted copy);
- a rotated Q-net's and AHCON's lesson replay (Ch. 4): the plain loops ``replay_q_reference`` /
  ``replay_ahc_reference`` against the registered compiled paths;
- a greedy test play (Ch. 4): ``run_trial`` against ``connrl.tasks.survival_play.greedy_play``;
- Ch. 8's recurrent replay over behaviours (weights and allowed choices): ``batch_targets`` + ``train_sequence``
  against the one kernel;
- the recurrent nets' forward over a lesson (Chs. 7, 8): unit by unit (tests/nets/test_recurrent_lanes.py keeps it)
  against ``_forward_sequence`` (vector lanes over units);
- state grouping (Ch. 6): ``group_lesson``'s plain loops (``group_states_reference``,
  ``centres_and_rewards_reference``) against its compiled paths;
- Boltzmann selection at T > 0: ``boltzmann_probabilities`` + cumsum + searchsorted against ``boltzmann_select``;
- greedy test plays over behaviours (Chs. 6, 8) and of Ch. 5's tasks: ``run_trial`` against
  ``connrl.tasks.recharge_play.greedy_play`` and ``connrl.tasks.robot_play.greedy_play``;
- the MLP forward pass, 1000 times in a compiled loop: the fastmath loop (tests/nets/test_mlp_kernel.py keeps it)
  against ``_forward_at``, as the kernels call it;
- a lesson replay over behaviours: the kernel's step-by-step loop (``_replay_q_steps``, with the new forward pass)
  against ``_replay_mlp``, which reuses the policy test's forward pass; a trial's 1000 replays, ``replay_q`` on
  each against ``replay_q_lessons``;
- Ch. 4's training plays (QCON, AHCON, QCON-M with the perfect model, AHCON-M with the learned one, planning
  from the first play), 20 plays after 10: ``run_trial`` against ``connrl.tasks.survival_train.learning_play``, each
  batch from a copy of the agent and world (the copy's time in both);
- the sixth round: 20 training trials over behaviours (Ch. 6's QCON, Ch. 8's recurrent-Q) and 20 cup trials with
  their greedy tests (Ch. 7's three learners), ``run_trial`` (and ``hidden_state.test_score``) against
  ``recharge_train.learning_play`` and ``cup_play``; recurrent-model's 70 model passes of a trial,
  ``train_checked`` on each against ``train_lessons``.
Each time is the best of --repeat rounds.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import sys
from pathlib import Path

import numba
import numpy as np
from bench_core import best_time  # seconds per call, the best of `repeat` batches

from connrl.agents.memory import replay_recurrent_q
from connrl.core.exploration import boltzmann_probabilities, boltzmann_select
from connrl.core.grouping import group_lesson
from connrl.core.lessons import Lesson
from connrl.core.replay import (
    ReplayParams,
    replay_ahc,
    replay_ahc_reference,
    replay_q,
    replay_q_lessons,
    replay_q_reference,
)
from connrl.core.rollout import run_trial
from connrl.envs.robot.recharge import ROOMS, sample_in_room
from connrl.envs.survival import ACTION_ROTATION, ROTATION_PERMUTATIONS, SurvivalEnv
from connrl.experiments.hidden_state import CupParams
from connrl.experiments.integration import IntegrationParams
from connrl.experiments.recharge import RechargeParams
from connrl.experiments.robot import RobotParams
from connrl.nets import OAON, NetConfig
from connrl.nets.kernels import _forward_at, _forward_sequence, _replay_mlp, _replay_q_steps, _rotated_values
from connrl.nets.recurrent import RecurrentNetConfig, RecurrentOAON
from connrl.nets.rotated import RotatedNet
from connrl.tasks import cup_play, hidden_state, recharge_play, recharge_train, robot_play
from connrl.tasks.hidden_state import make_agent as make_memory_agent
from connrl.tasks.hidden_state import make_cup_envs
from connrl.tasks.integration import make_integration_agent, make_integration_env
from connrl.tasks.recharge import make_high_level_agent, make_recharge_env
from connrl.tasks.robot import make_agent, make_env
from connrl.tasks.survival import SurvivalAgentParams, make_survival_agent
from connrl.tasks.survival_play import greedy_play
from connrl.tasks.survival_train import learning_play

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests keep the code as it was
from tests.nets.test_mlp_kernel import _fastmath_forward  # noqa: E402  (the MLP forward as it was)
from tests.nets.test_recurrent_lanes import _forward_by_unit  # noqa: E402  (the recurrent forward as it was)
from tests.nets.test_rotated_kernel import _gathered_fastmath  # noqa: E402  (the kernel as it was)

PERMS = np.ascontiguousarray(ROTATION_PERMUTATIONS[list(ACTION_ROTATION)])


def rows(repeat: int) -> list[tuple[str, float, float]]:
    rng = np.random.default_rng(0)
    n_in = PERMS.shape[1]
    out = []
    # rotated values
    w1, w2 = rng.uniform(-0.1, 0.1, (1, 30, n_in + 1)), rng.uniform(-0.1, 0.1, (1, 31))
    x, q, xr = rng.choice([-0.5, 0.5], n_in), np.empty(4), np.empty(n_in)
    out.append(("rotated values, 145-30-1 x 4 rotations (Ch. 4)",
                best_time(lambda: _gathered_fastmath(w1, w2, x, PERMS, 1.0, q), 20000, repeat),
                best_time(lambda: _rotated_values(w1, w2, x, PERMS, 1.0, q, xr), 20000, repeat)))
    # lesson replay into Ch. 4's nets
    lesson = Lesson(rng.choice([-0.5, 0.5], (101, n_in)), rng.integers(0, 4, 100), rng.choice([0.0, 0.4], 100), True)
    params = ReplayParams(gamma=0.9, lam=0.0, temperature=0.05, p_threshold=0.01)
    net = RotatedNet(NetConfig(n_in, 30, lr=0.1), PERMS, np.random.default_rng(1))
    nets = [copy.deepcopy(net) for _ in range(2)]
    out.append(("QCON replay of a 100-step lesson, rotated net (Ch. 4)",
                best_time(lambda: replay_q_reference(nets[0], lesson, params), 20, repeat),
                best_time(lambda: replay_q(nets[1], lesson, params), 20, repeat)))
    v = OAON(NetConfig(n_in, 30, lr=0.1), 1, np.random.default_rng(2))
    pairs = [(copy.deepcopy(v), copy.deepcopy(net)) for _ in range(2)]
    out.append(("AHCON replay of a 100-step lesson, rotated policy net (Ch. 4)",
                best_time(lambda: replay_ahc_reference(*pairs[0], lesson, params), 20, repeat),
                best_time(lambda: replay_ahc(*pairs[1], lesson, params), 20, repeat)))
    # greedy test plays
    env = SurvivalEnv("global")
    agent = make_survival_agent(SurvivalAgentParams("QCON"), env, np.random.default_rng(3))
    for k in range(20):
        run_trial(env, agent, trial=k, learning=True, seed=k, options={"layout_seed": k})
    seeds = range(1000, 1020)
    out.append(("20 greedy test plays, QCON (Ch. 4)",
                best_time(lambda: [run_trial(env, agent, trial=0, learning=False, seed=k, options={"layout_seed": k})
                                 for k in seeds], 1, repeat),
                best_time(lambda: [greedy_play(env, agent, k) for k in seeds], 1, repeat)))
    return out + later_rows(repeat, rng)


def later_rows(repeat: int, rng) -> list[tuple[str, float, float]]:
    """Chs. 6-8's hot paths, and Boltzmann selection."""
    out = []
    # Ch. 8's recurrent replay over behaviours
    cfg = RecurrentNetConfig(16, 12, 8, 1, lr=0.05)
    rnets = [RecurrentOAON(cfg, 4, np.random.default_rng(4)) for _ in range(2)]
    n = 60
    rl = Lesson(rng.choice([-0.5, 0.5], (n + 1, 16)), rng.integers(0, 4, n), rng.choice([0.0, 1.0], n), True)
    w = rng.choice([1.0, 100.0], (n, 4))
    ok = rng.random((n + 1, 4)) < 0.7
    rp = ReplayParams(gamma=0.9, lam=0.8, temperature=0.05, p_threshold=0.01, batch=True)
    out.append(("recurrent replay of a 60-step lesson over 4 behaviours (Ch. 8)",
                best_time(lambda: replay_recurrent_q(rnets[0], rl, rp, w, ok, fast=False), 300, repeat),
                best_time(lambda: replay_recurrent_q(rnets[1], rl, rp, w, ok), 300, repeat)))
    # Ch. 7/8's recurrent forward over a lesson, every net (the replay's and the model's first pass)
    w1, w2 = rng.uniform(-0.6, 0.6, (4, 12, 23)), rng.uniform(-0.6, 0.6, (4, 1, 13))
    xs, acts = rng.normal(size=(160, 14)), rng.integers(0, 4, 160)
    ys, cs = np.empty((160, 4, 1)), np.empty((161, 8))
    out.append(("recurrent forward of a 160-step lesson, 4 nets of 14+8-12-1 (Ch. 7/8)",
                best_time(lambda: _forward_by_unit(w1, w2, xs, acts, 1.5, 200.0, ys, cs), 300, repeat),
                best_time(lambda: _forward_sequence(w1, w2, xs, acts, 1.5, 200.0, ys, cs), 300, repeat)))
    # Ch. 6's state grouping of a long lesson (a random walk, so groups of many sizes)
    walk = np.cumsum(rng.normal(0, 0.1, (567, 16)), axis=0)
    gl = Lesson(walk, np.repeat(rng.integers(0, 4, 566), 20)[:566], rng.normal(size=566), False)
    g0, g1 = np.random.default_rng(6), np.random.default_rng(6)
    out.append(("state grouping of a 566-step lesson of 16 inputs (Ch. 6, 6.6.4)",
                best_time(lambda: group_lesson(gl, 0.9, (0.25, 1.25), _PlainRng(g0)), 50, repeat),
                best_time(lambda: group_lesson(gl, 0.9, (0.25, 1.25), g1), 50, repeat)))
    # Boltzmann selection
    merits, g = rng.normal(size=4), np.random.default_rng(5)

    def plain():
        p = boltzmann_probabilities(merits, 0.05)
        return min(int(np.searchsorted(np.cumsum(p), g.random() * 1.0, side="right")), p.size - 1), p

    out.append(("Boltzmann selection of 4 actions at T = 0.05 (every training step)",
                best_time(plain, 50000, repeat), best_time(lambda: boltzmann_select(merits, 0.05, g), 50000, repeat)))
    return out + robot_rows(repeat)


def robot_rows(repeat: int) -> list[tuple[str, float, float]]:
    """The robot's greedy test plays: over behaviours (Chs. 6, 8), and Ch. 5's door passing."""
    p = dataclasses.replace(RechargeParams(), max_steps=1000, step_scale=0.2, success_reward=500.0, xy_scale=8.0)
    env, agent = make_recharge_env(p), make_high_level_agent(p, np.random.default_rng(3))  # Exp. 4's world (6.6.4)
    for k in range(5):
        run_trial(env, agent, trial=k, learning=True, seed=k)
    rng = np.random.default_rng(7)
    tasks = [(sample_in_room(rng, env.world.layout, ROOMS[k % 3]), int(rng.integers(2**31))) for k in range(6)]
    assert recharge_play.compiled(env, agent)
    out = [("6 greedy test plays over behaviours, fifth-size steps (Chs. 6, 8)",
            best_time(lambda: [run_trial(env, agent, trial=0, learning=False, seed=s, options={"start": start})
                               for start, s in tasks], 1, repeat),
            best_time(lambda: [recharge_play.greedy_play(env, agent, s, start) for start, s in tasks], 1, repeat))]
    p = RobotParams(task="DP")
    renv, ragent = make_env(p), make_agent(p, np.random.default_rng(4))
    assert robot_play.compiled(renv, ragent)
    starts = [(renv.sample_task(rng), int(rng.integers(2**31))) for _ in range(20)]
    out.append(("20 greedy test plays of DP, 30 steps at most (Ch. 5)",
                best_time(lambda: [run_trial(renv, ragent, trial=0, learning=False, seed=s, options={"start": start},
                                             max_steps=30) for start, s in starts], 1, repeat),
                best_time(lambda: [robot_play.greedy_play(renv, ragent, s, start, 30) for start, s in starts], 1,
                          repeat)))
    return out + mlp_rows(repeat, rng)


def mlp_rows(repeat: int, rng) -> list[tuple[str, float, float]]:
    """The fourth round: the MLP forward pass (its hidden sums in written-out lanes, all before the sigmoids), the
    lesson replay that reuses the policy test's forward pass, and a trial's replays in one call."""
    out = []
    for n_in, n_h, where in ((14, 8, "Ch. 8's nets over behaviours"), (101, 30, "Ch. 6 Exp. 1's flat nets")):
        w1, w2 = rng.uniform(-0.5, 0.5, (4, n_h, n_in + 1)), rng.uniform(-0.5, 0.5, (4, n_h + 1))
        x, h = rng.choice([-0.5, 0.0, 0.5], n_in), np.empty(n_h)
        out.append((f"1000 MLP forward passes, {n_in}-{n_h}-1, in a compiled loop ({where})",
                    best_time(lambda w1=w1, w2=w2, x=x, h=h: _old_forwards(w1, w2, x, h, 1000), 200, repeat),
                    best_time(lambda w1=w1, w2=w2, x=x, h=h: _new_forwards(w1, w2, x, h, 1000), 200, repeat)))
    cfg = NetConfig(14, 8, value_range=100.0, lr=0.001)
    nets = [OAON(cfg, 4, np.random.default_rng(8)) for _ in range(2)]
    n = 126
    lessons = [Lesson(rng.choice([-0.5, 0.0, 0.5], (n + 1, 14)), rng.integers(0, 4, n), rng.choice([0.0, 10.0], n),
                      False) for _ in range(100)]
    w, ok = np.ones((n, 4)), np.ones((n + 1, 4), dtype=np.bool_)

    def kernel(fn, net, lesson, *extra):
        return fn(net.w1, net.w2, net.d1, net.d2, net._h, np.empty(4), lesson.inputs, lesson.actions.astype(np.int64),
                  lesson.rewards, False, np.full(n, 0.99), 0.8, 2.0, 0.005, 0.0, False, net.scale, net.lr, 0.9,
                  *extra, w, ok)

    out.append(("replay of a 126-step lesson over 4 behaviours, P_t > 0: step by step / the forward pass reused",
                best_time(lambda: kernel(_replay_q_steps, nets[0], lessons[0], 0, False), 300, repeat),
                best_time(lambda: kernel(_replay_mlp, nets[1], lessons[0]), 300, repeat)))
    picks = [lessons[int(k)] for k in rng.integers(0, 100, 1000)]
    params = ReplayParams(gamma=0.99, lam=0.8, temperature=2.0, p_threshold=0.005)
    out.append(("a trial's 1000 replays of 126-step lessons (Ch. 8): a call each / one call",
                best_time(lambda: [replay_q(nets[0], x, params) for x in picks], 1, repeat),
                best_time(lambda: replay_q_lessons(nets[1], picks, [0.005] * 1000, params, lambda _: (None, None)), 1,
                          repeat)))
    return out + training_rows(repeat) + sixth_rows(repeat)


def training_rows(repeat: int) -> list[tuple[str, float, float]]:
    """The fifth round: Ch. 4's training plays, each batch from a copy of the same agent and world."""
    out = []
    for framework, model in (("QCON", "learned"), ("AHCON", "learned"), ("QCON-M", "perfect"),
                             ("AHCON-M", "learned")):
        env = SurvivalEnv("global")
        env.reset(seed=1)
        agent = make_survival_agent(SurvivalAgentParams(framework, model=model, model_start=0), env,
                                    np.random.default_rng(3))
        for k in range(10):  # past a random net's short plays
            run_trial(env, agent, trial=k, learning=True, options={"layout_seed": 100 + k})

        def plays(play, start=(env, agent)):
            e, a = copy.deepcopy(start)  # together: a model's world stays the copied world
            for k in range(10, 30):
                play(e, a, trial=k, options={"layout_seed": k})

        name = framework + (f", {model} model" if framework.endswith("-M") else "")
        out.append((f"20 training plays of {name} (Ch. 4): run_trial / compiled",
                     best_time(lambda plays=plays: plays(lambda e, a, **kw: run_trial(e, a, learning=True, **kw)), 1,
                               repeat),
                     best_time(lambda plays=plays: plays(learning_play), 1, repeat)))
    return out


def sixth_rows(repeat: int) -> list[tuple[str, float, float]]:
    """The sixth round: training trials over behaviours and cup trials, each batch from a copy of the agent and world;
    the model's passes of a trial."""
    out = []
    for name, p, make_world, make in (
            ("Ch. 6 QCON", RechargeParams(), make_recharge_env, make_high_level_agent),
            ("Ch. 8 recurrent-Q", IntegrationParams(memory="recurrent", online=False), make_integration_env,
             make_integration_agent)):
        env, agent = make_world(p), make(p, np.random.default_rng(3))
        for k in range(5):
            run_trial(env, agent, trial=k, learning=True, seed=k)
        out.append((f"20 training trials over behaviours, {name}: run_trial / compiled",
                    *(best_time(lambda play=play, start=(env, agent): _trials(play, start, 5), 1, repeat)
                      for play in (run_trial, recharge_train.learning_play))))
    for arch in ("window-Q", "recurrent-Q", "recurrent-model"):
        train_env, test_env = make_cup_envs(2)
        train_env.reset(seed=1)
        test_env.reset(seed=2)
        agent = make_memory_agent(CupParams(task=2, arch=arch), train_env.observation_space.shape[0], 3,
                                  np.random.default_rng(3))
        for k in range(20):
            run_trial(train_env, agent, trial=k, learning=True)
        out.append((f"20 cup trials and their tests, {arch} (Ch. 7, Task 2): run_trial / compiled",
                    *(best_time(lambda play=play, score=score, start=(train_env, test_env, agent):
                                _cup_trials(play, score, start), 1, repeat)
                      for play, score in ((run_trial, hidden_state.test_score),
                                          (cup_play.learning_play, cup_play.test_score)))))
    model = agent.model
    picks = [len(agent.history) - 1] + list(np.random.default_rng(0).integers(0, len(agent.history), 69))
    out.append(("recurrent-model's 70 model passes of a trial (Ch. 7): train_checked each / one call",
                best_time(lambda: [model.train_checked(*agent._arrays(agent.history[i])[:4]) for i in picks], 1,
                          repeat),
                best_time(lambda: model.train_lessons(agent._packed_history(), picks), 1, repeat)))
    return out


def _trials(play, start, first):
    env, agent = copy.deepcopy(start)
    for k in range(first, first + 20):
        play(env, agent, trial=k, seed=k, **({"learning": True} if play is run_trial else {}))


def _cup_trials(play, score, start):
    train_env, test_env, agent = copy.deepcopy(start)
    for k in range(20, 40):
        play(train_env, agent, trial=k, **({"learning": True} if play is run_trial else {}))
        score(test_env, agent)


@numba.njit(cache=False)
def _old_forwards(w1, w2, x, h, n):  # from compiled code, as the replays call it: no Python call in the time
    s = 0.0
    for k in range(n):
        s += _fastmath_forward(w1, w2, k % w1.shape[0], x, h)
    return s


@numba.njit(cache=False)
def _new_forwards(w1, w2, x, h, n):  # as the kernels call it
    s = 0.0
    for k in range(n):
        s += _forward_at(w1, w2, k % w1.shape[0], x, 0, h)
    return s


class _PlainRng:
    """A Generator seen through plain method calls: ``group_lesson`` then takes its plain loops (the code as it was)."""

    def __init__(self, g):
        self.uniform, self.integers = g.uniform, g.integers


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"{'hot path':<72}{'before':>12}{'after':>12}{'ratio':>8}")
    for label, before, after in rows(args.repeat):
        print(f"{label:<72}{_fmt(before):>12}{_fmt(after):>12}{before / after:>7.1f}x")


def _fmt(seconds: float) -> str:
    return f"{seconds * 1e6:.1f} us" if seconds < 1e-3 else f"{seconds * 1e3:.2f} ms"


if __name__ == "__main__":
    main()
