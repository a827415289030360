"""Ch. 5: learning the elementary robot skills DP, DK and WFL with QCON-T (Figs. 5.4-5.10, the tables of 5.6).

Protocol (5.4): each run trains a fresh agent for 300 trials; a trial starts from a random pose of the
task's start region and ends at the goal or after 30 steps. Before the first trial and after every 10
trials the greedy policy (T = 0, learning off) is tested on 50 start poses drawn once per run; the
performance is the total reinforcement over the 50 tests divided by the steps they took. Each test task
also has a fixed simulator seed, so the sensing and control noise of a test is the same at every test
(less noise in the curve; the thesis does not say how it handled this).

Agent (5.3): ``connrl.agents.repairs.TeachingQCON``: six OAON Q-nets (hidden = round(0.3 x inputs):
16 for DP/DK, 11 for WF), lr 0.05, momentum 0.9, init +-0.5, Q in +-100, gamma 0.9, lambda 0.7 (set to 0
at the end of a lesson and after non-policy actions), T 0.05 -> 0.02 over 300 trials on Q/100, stuck
detection, on-line Q-learning during the trial and, after it, 60 lessons chosen by App. A.2 from the
latest 100 (fewer while fewer exist) plus every taught lesson, non-policy actions (P < 2 %) not replayed.

Taught lessons (3.7, 5.4) come from the scripted teachers of ``connrl.envs.robot`` (not a person):
``python -m connrl.experiments.robot make-lessons`` rewrites ``connrl/data/lessons/robot-{dp,dk,wfl}.json``
deterministically; 3 (DP, DK) or 2 (WFL) taught lessons are the first ones of the file.

Known gap (DP; measured on seeds 100-106, not the acceptance seeds): with 10 lessons the thesis reaches 2.5
reinforcement/step by trial 10 and 5 by trial 65; we reach 2.5 at about trial 270 (mean curve) and 5 in 1
run of 7. Checked and *not* the cause: taught lessons are replayed with P_t = 0 and the replay / selection
temperature is on the Q scale (tests/test_robot_agents.py); lessons match the current simulator. What we
measured instead:

- Replaying only the 10 taught lessons (no experience), the greedy action agrees with the taught one on
  ~50 % of the taught states after 1..100 replays -- about the share of "move forward" in the lessons --
  and the greedy test policy drives into walls (-7..-2 reinforcement/step). Positive examples carry no
  information that the untaken actions are worse (5.4.3); the untaken nets generalise from the states where
  they were taught to similar values. This holds equally with init +-0.1 (initial |Q| < 5 instead of ~35),
  value range 50 and 52 hidden units, so the initial output magnitude and hidden-unit count are not it.
  The lower repair raises agreement only to 0.59 (lr 0.05) / 0.70 (lr 0.2) after 100 replays.
- Early test performance is dominated by collision loops: at trial 10 (seed 100) 5/50 tests succeed and the
  greedy robot makes ~200 collisions (-10 each) in 1400 steps. DK shows the same dip (mean -6.7 at
  trial 10, seeds 0-6, 10 lessons).
- Full runs (7 seeds, 10 lessons, mean-curve trials to 2.5 / final): default 270 / 3.27; lower repair
  270 / 3.02; no on-line learning 260 / 3.11; 3x taught replays 280 / 2.63; hidden 50 % 270 / 2.61;
  T on Q/200 (merit_scale 200) never / 0.31; T on Q/50 270 / 2.82; lr 0.1 220 / 3.21; lr 0.2 210 / 3.23.
  With 48-in instead of 36-in doors (in-memory layout, diagnostic only) 200 / 3.87; no teaching still fails.
- A second look (seeds 100-106, 7 runs; pass rates, collisions and headings from ``scripts/dp_diagnosis/``, the
  other variants one-off runs of its harness): at trial 10 the greedy robot passes the door
  in 3.6 of 50 tests, where 2.5 reinforcement/step by trial 10 needs about 24 passes and few collisions.
  85-90 % of test collisions are the same forward move repeated with the front collision bit already on:
  Q(forward) there (~50) stays above the turns because its target, -10 + 0.9 max Q(next), bootstraps from
  the same spot where forward is still the maximum (~40 > turns at 5-20); one -10 error moves Q by 0.04,
  and forward falls below the best turn only after ~60 repeated updates. Yet with every collision penalty
  removed from the score the tests would give only 0.25 (trial 10) and 0.95 (trial 100): the gap is the
  pass rate, not the penalty. Facing the door (within 30 deg) the trial-10 robot passes 26 % of the time and
  otherwise sticks on a jamb of the 36-in door; facing away it passes 3 %. Other lesson sets (teacher
  seeds 1-3, or 20-40 % random teacher actions) and lr 0.4 / 1.0, a linear output unit, or treating
  timeouts as terminal leave trials 10-60 at about -1. Without teaching our curve never reaches 2.5
  (thesis: trial 280), so learning from the robot's own experience is slower too, not only the use of
  taught lessons. Our leading suspects are therefore the reconstructed geometry (door width against the
  24-in body, the start region), which the text does not pin down, rather than the learning machinery.
So no single thesis-stated or reconstructed setting closes the gap; the parameters stay at the thesis's.

Geometry studies (``connrl run robot-dp-geometry`` / ``robot-dk-geometry``, full profile, the acceptance seeds
0..6; the numbers are generated into docs/RESULTS.md): the two suspects above, made parameters
(``door_width``, ``dp_heading``, ``dock_tolerance``; defaults = SPEC 5) and crossed with the teaching
conditions. Wider (48-in) doors together with starts that face the door (+-45 deg) bring DP with 10 lessons to
2.5 at trial 60 and to 5 at trial 150 on the mean curve (SPEC geometry: 280 / never; thesis 10 / 65), yet
score about -1 at trial 10; either change alone helps less (facing: 120 / 230, wider: 270 / never). The facing
starts apply to the test tasks too, so part of that gain is an easier test, not faster learning. So the
reconstructed geometry explains part of the gap, not all of it. A tighter docking condition (10 instead of 30
deg) makes docking unlearnable without teaching (7 of 7 runs fail; thesis 2 of 7) and puts single-layer nets
behind multi-layer ones by final performance (1.91 vs 3.86; over the whole curve 0.59 vs 0.70), as in Fig.
5.10. Neither is made the default: the text does not give these numbers, and choosing them to match the
thesis's results would be fitting the task to the answer. Taught lessons for a geometry other than the shipped
lessons' are demonstrated afresh by the same scripted teacher, same seed and starts (``taught_lessons(...,
door_width=, dock_tolerance=)``).

Single-layer nets (5.4.4): DP and WFL are clearly worse than with a hidden layer, DK with our 30-deg docking
is not (7.63 vs 8.79 final; with 10 deg it is, see the geometry studies). Our docking is nearly linear in the
inputs: the light bits say where the charger is, and "turn towards the light, then drive" is a linear rule. It
is also easier than the thesis's in another way: without teaching 6 of our 7 runs learn it (final 6.2-10.8,
one at 2.6), where the thesis's "totally failed" in 2 of 7 (5.4.1). So our reconstructed docking (any head-on
contact within 30 deg of the heading, starts within 96 in with the light in sight) asks for less accuracy than
the thesis's "tight connection". A linear output unit (``linear_output``, as window-Q's perceptrons in Ch. 7)
gives the same picture on seeds 100-106 (``scripts/robot_variants.py``): final DK 8.36, DP 0.87, WFL 1.93.
"""

