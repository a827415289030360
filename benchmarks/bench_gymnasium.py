"""connrl's QCON-R against SB3's DQN (RL Zoo's settings and SB3's own defaults) on four Gymnasium tasks.

    python benchmarks/bench_gymnasium.py [--tasks ...] [--seeds 0 1 2 3 4] [--learners QCON-R SB3-zoo SB3-default]
                                         [--workers 1] [--out DIR] [--write docs/PERFORMANCE.md] [--no-run]

Per task, learner and seed: the greedy policy's mean return over 10 episodes (evaluation seeds 10,000-10,009) every
5,000 environment steps up to the learner's budget -- RL Zoo's DQN budget for SB3 (CartPole-v1 50k, Acrobot-v1 100k,
MountainCar-v0 120k, LunarLander-v3 100k), the settings file's ``n_timesteps`` for connrl (what ``connrl train``
runs; larger than RL Zoo's only where its training wall-clock stays below SB3-zoo's for RL Zoo's budget); the steps
to a *held solve* -- the greedy mean at or above the task's threshold (475, -100, -110, 200) at five evaluations in a
row, counted at the fifth; the training wall and CPU time (evaluations excluded) and so the environment steps per
second. Training goes on to the budget after a held solve, so the learning curves
are whole. connrl's random warm-up (1,000 steps that set its scales) is counted in its steps and time, as SB3's
``learning_starts`` steps are in SB3's; connrl evaluates after the trial that crosses each 5,000 mark, SB3 on the mark.

Learners: ``QCON-R`` with the task's entry of the shipped settings file ``connrl/data/hyperparams/qcon-r.yml``
(the options chosen for it, docs/PERFORMANCE.md); ``QCON-T``, the same given three episodes of a hand-written
teacher (``TEACHERS``; on LunarLander, Gymnasium's own demonstration heuristic, and ten episodes: ``TAUGHT``), the
teacher's steps counted in its budget; ``SB3-zoo``:
SB3's DQN with RL Zoo's hyperparameters (``RL_ZOO_DQN``, from rl-baselines3-zoo's hyperparams/dqn.yml);
``SB3-default``: ``DQN("MlpPolicy", env, seed=seed)`` (learning rate 1e-4, buffer 1,000,000, learning_starts 100,
batch 32, train_freq 4, target update every 10,000 steps, exploration 1 -> 0.05 over the first 10 %, net 64-64).
SB3 runs only where ``stable_baselines3`` imports (the ``bench`` extra), on one torch thread, as each connrl run has
one core.

Each run is written to ``--out`` as one JSON file (atomically) under a key of what it ran: the learner's settings and,
for connrl, a hash of connrl's source; for SB3, its and torch's versions. A run whose file exists with the same key
is read, not redone: an interrupted benchmark resumes, and SB3's runs are reused until SB3 or its settings change.
``--write`` puts the table, the verdict per task and the learning-curve plot (docs/figures/bench-gymnasium.png)
between ``<!-- bench_gymnasium:begin -->`` and ``<!-- bench_gymnasium:end -->`` of the given Markdown file.
With ``--workers 2`` two runs share the machine: read the speeds of such a run with that in mind.
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import json
import multiprocessing
import platform
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import gymnasium as gym
import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from gymnasium_report import Run, summarize, write_block  # noqa: E402

import connrl  # noqa: E402
from connrl.own.settings import task_settings  # noqa: E402
from connrl.storage import atomic_write_text, read_json, strict_json  # noqa: E402

TASKS = {"CartPole-v1": (475.0, 50_000), "Acrobot-v1": (-100.0, 100_000), "MountainCar-v0": (-110.0, 120_000),
         "LunarLander-v3": (200.0, 100_000)}  # threshold, RL Zoo's DQN budget
EVAL_EVERY, EVAL_EPISODES, HELD, EVAL_SEED = 5_000, 10, 5, 10_000
_ZOO_COMMON = {"policy": "MlpPolicy", "policy_kwargs": {"net_arch": [256, 256]}}
_ZOO_LUNAR_ACROBOT = dict(learning_rate=6.3e-4, batch_size=128, buffer_size=50_000, learning_starts=0, gamma=0.99,
                          target_update_interval=250, train_freq=4, gradient_steps=-1, exploration_fraction=0.12,
                          exploration_final_eps=0.1)
RL_ZOO_DQN = {  # rl-baselines3-zoo hyperparams/dqn.yml (its LunarLander-v2 entry for v3; n_timesteps is TASKS')
    "CartPole-v1": dict(learning_rate=2.3e-3, batch_size=64, buffer_size=100_000, learning_starts=1000, gamma=0.99,
                        target_update_interval=10, train_freq=256, gradient_steps=128, exploration_fraction=0.16,
                        exploration_final_eps=0.04),
    "Acrobot-v1": _ZOO_LUNAR_ACROBOT,
    "MountainCar-v0": dict(learning_rate=4e-3, batch_size=128, buffer_size=10_000, learning_starts=1000, gamma=0.98,
                           target_update_interval=600, train_freq=16, gradient_steps=8, exploration_fraction=0.2,
                           exploration_final_eps=0.07),
    "LunarLander-v3": _ZOO_LUNAR_ACROBOT,
}


def _lander_heuristic(obs) -> int:
    from types import SimpleNamespace

    from gymnasium.envs.box2d.lunar_lander import heuristic  # needs Box2D, as the task does
    return int(heuristic(SimpleNamespace(unwrapped=SimpleNamespace(continuous=False)), obs))


# QCON-T's teacher per task: (what it does, observation -> action), for taught_episodes(task) episodes from env seed 0
TEACHERS = {
    "CartPole-v1": ("push the way the pole falls (angle + 0.5 angular velocity)", lambda o: int(o[2] + 0.5 * o[3] > 0)),
    "Acrobot-v1": ("pump: torque the way the second joint turns", lambda o: 2 if o[5] > 0 else 0),
    "MountainCar-v0": ("swing: push the way the car moves", lambda o: 2 if o[1] >= 0 else 0),
    "LunarLander-v3": ("Gymnasium's demonstration heuristic (gymnasium.envs.box2d.lunar_lander.heuristic)",
                       _lander_heuristic),
}
TAUGHT_EPISODES = 3
# where more taught episodes were chosen by measurement (docs/notes/solve-protocol.md, addenda 10-15)
TAUGHT = {"LunarLander-v3": 10}


def taught_episodes(task: str) -> int:
    """The teacher's episodes QCON-T is given on ``task`` in the benchmark."""
    return TAUGHT.get(task, TAUGHT_EPISODES)

