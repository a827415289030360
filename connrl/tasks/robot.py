"""Ch. 5 wiring: the robot task worlds of a parameter set, the scripted teachers' taught lessons (3.7, 5.4), and
QCON-T (5.3) with its taught lessons; ``evaluate`` is the greedy test of 5.4.

The builders take ``RobotParams``, declared here beside them: each parameter once, with its range and where the
thesis states it (``connrl.core.params.param``).

Values marked (R) are reconstructions; docs/RECONSTRUCTION.md, "HEROINE robot world", gives each with its reason.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, fields
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from connrl.agents import LinearSchedule, QCONConfig, ReplayConfig
from connrl.agents.base import TAUGHT_ORDERS  # noqa: F401  (experiments see the learner through tasks)
from connrl.agents.teaching import TeachingConfig, TeachingQCON
from connrl.core.exploration import StuckConfig, TemperatureSchedule
from connrl.core.lesson_files import load_lessons, save_lessons
from connrl.core.lessons import Lesson
from connrl.core.params import check_types, param
from connrl.core.replay import REPAIRS
from connrl.core.rollout import run_trial
from connrl.envs.robot import OBS_SIZE, ROBOT_RADIUS, SONAR_MAX, Layout, RobotTaskEnv, teach
from connrl.envs.robot.constants import (
    COLLISION,
    DOOR_EDGE_JUMP,
    DP_FAR,
    DP_LATERAL,
    EDGE_MARK,
    PASS_DEPTH,
    SONAR_ORIGIN,
)
from connrl.envs.robot.sim import COLLISIONS, EDGE_MARKS, SONAR_ORIGINS
from connrl.nets import NetConfig
from connrl.tasks import robot_play

LESSON_DIR = Path(__file__).resolve().parent.parent / "data" / "lessons"
TAUGHT_COUNTS = {"DP": 10, "DK": 10, "WFL": 5, "WFR": 5}  # lessons shipped per task (5.4.1; WFR for Ch. 6)
# The world the shipped taught lessons were made in: the default layout's doors, docking, door edges, starts.
SHIPPED_WORLD = {"door_width": float(Layout.load("default").doors["A"].width), "dock_tolerance": 30.0,
                 "edge_jump": float(DOOR_EDGE_JUMP), "spread": False, "sonar_origin": SONAR_ORIGIN,
                 "collision": COLLISION, "edge_mark": EDGE_MARK, "dp_lateral": DP_LATERAL, "pass_depth": PASS_DEPTH}
# The world details each task's demonstrations depend on (the rest are put back to the shipped values, so a change
# elsewhere still reads the file): docking happens away from the doors, only DP sees door edges and DP starts.
_TASK_WORLD = {"DP": ("door_width", "edge_jump", "spread", "sonar_origin", "collision", "edge_mark", "dp_lateral",
                      "pass_depth"),
               "DK": ("dock_tolerance", "sonar_origin", "collision"),
               "WFL": ("door_width", "sonar_origin", "collision"), "WFR": ("door_width", "sonar_origin", "collision")}
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
# The teacher's DP starts lie 24..LESSON_FAR in from the door's wall (R): the band of the worlds before issue 44,
# kept so the default world's lessons are the ones its predictions were measured with.
LESSON_FAR = 72.0


MAX_TAUGHT = 200  # taught lessons an agent may ask for: the shipped ones, then fresh demonstrations

@dataclass(frozen=True)
class RobotParams:
    """One Ch. 5 run: the thesis's values where it states them (5.3, 5.4), else marked R (reconstructed; see
    docs/RECONSTRUCTION.md, "HEROINE robot world" and "Learners and protocols")."""

    task: str = param("DP", note="'DP' | 'DK' | 'WFL' (5.4) | 'WFR' (Ch. 6's behaviour library)",
                      choices=("DP", "DK", "WFL", "WFR"))
    lessons: int = param(10, ">=0", "taught lessons given to the agent (5.4.1: 0/3/10 DP, DK; 0/2/5 WFL)")
    hidden_fraction: float = param(0.3, ">=0", "hidden units ~ 30 % of inputs (5.3.3); 0 = single-layer (5.4.4)")
    lr: float = param(0.05, ">0", "back-propagation learning rate (5.3.3; 5.4.4: 0.04 DP/DK, 0.03 WFL)")
    momentum: float = param(0.9, "0..<1", "(5.3.3; 5.4.4: 0)")
    init_range: float = param(0.5, ">0", "initial weights in +-0.5 (5.3.3)")
    value_range: float = param(100.0, ">0", "Q in +-100 (5.3.1)")
    binary_low: float = param(-0.5, note="binary inputs +-0.5 (5.3.2); 0 -> 0/1 (5.4.4)")
    gamma: float = param(0.9, "0..1", "(5.3.1)")
    lam: float = param(0.7, "0..1", "(5.4.1)")
    t_start: float = param(0.05, ">0", "T: 0.05 -> 0.02 over the run (5.3.4), on Q / value_range")
    t_end: float = param(0.02, ">0")
    online: bool = param(True, note="Q-learning on each step as well as replay (Fig. 3.4, R)")
    capacity: int = param(100, ">=1", "latest lessons kept for replay (App. A.2, R for Ch. 5)")
    lessons_per_trial: int = param(60, ">=0", "experienced lessons replayed after each trial (5.3.5)")
    p_threshold: float = param(0.02, "0..<1", "P_l: non-policy threshold (5.3.5)")
    repair: str = param("none", note="'none' | 'lower' | 'raise' (5.4.3)", choices=REPAIRS)
    taught_order: str = param("after", note="taught lessons replayed 'after' the experienced ones or 'shuffled' among "
                              "them (R)", choices=TAUGHT_ORDERS)
    stuck_window: int = param(8, ">=1", "stuck detection (5.3.4, R): last 8 positions ...")
    stuck_radius: float = param(12.0, ">=0", "... within 12 in (one move) of their mean ...")
    stuck_boost: float = param(5.0, ">0", "... multiply T by 5")
    trials: int = param(300, ">=1", "trials per run (5.4)")
    max_steps: int = param(30, ">=1", "steps per trial and per test (5.4)")
    test_every: int = param(10, ">=1", "test after every 10 trials (5.4)")
    test_tasks: int = param(50, ">=1", "fixed test tasks per run (5.4)")
    paths: int = param(0, ">=0", "greedy solution paths recorded at the end of the run (Figs. 5.5-5.7)")
    linear_output: bool = param(False, note="single-layer nets only: linear output unit (7.4's linear OAON; "
                                "diagnostic)")
    door_width: float = param(SHIPPED_WORLD["door_width"], note="doorway width, in: the layout's 49 (R, issue 44; "
                              "SPEC 36)")
    dp_heading: float = param(180.0, "0..180", "DP starts face within +-this many deg of the door (180 = any heading, "
                              "5.4)")
    dock_tolerance: float = param(30.0, "0..180", "DK: a head-on charger contact within this many deg docks (R; "
                                  "robot-dk-geometry)")
    dp_far: float = param(DP_FAR, note="DP starts lie 24..dp_far in from the door's wall (R)")
    edge_jump: float = param(SHIPPED_WORLD["edge_jump"], ">0", "readings this far apart mark a door edge (R, Fig. "
                             "5.3b; SPEC 24)")
    lesson_starts: str = param("random", note="DP teacher's starts: 'random' headings or 'spread' (hand-picked, R)",
                               choices=("random", "spread"))
    # issue 44's world family (R; docs/RECONSTRUCTION.md, "The robot world as a family")
    sonar_origin: str = param(SHIPPED_WORLD["sonar_origin"], note="sonar distances from the 'body' surface or the "
                              "'centre'", choices=SONAR_ORIGINS)
    collision: str = param(SHIPPED_WORLD["collision"], note="a touching move is 'cancel'led or made 'partial'ly to "
                           "the contact", choices=COLLISIONS)
    edge_mark: str = param(SHIPPED_WORLD["edge_mark"], note="a door-edge jump marks the 'nearer' reading or 'both'",
                           choices=EDGE_MARKS)
    dp_lateral: float = param(SHIPPED_WORLD["dp_lateral"], note="DP starts within +-this x half the door width of its "
                              "centre")
    pass_depth: float = param(SHIPPED_WORLD["pass_depth"], note="DP succeeds this far past the door line (0: in the "
                              "other room)")
    noise: bool = param(True, note="sensing and control noise of 5.2.1, in training and in the tests")

    def __post_init__(self):
        check_types(self)
        if not 0.25 <= self.dp_lateral <= 3.0:
            raise ValueError(f"parameter dp_lateral must be in [0.25, 3] (DP starts within +-dp_lateral x half the "
                             f"door width of its centre), got {self.dp_lateral}")
        if not 0.0 <= self.pass_depth <= 48.0:
            raise ValueError(f"parameter pass_depth must be in [0, 48] (in past the door line), got {self.pass_depth}")
        if not self.door_width > 2 * ROBOT_RADIUS:
            raise ValueError(f"parameter door_width must exceed the robot's diameter ({2 * ROBOT_RADIUS:g} in), "
                             f"got {self.door_width}")

        if not 24.0 <= self.dp_far <= 96.0:
            raise ValueError(f"parameter dp_far must be in [24, 96] (in; DP starts lie 24..dp_far from the door's "
                             f"wall, near the door), got {self.dp_far}")
        if self.edge_jump > SONAR_MAX:
            raise ValueError(f"parameter edge_jump must be at most {SONAR_MAX} (the sonar's range; above it no door "
                             f"edge is ever seen), got {self.edge_jump}")
        if self.lessons > MAX_TAUGHT:
            raise ValueError(f"parameter lessons must be at most {MAX_TAUGHT} (beyond the shipped "
                             f"{TAUGHT_COUNTS[self.task]} the teacher demonstrates afresh), got {self.lessons}")

    def check_combination(self):
        defaults = {f.name: f.default for f in fields(RobotParams)}
        dp_only = [k for k in ("dp_heading", "dp_far", "lesson_starts", "edge_jump", "edge_mark", "dp_lateral",
                               "pass_depth") if getattr(self, k) != defaults[k]]
        if self.task != "DP" and dp_only:
            raise ValueError(f"parameter(s) {', '.join(dp_only)} apply to task DP only (its start region, teacher "
                             f"and door-edge inputs), got task {self.task}")


def lesson_path(task: str) -> Path:
    return LESSON_DIR / f"robot-{task.lower()}.json"


def make_env(p: RobotParams) -> RobotTaskEnv:
    """The task environment of a parameter set (the layout's doors resized when ``door_width`` asks)."""
    layout = Layout.load("default")
    if p.door_width != SHIPPED_WORLD["door_width"]:
        layout = layout.with_door_width(p.door_width)
    return RobotTaskEnv(p.task, layout=layout, binary_low=p.binary_low, max_steps=p.max_steps,
                        dp_heading=p.dp_heading, dp_depth=(24.0, p.dp_far), dock_tolerance=p.dock_tolerance,
                        edge_jump=p.edge_jump, noise=p.noise, sonar_origin=p.sonar_origin, collision=p.collision,
                        edge_mark=p.edge_mark, dp_offset=p.dp_lateral * p.door_width / 2.0, pass_depth=p.pass_depth)


def world_of(p: RobotParams) -> dict:
    """The world details of a parameter set, keyed as SHIPPED_WORLD (``spread``: DP lessons from spread starts)."""
    return {"door_width": p.door_width, "dock_tolerance": p.dock_tolerance, "edge_jump": p.edge_jump,
            "spread": p.lesson_starts == "spread", "sonar_origin": p.sonar_origin, "collision": p.collision,
            "edge_mark": p.edge_mark, "dp_lateral": p.dp_lateral, "pass_depth": p.pass_depth}


def spread_heading(start: tuple, k: int, layout: Layout) -> tuple:
    """The k-th hand-picked start (R): the drawn position, the heading turned from the bearing of the nearest door
    by the golden-ratio sequence 0, 222, 85, 307, ... deg, so any first few lessons face the door from many angles,
    turn-arounds included (5.4: "a manually-chosen start position")."""
    x, y, _ = start
    door = min(layout.doors.values(), key=lambda d: math.hypot(d.center[0] - x, d.center[1] - y))
    bearing = math.degrees(math.atan2(door.center[1] - y, door.center[0] - x))
    return (x, y, (bearing + 360.0 * ((k * GOLDEN) % 1.0)) % 360.0)


def make_taught_lessons(task: str, n: int | None = None, seed: int = 0, max_tries: int = 200,
                        env: RobotTaskEnv | None = None, spread: bool = False) -> list[Lesson]:
    """Demonstrations by the scripted teacher of ``task`` from start poses drawn with ``seed``.

    DP and DK keep only demonstrations that reach the goal (the thesis's "positive examples", 5.4.1);
    WFL keeps every 30-step demonstration. Deterministic given ``seed``. ``env`` (default: ``lesson_env`` in the
    shipped world, the recipe of the lesson files) sets the geometry the teacher demonstrates in. ``spread`` (DP): the
    k-th lesson's heading is set by ``spread_heading`` instead of drawn.
    """
    n = TAUGHT_COUNTS[task] if n is None else n
    env = lesson_env(task, SHIPPED_WORLD) if env is None else env
    rng = np.random.default_rng(seed)
    out: list[Lesson] = []
    for i in range(max_tries):
        if len(out) == n:
            break
        start = env.sample_task(rng)
        if spread:
            start = spread_heading(start, len(out), env.layout)
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
    """Regenerate connrl/data/lessons/robot-{dp,dk,wfl}.json (``connrl make-lessons robot``)."""
    paths = []
    for task in TAUGHT_COUNTS:
        lessons = make_taught_lessons(task, seed=seed)
        p = lesson_path(task)
        save_lessons(p, lessons, env_id=f"connrl/Robot-{task}-v0", env_kwargs={},
                     source=f"connrl.tasks.robot.make_taught_lessons({task!r}, n={len(lessons)}, "
                            f"seed={seed}): scripted teacher, not a person")
        paths.append(p)
    return paths


def binary_columns(task: str) -> np.ndarray:
    """Indices of the binary inputs of a task's observation (see connrl.envs.robot)."""
    if task in ("DK", "DP"):
        return np.arange(24, 52)
    return np.r_[24:28, 30:36]


@functools.lru_cache(maxsize=8)
def _demonstrated(task: str, n: int, world: tuple) -> tuple[Lesson, ...]:
    """The shipped lessons' recipe (seed 0, the default start region with any heading, 30 steps) in another world
    or for more lessons than the file has; cached per process (callers copy the inputs before changing them)."""
    w = dict(world)
    return tuple(make_taught_lessons(task, n, seed=0, env=lesson_env(task, w), max_tries=max(200, 20 * n),
                                     spread=w["spread"]))


def lesson_env(task: str, world: dict) -> RobotTaskEnv:
    """Where the scripted teacher demonstrates: the world's details, DP starts 24..LESSON_FAR in out, any heading."""
    w = {k: v for k, v in world.items() if k != "spread"}
    return make_env(SimpleNamespace(task=task, binary_low=-0.5, max_steps=30, dp_heading=180.0, dp_far=LESSON_FAR,
                                    noise=True, **w))


def taught_lessons(task: str, n: int, binary_low: float = -0.5, **world) -> list[Lesson]:
    """The first ``n`` taught lessons of ``task``, re-encoded for ``binary_low`` (files use -0.5/+0.5).

    ``world``: details of SHIPPED_WORLD that differ (e.g. ``door_width=36``). In the world of the shipped lessons,
    and for at most as many as the file has, they are read from the file; otherwise the same scripted teacher
    demonstrates afresh (same seed and starts, deterministic), so the first lessons of a longer list are the file's.
    """
    if n == 0:
        return []
    unknown = set(world) - set(SHIPPED_WORLD)
    if unknown:
        raise TypeError(f"taught_lessons: unknown world detail(s) {sorted(unknown)}; known: {sorted(SHIPPED_WORLD)}")
    full = {**SHIPPED_WORLD, **world}
    full = {k: (type(SHIPPED_WORLD[k])(v) if k in _TASK_WORLD[task] else SHIPPED_WORLD[k]) for k, v in full.items()}
    if full != SHIPPED_WORLD or n > TAUGHT_COUNTS[task]:
        lessons = _demonstrated(task, n, tuple(full.items()))
    else:
        lessons = load_lessons(lesson_path(task), env_id=f"connrl/Robot-{task}-v0", input_dim=OBS_SIZE[task],
                               n_actions=6)
        if n > len(lessons):
            raise ValueError(f"{task}: {n} taught lessons asked for, the file has {len(lessons)}")
    out = []
    for lesson in lessons[:n]:
        x = lesson.inputs.copy()
        x[:, binary_columns(task)] += binary_low + 0.5
        out.append(Lesson(x, lesson.actions, lesson.rewards, lesson.terminated, lesson.truncated, True,
                          dict(lesson.meta)))
    return out


def make_agent(p: RobotParams, rng: np.random.Generator) -> TeachingQCON:
    """QCON-T of 5.3 from the run's parameters; ``linear_output``:
    single-layer nets with a linear output unit."""
    n_in = OBS_SIZE[p.task]
    hidden = int(round(p.hidden_fraction * n_in))
    net = NetConfig(n_in, hidden, value_range=p.value_range, init_range=p.init_range, lr=p.lr,
                    momentum=p.momentum, linear_output=bool(p.linear_output) and hidden == 0)
    replay = ReplayConfig(capacity=p.capacity,
                          lessons_per_trial=LinearSchedule(p.lessons_per_trial, p.lessons_per_trial),
                          p_threshold=p.p_threshold, taught_order=p.taught_order)
    cfg = QCONConfig(net=net, temperature=TemperatureSchedule.direct(p.t_start, p.t_end, p.trials),
                     gamma=p.gamma, lam=p.lam, online=p.online, replay=replay,
                     stuck=StuckConfig(p.stuck_window, p.stuck_radius, p.stuck_boost))
    agent = TeachingQCON(cfg, 6, rng, TeachingConfig(repair=p.repair, merit_scale=p.value_range))
    agent.add_taught_lessons(taught_lessons(p.task, p.lessons, p.binary_low, **world_of(p)))
    return agent


def teacher_score(env: RobotTaskEnv, tasks, seeds) -> tuple[float, int]:
    """The scripted teacher (true pose) on fixed tasks: reinforcement per step as ``evaluate``, and its successes."""
    total, steps, successes = 0.0, 0, 0
    for start, seed in zip(tasks, seeds, strict=True):
        lesson = teach(env, start, seed=int(seed))
        total += sum(s[2] for s in lesson)
        steps += len(lesson)
        successes += bool(lesson[-1][4])
    return total / steps, successes


def evaluate(env: RobotTaskEnv, agent, tasks, seeds, max_steps: int, paths: list | None = None) -> float:
    """Greedy test on fixed tasks: total reinforcement / total steps (5.4)."""
    total, steps = 0.0, 0
    fast = robot_play.compiled(env, agent)  # the same plays, compiled (connrl.tasks.robot_play)
    for i, (start, s) in enumerate(zip(tasks, seeds, strict=True)):
        if fast:
            stats = robot_play.greedy_play(env, agent, int(s), start, max_steps)
        else:
            stats = run_trial(env, agent, trial=0, learning=False, seed=int(s), options={"start": start},
                              max_steps=max_steps)
        total += stats.total_reward
        steps += stats.steps
        if paths is not None and i < len(paths):
            paths[i] = {"poses": [[round(v, 2) for v in pose] for pose in env.trace],
                        "success": bool(stats.info.get("success")), "reward": stats.total_reward}
    return total / max(steps, 1)