from __future__ import annotations

import functools
import json
import math
import sys
from pathlib import Path

import numpy as np

from connrl.agents import LinearSchedule, QCONConfig, ReplayConfig
from connrl.agents.teaching import TeachingConfig, TeachingQCON
from connrl.core.exploration import StuckConfig, TemperatureSchedule
from connrl.core.lesson_files import load_lessons, save_lessons
from connrl.core.lessons import Lesson
from connrl.envs.robot import OBS_SIZE, Layout, RobotTaskEnv, teach
from connrl.experiments.protocol import run_trial
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant
from connrl.nets import NetConfig

LESSON_DIR = Path(__file__).resolve().parent.parent / "data" / "lessons"
TAUGHT_COUNTS = {"DP": 10, "DK": 10, "WFL": 5}  # lessons shipped per task (5.4.1)

ROBOT_PARAMS = {
    "task": "DP",  # "DP" | "DK" | "WFL" (5.4)
    "lessons": 10,  # taught lessons given to the agent (5.4.1: 0/3/10 DP, DK; 0/2/5 WFL)
    "hidden_fraction": 0.3,  # hidden units ~ 30 % of inputs (5.3.3); 0 = single-layer (5.4.4)
    "lr": 0.05,  # back-propagation learning rate (5.3.3; 5.4.4: 0.04 DP/DK, 0.03 WFL)
    "momentum": 0.9,  # (5.3.3; 5.4.4: 0)
    "init_range": 0.5,  # initial weights in +-0.5 (5.3.3)
    "value_range": 100.0,  # Q in +-100 (5.3.1)
    "binary_low": -0.5,  # binary inputs +-0.5 (5.3.2); 0 -> 0/1 (5.4.4)
    "gamma": 0.9,  # (5.3.1)
    "lam": 0.7,  # (5.4.1)
    "t_start": 0.05,  # T: 0.05 -> 0.02 over the run (5.3.4), on Q / value_range
    "t_end": 0.02,
    "online": True,  # Q-learning on each step as well as replay (Fig. 3.4, R)
    "capacity": 100,  # latest lessons kept for replay (App. A.2, R for Ch. 5)
    "lessons_per_trial": 60,  # experienced lessons replayed after each trial (5.3.5)
    "p_threshold": 0.02,  # P_l: non-policy threshold (5.3.5)
    "repair": "none",  # "none" | "lower" | "raise" (5.4.3)
    "stuck_window": 8,  # stuck detection (5.3.4, R): last 8 positions ...
    "stuck_radius": 12.0,  # ... within 12 in (one move) of their mean ...
    "stuck_boost": 5.0,  # ... multiply T by 5
    "trials": 300,  # trials per run (5.4)
    "max_steps": 30,  # steps per trial and per test (5.4)
    "test_every": 10,  # test after every 10 trials (5.4)
    "test_tasks": 50,  # fixed test tasks per run (5.4)
    "paths": 0,  # greedy solution paths recorded at the end of the run (Figs. 5.5-5.7)
    "linear_output": False,  # single-layer nets only: linear output unit (7.4's linear OAON; diagnostic)
    "door_width": 36.0,  # doorway width, in (SPEC 5, R); others: sensitivity study (robot-dp-geometry)
    "dp_heading": 180.0,  # DP starts face within +-this many deg of the door (180 = any heading, 5.4)
    "dock_tolerance": 30.0,  # DK: a head-on charger contact within this many deg docks (R; robot-dk-geometry)
}