LEARNERS = ("QCON-R", "QCON-T", "SB3-zoo", "SB3-default")
PROTOCOL = 1  # raise it when the evaluation or timing above changes: every cached run is redone


class _Curve:
    """The evaluations of one run: ``add(steps, returns)`` at each mark; ``held`` is the steps at the fifth
    evaluation in a row at the threshold (the first such), else None. ``eval_s`` / ``eval_cpu`` add up the
    evaluations' wall and CPU seconds, which are kept out of the training time."""

    def __init__(self, threshold: float):
        self.threshold, self.next, self.streak, self.held = threshold, EVAL_EVERY, 0, None
        self.points: list[tuple[int, float]] = []
        self.eval_s = self.eval_cpu = 0.0

    def due(self, steps: int) -> bool:
        return steps >= self.next

    def add(self, steps: int, evaluate) -> None:
        t0, c0 = time.perf_counter(), time.process_time()
        mean = float(np.mean(evaluate()))
        self.eval_s += time.perf_counter() - t0
        self.eval_cpu += time.process_time() - c0
        self.next += EVAL_EVERY
        self.points.append((steps, mean))
        self.streak = self.streak + 1 if mean >= self.threshold else 0
        if self.streak >= HELD and self.held is None:
            self.held = steps


def connrl_budget(task: str) -> int:
    """connrl's budget for ``task``: its settings entry's ``n_timesteps``, else RL Zoo's."""
    entry, _ = task_settings(task, "QCON-R")
    return int((entry or {}).get("n_timesteps") or TASKS[task][1])


def connrl_options(task: str) -> dict:
    """QCON-R's options for ``task``: its entry in the shipped settings file (none: the defaults)."""
    entry, _ = task_settings(task, "QCON-R")
    return dict(entry["options"]) if entry else {}


def run_connrl(task: str, seed: int, options: dict | None = None, kind: str = "QCON-R", setup=None,
               budget: int | None = None, taught: int | None = None) -> dict:
    """One connrl run (``options``: AgentOptions fields, default the shipped settings) of ``budget`` steps (default
    RL Zoo's). QCON-T first records ``taught`` episodes (default: the benchmark's for the task, ``taught_episodes``)
    of the task's teacher (env seeds 0 on); their steps count in its budget and time. ``setup(agent, env)``, when
    given, changes the agent before it learns (scripts/own_task/planning_grouping.py)."""
    threshold, zoo_budget = TASKS[task]
    budget = budget or zoo_budget
    taught = taught_episodes(task) if taught is None else taught
    options = connrl_options(task) if options is None else options
    env, eval_env = gym.make(task), gym.make(task)
    t0, c0 = time.perf_counter(), time.process_time()
    taught_steps = 0
    if kind == "QCON-T":
        with tempfile.TemporaryDirectory() as tmp:
            lessons = connrl.record_lessons(env, TEACHERS[task][1], taught, Path(tmp) / "teacher.json")
            taught_steps = sum(len(x) for x in lessons)
            agent = connrl.make_agent(env, kind, seed=seed, lessons=Path(tmp) / "teacher.json", **options)
    else:
        agent = connrl.make_agent(env, kind, seed=seed, **options)
    if setup is not None:
        setup(agent, env)
    # the warm-up's environment steps count like SB3's learning_starts, and so do the teacher's
    before = agent.options.warmup_steps + taught_steps
    if before >= budget:
        raise ValueError(f"the warm-up ({agent.options.warmup_steps:,} steps) and the teacher's {taught_steps:,} steps "
                         f"leave nothing of the {budget:,}-step budget: teach fewer episodes or give a larger budget")
    curve = _Curve(threshold)

    def evaluate(a, _ret):
        if curve.due(before + a.steps_done):
            curve.add(before + a.steps_done, lambda: connrl.evaluate(a, eval_env, EVAL_EPISODES, seed=EVAL_SEED))
        return True

    agent.learn(budget - before, callback=evaluate)
    return _record(curve, time.perf_counter() - t0, time.process_time() - c0, before + agent.steps_done, budget,
                   diverged=agent.divergence())