DEFAULT_GEOMETRY = {"door_width": 36.0, "dock_tolerance": 30.0}  # what the shipped taught lessons were made in

THRESHOLDS = (2.5, 5.0)  # the two performance levels of the tables in 5.6


def quantity_name(level: float) -> str:
    return f"trials_to_{level:g}"


# ------------------------------------------------------------------------------------------- lessons

def lesson_path(task: str) -> Path:
    return LESSON_DIR / f"robot-{task.lower()}.json"


def make_env(p: dict) -> RobotTaskEnv:
    """The task environment of a parameter set (the layout's doors widened when ``door_width`` asks)."""
    layout = Layout.load("default")
    if p["door_width"] != DEFAULT_GEOMETRY["door_width"]:
        layout = layout.with_door_width(p["door_width"])
    return RobotTaskEnv(p["task"], layout=layout, binary_low=p["binary_low"], max_steps=p["max_steps"],
                        dp_heading=p["dp_heading"], dock_tolerance=p["dock_tolerance"])


def make_taught_lessons(task: str, n: int | None = None, seed: int = 0, max_tries: int = 200,
                        env: RobotTaskEnv | None = None) -> list[Lesson]:
    """Demonstrations by the scripted teacher of ``task`` from start poses drawn with ``seed``.

    DP and DK keep only demonstrations that reach the goal (the thesis's "positive examples", 5.4.1);
    WFL keeps every 30-step demonstration. Deterministic given ``seed``. ``env`` (default: the task on
    the default layout) sets the geometry the teacher demonstrates in.
    """
    n = TAUGHT_COUNTS[task] if n is None else n
    env = RobotTaskEnv(task) if env is None else env
    rng = np.random.default_rng(seed)
    out: list[Lesson] = []
    for i in range(max_tries):
        if len(out) == n:
            break
        start = env.sample_task(rng)
        play_seed = int(rng.integers(2**31))
        steps = teach(env, start, seed=play_seed)
        success = bool(steps[-1][4])
        if task in ("DP", "DK") and not success:
            continue
        reward = float(sum(s[2] for s in steps))
        out.append(Lesson.from_steps(steps, taught=True, meta={
            "teacher": f"connrl.envs.robot.teach ({task})", "start": [round(v, 3) for v in start],
            "play_seed": play_seed, "attempt": i, "steps": len(steps), "success": success, "reward": reward}))
    if len(out) < n:
        raise RuntimeError(f"the {task} teacher succeeded only {len(out)} times in {max_tries} tries")
    return out


def write_taught_lessons(seed: int = 0) -> list[Path]:
    """Regenerate connrl/data/lessons/robot-{dp,dk,wfl}.json (``python -m connrl.experiments.robot make-lessons``)."""
    paths = []
    for task in TAUGHT_COUNTS:
        lessons = make_taught_lessons(task, seed=seed)
        p = lesson_path(task)
        save_lessons(p, lessons, env_id=f"connrl/Robot-{task}-v0", env_kwargs={},
                     source=f"connrl.experiments.robot.make_taught_lessons({task!r}, n={len(lessons)}, "
                            f"seed={seed}): scripted teacher, not a person")
        paths.append(p)
    return paths


def binary_columns(task: str) -> np.ndarray:
    """Indices of the binary inputs of a task's observation (see connrl.envs.robot)."""
    if task in ("DK", "DP"):
        return np.arange(24, 52)
    return np.r_[24:28, 30:36]


@functools.lru_cache(maxsize=8)
def _demonstrated(task: str, door_width: float, dock_tolerance: float) -> tuple[Lesson, ...]:
    """The shipped lessons' recipe (seed 0, starts with any heading, 30 steps) in another geometry; cached
    per process (callers copy the inputs before changing them)."""
    env = make_env({**ROBOT_PARAMS, "task": task, "door_width": door_width, "dock_tolerance": dock_tolerance,
                    "binary_low": -0.5, "max_steps": 30, "dp_heading": 180.0})
    return tuple(make_taught_lessons(task, seed=0, env=env))


def taught_lessons(task: str, n: int, binary_low: float = -0.5, door_width: float = 36.0,
                   dock_tolerance: float = 30.0) -> list[Lesson]:
    """The first ``n`` taught lessons of ``task``, re-encoded for ``binary_low`` (files use -0.5/+0.5).

    In the geometry of the shipped lessons (DEFAULT_GEOMETRY) they are read from the file; in another one
    the same scripted teacher demonstrates afresh there (same seed and starts, deterministic).
    """
    if n == 0:
        return []
    if task != "DK":
        dock_tolerance = DEFAULT_GEOMETRY["dock_tolerance"]  # only docking depends on it
    if (door_width, dock_tolerance) != (DEFAULT_GEOMETRY["door_width"], DEFAULT_GEOMETRY["dock_tolerance"]):
        lessons = _demonstrated(task, float(door_width), float(dock_tolerance))
        where = f"the teacher made {len(lessons)} with {door_width:g}-in doors, docking within {dock_tolerance:g} deg"
    else:
        lessons = load_lessons(lesson_path(task), env_id=f"connrl/Robot-{task}-v0", input_dim=OBS_SIZE[task],
                               n_actions=6)
        where = f"the file has {len(lessons)}"
    if n > len(lessons):
        raise ValueError(f"{task}: {n} taught lessons asked for, {where}")
    out = []
    for lesson in lessons[:n]:
        x = lesson.inputs.copy()
        x[:, binary_columns(task)] += binary_low + 0.5
        out.append(Lesson(x, lesson.actions, lesson.rewards, lesson.terminated, lesson.truncated, True,
                          dict(lesson.meta)))
    return out


# --------------------------------------------------------------------------------------------- agent

def make_agent(p: dict, rng: np.random.Generator) -> TeachingQCON:
    """QCON-T of 5.3 from ROBOT_PARAMS (``linear_output``: single-layer nets with a linear output unit)."""
    n_in = OBS_SIZE[p["task"]]
    hidden = int(round(p["hidden_fraction"] * n_in))
    net = NetConfig(n_in, hidden, value_range=p["value_range"], init_range=p["init_range"], lr=p["lr"],
                    momentum=p["momentum"], linear_output=bool(p["linear_output"]) and hidden == 0)
    replay = ReplayConfig(capacity=p["capacity"],
                          lessons_per_trial=LinearSchedule(p["lessons_per_trial"], p["lessons_per_trial"]),
                          p_threshold=p["p_threshold"])
    cfg = QCONConfig(net=net, temperature=TemperatureSchedule.direct(p["t_start"], p["t_end"], p["trials"]),
                     gamma=p["gamma"], lam=p["lam"], online=p["online"], replay=replay,
                     stuck=StuckConfig(p["stuck_window"], p["stuck_radius"], p["stuck_boost"]))
    agent = TeachingQCON(cfg, 6, rng, TeachingConfig(repair=p["repair"], merit_scale=p["value_range"]))
    agent.add_taught_lessons(taught_lessons(p["task"], p["lessons"], p["binary_low"], p["door_width"],
                                            p["dock_tolerance"]))
    return agent


# ----------------------------------------------------------------------------------------------- run

def evaluate(env: RobotTaskEnv, agent, tasks, seeds, max_steps: int, paths: list | None = None) -> float:
    """Greedy test on fixed tasks: total reinforcement / total steps (5.4)."""
    total, steps = 0.0, 0
    for i, (start, s) in enumerate(zip(tasks, seeds, strict=True)):
        stats = run_trial(env, agent, trial=0, learning=False, seed=int(s), options={"start": start},
                          max_steps=max_steps)
        total += stats.total_reward
        steps += stats.steps
        if paths is not None and i < len(paths):
            paths[i] = {"poses": [[round(v, 2) for v in pose] for pose in env.trace],
                        "success": bool(stats.info.get("success")), "reward": stats.total_reward}
    return total / max(steps, 1)


def first_reaching(xs, ys, level: float):
    """First trial count whose test performance is >= level (None if never)."""
    for x, y in zip(xs, ys, strict=True):
        if y >= level:
            return x
    return None