def run_sb3(task: str, seed: int, zoo: bool) -> dict:
    """The same for SB3's DQN, with RL Zoo's hyperparameters (``zoo``) or SB3's defaults; greedy is
    ``deterministic=True``."""
    import torch
    from stable_baselines3 import DQN
    from stable_baselines3.common.callbacks import BaseCallback

    torch.set_num_threads(1)
    threshold, budget = TASKS[task]
    eval_env, curve = gym.make(task), _Curve(threshold)

    class Evaluate(BaseCallback):
        def _on_step(self) -> bool:
            if curve.due(self.num_timesteps):
                curve.add(self.num_timesteps, self.greedy_returns)
            return True

        def greedy_returns(self) -> list[float]:
            return policy_returns(eval_env, lambda obs: int(self.model.predict(obs, deterministic=True)[0]))

    settings = sb3_settings(task, zoo)
    # device="cpu" is what "auto" picks on a machine without CUDA; verbose=0 only silences it
    model = DQN(env=gym.make(task), seed=seed, device="cpu", verbose=0, **settings)
    t0, c0 = time.perf_counter(), time.process_time()
    model.learn(budget, callback=Evaluate())
    return _record(curve, time.perf_counter() - t0, time.process_time() - c0, int(model.num_timesteps), budget)


def policy_returns(env, act, episodes: int = EVAL_EPISODES) -> list[float]:
    """The returns of ``act`` (observation -> action) on the evaluation episodes (environment seeds from
    ``EVAL_SEED``)."""
    returns = []
    for k in range(episodes):
        obs, _ = env.reset(seed=EVAL_SEED + k)
        done, total = False, 0.0
        while not done:
            obs, r, terminated, truncated, _ = env.step(act(obs))
            total, done = total + float(r), terminated or truncated
        returns.append(total)
    return returns


def sb3_settings(task: str, zoo: bool) -> dict:
    return {**_ZOO_COMMON, **RL_ZOO_DQN[task]} if zoo else {"policy": "MlpPolicy"}


def _record(curve: _Curve, wall: float, cpu: float, steps: int, budget: int, diverged: str | None = None) -> dict:
    return {"held": curve.held, "curve": curve.points, "wall": wall - curve.eval_s, "cpu": cpu - curve.eval_cpu,
            "steps": steps, "budget": budget, "diverged": diverged}


@functools.cache  # run_key asks once per task and learner; the source does not change within a run
def _source_hash() -> str:
    """A hash of connrl's source: a connrl run is redone when the code that ran it changes."""
    h = hashlib.sha256()
    for f in sorted(Path(connrl.__file__).parent.rglob("*")):
        if f.suffix in (".py", ".yml") and "__pycache__" not in f.parts:
            h.update(f.relative_to(Path(connrl.__file__).parent).as_posix().encode() + f.read_bytes())
    return h.hexdigest()[:16]


def run_key(learner: str, task: str) -> dict:
    """What a run depends on besides its seed (a cached run with another key is redone)."""
    common = {"learner": learner, "protocol": {"version": PROTOCOL, "threshold_budget": TASKS[task],
                                               "eval": [EVAL_EVERY, EVAL_EPISODES, HELD, EVAL_SEED]},
              "machine": platform.machine(), **_versions("numpy", "gymnasium", "box2d")}
    if learner.startswith("QCON"):  # numba: the kernels are compiled with fastmath
        teacher = {"teacher": [TEACHERS[task][0], taught_episodes(task)]} if learner == "QCON-T" else {}
        return {**common, "options": connrl_options(task), "budget": connrl_budget(task), **teacher,
                "connrl_source": _source_hash(),
                **_versions("numba")}
    return {**common, "settings": sb3_settings(task, learner == "SB3-zoo"),
            **_versions("stable-baselines3", "torch")}