def run_robot(p: dict, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    env, test_env = make_env(p), make_env(p)
    task_rng = np.random.default_rng(rng.integers(2**63))
    tests = [test_env.sample_task(task_rng) for _ in range(p["test_tasks"])]
    test_seeds = task_rng.integers(2**31, size=p["test_tasks"])
    agent = make_agent(p, rng)
    env.reset(seed=int(rng.integers(2**31)))
    xs, ys, rows = [], [], []

    def test(k):
        perf = evaluate(test_env, agent, tests, test_seeds, p["max_steps"])
        xs.append(k)
        ys.append(perf)
        rows.append({"trials": k, "performance": perf})

    test(0)
    successes = 0
    for k in range(p["trials"]):
        stats = run_trial(env, agent, trial=k, learning=True)
        successes += bool(stats.info.get("success"))
        if (k + 1) % p["test_every"] == 0 or k + 1 == p["trials"]:
            test(k + 1)
            rows[-1]["train_successes"] = successes
        progress(k + 1, p["trials"])
    extra = {}
    if p["paths"]:
        recorded: list = [None] * min(p["paths"], len(tests))
        evaluate(test_env, agent, tests[:len(recorded)], test_seeds[:len(recorded)], p["max_steps"], recorded)
        extra["paths"] = recorded
    metrics = {quantity_name(level): first_reaching(xs, ys, level) for level in THRESHOLDS}
    tail = ys[-3:]
    metrics["final_performance"] = float(np.mean(tail))
    metrics["mean_performance"] = float(np.mean(ys))
    return RunResult(xs, ys, metrics, rows, extra)


# --------------------------------------------------------------------------------------------- specs

def _q_reach(level: float, section: str = "5.6") -> Quantity:
    return Quantity(quantity_name(level), f"trials until a test reaches {level:g} reinforcement/step (per run)",
                    "lower", section)


Q_FINAL = Quantity("final_performance", "mean test performance over the last 3 tests (trials 280-300)",
                   "higher", "5.4")
Q_MEAN = Quantity("mean_performance", "test performance averaged over all 31 tests (area under the curve)",
                  "higher", "5.4")

PROFILES = {
    "tiny": {"runs": 1, "trials": 4, "test_every": 2, "test_tasks": 3, "lessons_per_trial": 3, "paths": 2},
    "quick": {"runs": 2, "trials": 100, "test_tasks": 25},
    "full": {"runs": 7},
}


def _spec(name, title, section, base, variants, quantities, paths=0, description=""):
    return ExperimentSpec(name=name, title=title, section=section, run="connrl.experiments.robot:run_robot",
                          params={**ROBOT_PARAMS, **base, "paths": paths},
                          profiles={k: ({**v, "paths": min(v.get("paths", paths), paths)} if paths else dict(v))
                                    for k, v in PROFILES.items()},
                          variants=tuple(variants), quantities=tuple(quantities), x_label="trials",
                          y_label="reinforcement per step (greedy test, 50 tasks)", description=description,
                          y_reference={"2.5": 2.5, "5": 5.0} if base.get("task") == "DP" else {})


_DP_Q = (_q_reach(2.5), _q_reach(5.0), Q_FINAL, Q_MEAN)
_Q = (Q_FINAL, Q_MEAN)

EXPERIMENTS = [
    _spec("robot-teaching-dp", "Exp. 1: door passing (DP) with 0, 3 and 10 taught lessons", "5.4.1 Fig. 5.4a",
          {"task": "DP"},
          [Variant("no teaching", {"lessons": 0}, {"trials_to_2.5": 280}),
           Variant("3 lessons", {"lessons": 3}, {"trials_to_2.5": 20}),
           Variant("10 lessons", {"lessons": 10}, {"trials_to_2.5": 10, "trials_to_5": 65})],
          _DP_Q, paths=8),
    _spec("robot-teaching-dk", "Exp. 1: docking (DK) with 0, 3 and 10 taught lessons", "5.4.1 Fig. 5.4b",
          {"task": "DK"},
          [Variant("no teaching", {"lessons": 0}), Variant("3 lessons", {"lessons": 3}),
           Variant("10 lessons", {"lessons": 10})], _Q, paths=6),
    _spec("robot-teaching-wfl", "Exp. 1: left wall following (WFL) with 0, 2 and 5 taught lessons",
          "5.4.1 Fig. 5.4c", {"task": "WFL"},
          [Variant("no teaching", {"lessons": 0}), Variant("2 lessons", {"lessons": 2}),
           Variant("5 lessons", {"lessons": 5})], _Q, paths=6),
    _spec("robot-lambda-dp", "Exp. 2: TD(lambda) on DP with 10 taught lessons", "5.4.2 Fig. 5.8a",
          {"task": "DP", "lessons": 10},
          [Variant("lambda=0", {"lam": 0.0}, {"trials_to_5": 280}),
           Variant("lambda=0.3", {"lam": 0.3}, {"trials_to_5": 140}),
           Variant("lambda=0.7", {"lam": 0.7}, {"trials_to_5": 65}),
           Variant("lambda=0.9", {"lam": 0.9}), Variant("lambda=1", {"lam": 1.0})], _DP_Q),
    _spec("robot-lambda-wfl", "Exp. 2: TD(lambda) on WFL without teaching", "5.4.2 Fig. 5.8b",
          {"task": "WFL", "lessons": 0},
          [Variant(f"lambda={lam:g}", {"lam": lam}) for lam in (0.0, 0.3, 0.7, 0.9, 1.0)], _Q),
    _spec("robot-repairs-3", "Exp. 3: lower / raise repairs on DP with 3 taught lessons", "5.4.3 Fig. 5.9a",
          {"task": "DP", "lessons": 3},
          [Variant(r, {"repair": r}) for r in ("none", "lower", "raise")], _DP_Q),
    _spec("robot-repairs-10", "Exp. 3: lower / raise repairs on DP with 10 taught lessons", "5.4.3 Fig. 5.9b",
          {"task": "DP", "lessons": 10},
          [Variant(r, {"repair": r}) for r in ("none", "lower", "raise")], _DP_Q),
    _spec("robot-single-layer", "Exp. 4: single-layer Q-nets (0/1 binaries, no momentum) on DP, DK, WFL",
          "5.4.4 Fig. 5.10", {"hidden_fraction": 0.0, "momentum": 0.0, "binary_low": 0.0},
          [Variant("DP single-layer", {"task": "DP", "lessons": 10, "lr": 0.04}),
           Variant("DK single-layer", {"task": "DK", "lessons": 10, "lr": 0.04}),
           Variant("WFL single-layer", {"task": "WFL", "lessons": 5, "lr": 0.03})], _Q,
          description="compare with the multi-layer curves of robot-teaching-* (10/10/5 lessons)"),
    _spec("robot-dp-geometry", "Sensitivity of DP to the reconstructed geometry: door width and start heading "
          "(not a thesis figure)", "5.4.1, 5.6; SPEC 5 (R)", {"task": "DP"},
          [Variant(f"{w:g}-in doors, {h}, {n} lessons", {"door_width": w, "dp_heading": hd, "lessons": n},
                   {"trials_to_2.5": {0: 280, 3: 20, 10: 10}[n], **({"trials_to_5": 65} if n == 10 else {})})
           for w in (36.0, 48.0) for h, hd in (("any heading", 180.0), ("facing +-45", 45.0))
           for n in (0, 3, 10)], _DP_Q,
          description="the thesis does not give the door width (SPEC 5 reconstructs 36 in for a 24-in body) nor "
                      "the start headings beyond 'near a door'; thesis numbers are its Fig. 5.4a / 5.6 values"),
    _spec("robot-dk-geometry", "Sensitivity of DK to the reconstructed docking tolerance, multi- vs single-layer "
          "(not a thesis figure)", "5.4.1, 5.4.4; SPEC 5 (R)", {"task": "DK"},
          [Variant(f"{tol:g} deg, {arch}, {n} lessons",
                   {"dock_tolerance": tol, "lessons": n, **over})
           for tol in (30.0, 10.0)
           for arch, over in (("multi-layer", {}), ("single-layer", {"hidden_fraction": 0.0, "momentum": 0.0,
                                                                     "binary_low": 0.0, "lr": 0.04}))
           for n in (0, 10)], _Q,
          description="docking = a forward move stopped head-on by the charger, the contact within the tolerance "
                      "of the heading; the thesis asks for a 'tight connection' without giving a number"),
]


# ------------------------------------------------------------------------------------------- results

def _records(spec: ExperimentSpec, out: Path) -> tuple[dict | None, list[dict]]:
    from connrl.experiments.runner import load_record, make_jobs

    p = out / spec.name / "summary.json"
    if not p.exists():
        return None, []
    summary = json.loads(p.read_text())
    jobs = make_jobs(spec, summary["profile"], summary["runs_per_variant"], summary["base_seed"], out)
    return summary, [r for r in (load_record(j) for j in jobs) if r is not None]


def mean_curve(records: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    xs = np.asarray(records[0]["curve_x"], dtype=float)
    ys = np.array([r["curve_y"] for r in records if len(r["curve_y"]) == xs.size], dtype=float)
    return xs, ys.mean(axis=0)


def _fmt(v, nd=2) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "—"
    return f"{v:.{nd}f}" if isinstance(v, float) and not float(v).is_integer() else f"{v:g}"


def draw_solution_paths(records: list[dict], file: Path, task: str, k: int) -> Path | None:
    """Figs. 5.5-5.7: up to ``k`` greedy paths of the first run's final policy (successful ones first)."""
    from connrl.envs.robot import Layout, render_paths

    rec = next((r for r in sorted(records, key=lambda r: r["seed"]) if r.get("extra", {}).get("paths")), None)
    if rec is None:
        return None
    paths = sorted(rec["extra"]["paths"], key=lambda p: (not p["success"], -p["reward"]))[:k]
    render_paths(Layout.load("default"), [p["poses"] for p in paths],
                 labels=[f"{'goal' if p['success'] else 'no goal'}, {len(p['poses']) - 1} steps, "
                         f"r={p['reward']:g}" for p in paths],
                 title=f"{task}: greedy paths after {rec['params']['trials']} trials (seed {rec['seed']})",
                 file=file)
    return file


def results_section(out_dir: Path, doc: Path = Path("docs/RESULTS.md")) -> str:
    """Markdown for docs/RESULTS.md: our Ch. 5 numbers beside the thesis's, from OUT/robot-*/ records."""
    from connrl.report.page import figure

    out_dir = Path(out_dir)
    intro = ["## Chapter 5: robot skills with QCON-T (DP, DK, WFL)", "",
             "Performance = reinforcement per step on 50 fixed greedy test tasks, tested every 10 trials. "
             "\"Mean curve\" columns read the level off the mean learning curve over runs, as the thesis's "
             "tables of 5.6 do; \"per run\" is the mean of each run's first test reaching the level "
             "(over the runs that reached it). Taught lessons: scripted teachers "
             "(`python -m connrl.experiments.robot make-lessons`).", ""]
    lines: list[str] = []
    curves: dict[tuple[str, str], tuple[np.ndarray, np.ndarray, int]] = {}
    any_found = False
    walls, run_walls, cpus, seeds = [], [], set(), {}
    for spec in EXPERIMENTS:
        summary, recs = _records(spec, out_dir)
        if summary is None or not recs:
            continue
        any_found = True
        seeds[spec.name] = f"{summary['base_seed']}..{summary['base_seed'] + summary['runs_per_variant'] - 1}"
        walls.append(summary["timing"]["wall_time_s"])
        run_walls += summary["timing"]["run_wall_time_s"]
        cpus.add(summary["environment"].get("cpus"))
        prof = summary["profile"]
        lines += [f"### {spec.name}: {spec.title} (thesis {spec.section})", "",
                  f"`connrl run {spec.name} --profile {prof} --seed {summary['base_seed']}` — "
                  f"{summary['runs_per_variant']} runs per variant, seeds {seeds[spec.name]}, "
                  f"wall {summary['timing']['wall_time_s']:.0f} s.", ""]
        dp = any(q.name == "trials_to_2.5" for q in spec.quantities)
        head = "| variant | final perf. | mean perf. |"
        if dp:
            head += " to 2.5 (mean curve) | to 2.5 (per run, reached) | thesis | to 5 (mean curve) " \
                    "| to 5 (per run, reached) | thesis |"
        lines += [head, "|" + "---|" * (head.count("|") - 1)]
        for v in spec.variants:
            vr = [r for r in recs if r["variant"] == v.label]
            if not vr:
                continue
            xs, ys = mean_curve(vr)
            curves[(spec.name, v.label)] = (xs, ys, len(vr))
            qs = summary["variants"][v.label]["quantities"]
            row = f"| {v.label} | {_fmt(qs['final_performance']['mean'])} | {_fmt(qs['mean_performance']['mean'])} |"
            if dp:
                for level in THRESHOLDS:
                    q = qs[quantity_name(level)]
                    row += (f" {_fmt(first_reaching(list(xs), list(ys), level))} | {_fmt(q['mean'], 0)} "
                            f"({q['runs_reaching']}/{len(q['per_run'])}) | {_fmt(q['thesis'])} |")
            lines.append(row)
        lines.append("")
        panels = _PANELS.get(spec.name)
        png = (_draw_panels(spec, curves, panels, out_dir / spec.name / "panels.png") if panels
               else out_dir / spec.name / "curve.png")
        link = figure(png, doc, f"{spec.name}-curves")
        if link:
            lines += [f"Mean learning curves ({'one panel per geometry' if panels else 'shaded: min-max over runs'}):",
                      "", link, ""]
        if spec.params.get("paths"):
            task = spec.params["task"]
            best = spec.variants[-1].label
            f = draw_solution_paths([r for r in recs if r["variant"] == best], out_dir / spec.name /
                                    "solution-paths.png", task, {"DP": 4, "DK": 3, "WFL": 3}[task])
            if f is not None:
                lines += [f"Solution paths (Figs. 5.5-5.7) of the learned greedy policies, {best}:", "",
                          figure(Path(f), doc, f"{spec.name}-paths"), ""]
    if not any_found:
        return "\n".join(intro + ["No Ch. 5 results yet: run `connrl run robot-teaching-dp` etc.", ""])
    from connrl.envs.robot import render_figure_5_3

    sim_png = out_dir / "robot-figure-5-3.png"
    render_figure_5_3(file=sim_png)
    intro += ["The simulator as Fig. 5.3 shows it (`connrl.envs.robot.render_figure_5_3`, noisy readings, seed 0):",
              "", figure(sim_png, doc, "robot-figure-5-3"), ""]
    lines = intro + lines
    lines += [f"**Compute:** the {len(walls)} Ch. 5 experiments above ({len(run_walls)} runs) took "
              f"{sum(walls) / 60:.1f} min of wall time together ({sum(run_walls) / 60:.1f} min summed over runs; "
              f"machine with {', '.join(str(c) for c in sorted(cpus, key=str))} CPUs; the `connrl run` commands "
              "above).", ""]
    lines += _speedup_tables(curves)
    lines += ["### Where Ch. 5 falls short", "",
              "Door passing learns far slower than the thesis's, with or without taught lessons (tables above). "
              "What we measured, in the module docstring of `connrl/experiments/robot.py` with the scripts in "
              "`scripts/dp_diagnosis/` (seeds 100-106): early greedy tests are dominated by repeated forward "
              "collisions that bootstrap from their own over-valued next state, but even with every collision "
              "penalty removed the trial-10 robot passes the door in only about 4 of 50 tests, where the "
              "thesis's 2.5 at trial 10 needs about half. Learning rate, output scaling, hidden units, temperature "
              "scale, repairs, other lesson sets and a linear output unit do not close it. That left the "
              "reconstructed geometry (36-in doors against a 24-in body, starts with any heading), which the "
              "text does not pin down; the two geometry studies (tables above, notes below) measure it.", "",
              "Single-layer nets (robot-single-layer against robot-teaching-*): see the table above for DP and "
              "WFL. With our 30-deg docking, docking is nearly a linear rule of the light bits (turn towards the "
              "light, drive) and easier than the thesis's (compare robot-teaching-dk without teaching with the "
              "thesis's 2 failed runs of 7); the docking-tolerance study below asks for a tighter connection.",
              "",
              *_geometry_notes(curves, seeds)]
    return "\n".join(lines)


_PANELS = {  # experiments drawn as small multiples: panel title -> [(line label, variant label)]
    "robot-dp-geometry": {f"{w}-in doors, {h}": [(f"{n} lessons", f"{w}-in doors, {h}, {n} lessons")
                                                 for n in (0, 3, 10)]
                          for w in (36, 48) for h in ("any heading", "facing +-45")},
    "robot-dk-geometry": {f"dock within {t} deg": [(f"{a}, {n} lessons", f"{t} deg, {a}, {n} lessons")
                                                   for a in ("multi-layer", "single-layer") for n in (0, 10)]
                          for t in (30, 10)},
}


def _draw_panels(spec: ExperimentSpec, curves, panels: dict, file: Path) -> Path:
    """One panel per group of variants (mean curves), shared axes, the thesis's 2.5 / 5 levels dashed."""
    import matplotlib.pyplot as plt

    from connrl.report.plots import save_figure  # (importing plots selects the Agg backend)

    n = len(panels)
    cols = 2
    fig, axes = plt.subplots((n + cols - 1) // cols, cols, figsize=(9, 3.2 * ((n + cols - 1) // cols)), dpi=110,
                             sharex=True, sharey=True, squeeze=False)
    for ax, (title, lines) in zip(axes.flat, panels.items(), strict=False):
        for i, (label, variant) in enumerate(lines):
            if (spec.name, variant) in curves:
                xs, ys, k = curves[(spec.name, variant)]
                ax.plot(xs, ys, color=f"C{i}", lw=1.5, label=f"{label} ({k} runs)")
        for y in spec.y_reference.values():
            ax.axhline(y, color="k", ls="--", lw=0.7)
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    for ax in axes[-1]:
        ax.set_xlabel(spec.x_label)
    for ax in axes[:, 0]:
        ax.set_ylabel("reinforcement / step")
    fig.suptitle(f"{spec.name} (mean over runs; dashed: 2.5 and 5)" if spec.y_reference else spec.name, fontsize=10)
    fig.tight_layout()
    save_figure(fig, file)
    plt.close(fig)
    return file


def _geometry_notes(curves, seeds: dict[str, str]) -> list[str]:
    """Generated sentences on robot-dp-geometry / robot-dk-geometry (empty when they were not run)."""
    out = []

    def curve(exp, label):
        xs, ys, _ = curves[(exp, label)]
        return list(xs), np.asarray(ys)

    def reach(label, level):
        n = first_reaching(*curve("robot-dp-geometry", label), level)
        return "not reached" if n is None else f"trial {n:g}"

    def final(exp, label):
        return float(np.mean(curve(exp, label)[1][-3:]))

    def at(label, trial):
        xs, ys = curve("robot-dp-geometry", label)
        return float(ys[xs.index(trial)]) if trial in xs else float("nan")

    combos = [f"{w}-in doors, {h}" for w in (36, 48) for h in ("any heading", "facing +-45")]
    if all(("robot-dp-geometry", f"{g}, {n} lessons") in curves for g in combos for n in (0, 3, 10)):
        def row(n, level):
            return "; ".join(f"{g}: {reach(f'{g}, {n} lessons', level)}" for g in combos)

        def mean_perf(g, n):
            return float(np.mean(curve("robot-dp-geometry", f"{g}, {n} lessons")[1]))

        best = max(combos, key=lambda g: mean_perf(g, 10))
        best10, spec10 = at(f"{best}, 10 lessons", 10), at(f"{combos[0]}, 10 lessons", 10)
        helped = mean_perf(best, 10) > mean_perf(combos[0], 10)
        ordered = all(mean_perf(g, 10) > mean_perf(g, 3) > mean_perf(g, 0) for g in combos)
        verdict = ("the geometry explains part of the gap, not all of it" if helped and not best10 >= 2.5
                   else "the geometry closes the gap at trial 10" if helped else "the geometry does not help")
        out += [f"**Door width and start heading** (`robot-dp-geometry`, seeds {seeds['robot-dp-geometry']}): "
                "the thesis gives neither. Mean-curve trials to 2.5 with 10 lessons (thesis 10): " + row(10, 2.5) +
                ". To 5 with 10 lessons (thesis 65): " + row(10, 5.0) + ". To 2.5 with 3 lessons (thesis 20): " +
                row(3, 2.5) + ". Without teaching (thesis 280): " + row(0, 2.5) + ". The facing starts apply to "
                "the 50 test tasks as well, so they make the test easier too, not only the learning. The best of "
                f"these geometries ({best}, by mean performance with 10 lessons) scores {best10:.2f} at trial 10 "
                f"with 10 lessons (SPEC geometry {spec10:.2f}; thesis 2.5), so {verdict}; the order of the "
                "teaching conditions (mean performance, 10 > 3 > 0 lessons) "
                + ("holds in every geometry." if ordered else "does not hold in every geometry."), ""]
    dk = [f"{t} deg, {a}, {n} lessons" for t in (30, 10) for a in ("multi-layer", "single-layer") for n in (0, 10)]
    if all(("robot-dk-geometry", k) in curves for k in dk):
        f = {k: final("robot-dk-geometry", k) for k in dk}

        def behind(t):  # single-layer clearly behind: below 3/4 of multi-layer's final performance
            return f[f"{t} deg, single-layer, 10 lessons"] < 0.75 * f[f"{t} deg, multi-layer, 10 lessons"]

        out += [f"**Docking tolerance** (`robot-dk-geometry`, seeds {seeds['robot-dk-geometry']}): final "
                "performance, multi-layer vs single-layer with 10 lessons: " + "; ".join(
                    f"{t} deg {f[f'{t} deg, multi-layer, 10 lessons']:.2f} vs "
                    f"{f[f'{t} deg, single-layer, 10 lessons']:.2f}" for t in (30, 10)) +
                ". Without teaching, multi-layer: " + "; ".join(
                    f"{t} deg {f[f'{t} deg, multi-layer, 0 lessons']:.2f}" for t in (30, 10)) +
                " (the thesis's failed in 2 of 7 runs, 5.4.1). Single-layer nets fall clearly behind (below 3/4 "
                "of multi-layer's final performance) " + {
                    (False, True): "only with the tighter connection, as in Fig. 5.10.",
                    (True, True): "with either tolerance, as in Fig. 5.10.",
                    (True, False): "only with the looser connection.",
                    (False, False): "with neither tolerance."}[(behind(30), behind(10))], ""]
    return out


def _speedup_tables(curves) -> list[str]:
    out = []
    rows = [("no teaching", ("robot-teaching-dp", "no teaching"), 280, None),
            ("3 taught lessons", ("robot-teaching-dp", "3 lessons"), 20, 14),
            ("10 taught lessons", ("robot-teaching-dp", "10 lessons"), 10, 28)]
    rows2 = [("lambda = 0", ("robot-lambda-dp", "lambda=0"), 280, None),
             ("lambda = 0.3", ("robot-lambda-dp", "lambda=0.3"), 140, 2.0),
             ("lambda = 0.7", ("robot-lambda-dp", "lambda=0.7"), 65, 4.3)]
    for title, level, table in (("Speedup from teaching (DP, lambda = 0.7, trials to reach 2.5)", 2.5, rows),
                                ("Speedup from lambda (DP, 10 lessons, trials to reach 5)", 5.0, rows2)):
        if not all(key in curves for _, key, _, _ in table):
            continue
        out += [f"### {title} (thesis 5.6)", "", "| | trials (ours) | speedup (ours) | trials (thesis) | "
                "speedup (thesis) |", "|---|---|---|---|---|"]
        base = None
        for label, key, t_trials, t_speed in table:
            xs, ys, _ = curves[key]
            n = first_reaching(list(xs), list(ys), level)
            if base is None:
                base = n
                sp = None
            else:
                sp = (base / n) if (base and n) else None
            out.append(f"| {label} | {_fmt(n) if n is not None else 'not reached'} | {_fmt(sp, 1)} | "
                       f"{t_trials} | {_fmt(t_speed, 1)} |")
        out.append("")
    return out


if __name__ == "__main__":
    if sys.argv[1:] == ["make-lessons"]:
        for path in write_taught_lessons():
            print(path)
    else:
        raise SystemExit("usage: python -m connrl.experiments.robot make-lessons")