def _versions(*packages: str) -> dict:
    out = {}
    for name in packages:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    return out


def _job(args: tuple) -> dict:
    learner, task, seed = args
    if learner.startswith("QCON"):
        return run_connrl(task, seed, kind=learner, budget=connrl_budget(task))
    return run_sb3(task, seed, zoo=learner == "SB3-zoo")


def _cached(path: Path, key: dict) -> dict | None:
    if not path.exists():
        return None
    try:
        doc = read_json(path, "benchmark run")
    except ValueError as exc:
        print(f"{exc}: redone", flush=True)
        return None
    return doc if isinstance(doc, dict) and doc.get("key") == json.loads(strict_json(key)) else None


def _args() -> argparse.Namespace:
    """The command line, checked before anything runs."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=list(TASKS), choices=list(TASKS))
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2, 3, 4])
    ap.add_argument("--learners", nargs="+", default=list(LEARNERS), choices=LEARNERS)
    ap.add_argument("--workers", type=int, default=1, help="runs at once (default 1: speeds from a quiet machine)")
    ap.add_argument("--out", type=Path, default=Path("benchmarks/results/gymnasium"))
    ap.add_argument("--write", type=Path, default=None, help="Markdown file to put the results block in")
    ap.add_argument("--no-run", action="store_true", help="report the runs on disk only; run none")
    args = ap.parse_args()
    if args.workers < 1:
        ap.error(f"--workers must be 1 or more, got {args.workers}")
    for name in ("tasks", "seeds", "learners"):
        values = getattr(args, name)
        if len(set(values)) < len(values):
            ap.error(f"--{name} names one twice: {' '.join(map(str, values))}")
    if min(args.seeds) < 0:
        ap.error(f"--seeds must be whole numbers >= 0, got {min(args.seeds)}")
    if args.out.exists() and not args.out.is_dir():
        ap.error(f"--out {args.out}: is a file, not a folder of runs")
    if args.write is not None and not args.write.is_file():
        ap.error(f"--write {args.write}: no such Markdown file (give docs/PERFORMANCE.md or another existing file)")
    return args


def _installed(tasks: list[str], learners: list[str]) -> tuple[list[str], list[str]]:
    """The tasks and learners this machine can run, each one left out said so in one line."""
    if any(name.startswith("SB3") for name in learners):
        try:
            import stable_baselines3  # noqa: F401
        except ImportError:
            print("SB3-DQN: not run (stable_baselines3 is not installed: pip install -e \".[bench]\")", flush=True)
            learners = [name for name in learners if not name.startswith("SB3")]
    kept = []
    for task in tasks:
        try:
            gym.make(task).close()
            kept.append(task)
        except gym.error.DependencyNotInstalled:
            print(f"{task}: not run (Box2D is not installed: pip install -e \".[bench]\")", flush=True)
    return kept, learners


def main() -> None:
    args = _args()
    tasks, learners = _installed(list(args.tasks), list(args.learners))
    args.out.mkdir(parents=True, exist_ok=True)
    runs, todo = [], []
    for task in tasks:
        for learner in learners:
            if learner == "QCON-T" and task not in TEACHERS:
                continue  # no teacher written for it
            key = run_key(learner, task)
            for seed in args.seeds:
                path = args.out / f"{task}_{learner}_{seed}.json"
                doc = _cached(path, key)
                if doc is not None:
                    runs.append(Run(task, learner, seed, doc))
                else:
                    todo.append((path, key, (learner, task, seed)))
    print(f"{len(runs)} runs read from {args.out}, {0 if args.no_run else len(todo)} to run", flush=True)
    if args.no_run:
        todo = []
    with ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = {pool.submit(_job, job): (path, key, job) for path, key, job in todo}
        for future in as_completed(futures):  # each run is on disk as soon as it ends: a stop loses only those running
            path, key, (learner, task, seed) = futures[future]
            try:
                result = future.result()
            except Exception as exc:  # one failed run is reported; the others are kept
                print(f"{task:<16} {learner:<12} seed {seed:>4}: failed ({type(exc).__name__}: {exc})", flush=True)
                continue
            doc = json.loads(strict_json({"key": key, "workers": args.workers, **result}))
            atomic_write_text(path, strict_json(doc))
            runs.append(Run(task, learner, seed, doc))
            last = doc["curve"][-1][1] if doc["curve"] else float("nan")
            print(f"{task:<16} {learner:<12} seed {seed:>4}: held at {doc['held'] or 'not held'}, last greedy "
                  f"{last:.1f}, cpu {doc['cpu']:.1f} s", flush=True)
    text = summarize(runs, tasks, learners, TASKS, args.seeds)
    print(text)
    if args.write is not None:
        write_block(args.write, text, runs, tasks, learners, TASKS, " ".join(sys.argv[1:]))


if __name__ == "__main__":
    main()
