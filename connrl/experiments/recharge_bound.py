"""Ch. 6's bound: what a fixed rule over the behaviour library achieves on the learners' own test tasks (ours).

The high-level learner of Exps 2-4 can do no better than the best choice among the shipped behaviours, so a low Ch. 6
result has two possible causes: the behaviours cannot reach the charger in time, or the learner does not find the
choice that does. This experiment separates them. A fixed rule, reading the true room and position (which the learner
has only through its inputs), plays the recharging task of ``connrl.experiments.recharge`` on exactly the test tasks a
learning run of the same seed and ``tests_per_room`` is tested on:

- DK (docking) whenever it is applicable;
- else DP (door passing) when it is applicable within ``near_door`` inches of the door that leads on towards the
  charger (room B: door B into C; room C: door A into A);
- else the room's wall follower (``wall_A`` / ``wall_B`` / ``wall_C``: WFL or WFR; chosen on the development seeds
  100-106, docs/RECONSTRUCTION.md, "Ch. 6 bound").

The variant without position takes DP wherever it is applicable outside room A: what a rule that knows only its room
can do, the hidden state 6.4.2 adds X-Y against. The variant with room history (Ch. 8's counterpart, 8.1) has no
position either, but remembers the room it came from: in room C, come from room B, it refuses DP while door B is
still in sight (DP has stayed applicable since it entered), so a robot out of room B does not pass straight back. It
is what a memory of a few steps can add where the two doorways of room C look alike. The variant with the best wall
followers plays every one of the 8 choices of (``wall_A``, ``wall_B``, ``wall_C``) on each task and keeps the best
(docked first, then fewest steps): an oracle that knows which way round each room is shorter from where it starts,
as a learner reading X-Y could.
Reported per start room: the share of test tasks docked, the mean primitive steps of those that dock, reinforcement
per step, and the scripted teacher's on the same tasks.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np

from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, ROOMS, sample_in_room
from connrl.envs.robot.teachers import teach_chg
from connrl.experiments.recharge import LAYOUT
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant
from connrl.tasks.recharge import WALLS, BoundParams, make_recharge_env  # noqa: F401  (re-exported)

LEADS_ON = {"B": "B", "C": "A"}  # the door out of a room towards the charger (in room A)


def fixed_test_tasks(tests_per_room: int, rng: np.random.Generator) -> tuple[list, np.ndarray]:
    """The fixed test tasks (room, start) and their seeds, drawn as ``connrl.experiments.recharge.run_rooms`` draws
    them first from a run's generator: the same seed and ``tests_per_room`` give the same tasks."""
    task_rng = np.random.default_rng(rng.integers(2**63))
    tasks = [(r, sample_in_room(task_rng, LAYOUT, r)) for r in ROOMS for _ in range(tests_per_room)]
    return tasks, task_rng.integers(2**31, size=len(tasks))


class RoomHistory:
    """What the history rule remembers along a trial: the room it is in, the room it came from, and whether the door
    it came in by is still in sight (DP has stayed applicable since it entered). A trial's start has come from no
    room."""

    def __init__(self):
        self.room, self.came_from, self.door_in_sight = None, None, False

    def update(self, info: dict) -> None:
        dp = bool(info["applicable"][BEHAVIOUR_TASKS.index("DP")])
        if self.room is not None and info["room"] != self.room:
            self.came_from, self.door_in_sight = self.room, dp  # just came through a door
        self.room = info["room"]
        self.door_in_sight &= dp


def choose(p: BoundParams, info: dict, history: RoomHistory | None = None) -> str:
    """The rule's behaviour in the state of ``info`` (module docstring); ``history``, updated with ``info`` already,
    for the history rule."""
    applicable = dict(zip(BEHAVIOUR_TASKS, info["applicable"], strict=True))
    room = info["room"]
    if applicable["DK"]:
        return "DK"
    if applicable["DP"] and room in LEADS_ON:
        if p.history:
            if history is None:
                raise ValueError("the history rule (history=True) needs the trial's RoomHistory, updated with info")
            if room == "C" and history.came_from == "B" and history.door_in_sight:
                return p.wall_C  # not straight back into room B
        if not p.position:
            return "DP"
        (x0, y0, x1, y1) = LAYOUT.doors[LEADS_ON[room]].segment
        if math.dist(info["pose"][:2], ((x0 + x1) / 2, (y0 + y1) / 2)) < p.near_door:
            return "DP"
    return {"A": p.wall_A, "B": p.wall_B, "C": p.wall_C}[room]


def play(env, p: BoundParams, start, seed: int) -> tuple[bool, int, float]:
    """One test task under the rule: (docked, primitive steps, total reinforcement)."""
    _, info = env.reset(seed=seed, options={"start": start})
    total, steps, history = 0.0, 0, RoomHistory()
    while True:
        history.update(info)
        _, r, terminated, truncated, info = env.step(BEHAVIOUR_TASKS.index(choose(p, info, history)))
        total, steps = total + r, steps + 1
        if terminated or truncated:
            return bool(info["success"]), steps, total


def play_best_walls(env, p: BoundParams, start, seed: int) -> tuple[bool, int, float]:
    """The task under each of the 8 wall-follower choices; the best play: docked first, then fewest steps."""
    plays = [play(env, dataclasses.replace(p, wall_A=a, wall_B=b, wall_C=c), start, seed)
             for a, b, c in itertools.product(WALLS, repeat=3)]
    return min(plays, key=lambda x: (not x[0], x[1], -x[2]))


def run_bound(p: BoundParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    tasks, seeds = fixed_test_tasks(p.tests_per_room, rng)
    env = make_recharge_env(p)
    by_room = {r: [] for r in ROOMS}
    teacher = {r: [] for r in ROOMS}
    for i, ((room, start), s) in enumerate(zip(tasks, seeds, strict=True)):
        by_room[room].append((play_best_walls if p.best_walls else play)(env, p, start, int(s)))
        lesson = teach_chg(env.world, start, seed=int(s))
        teacher[room].append((bool(lesson[-1][4]), len(lesson), sum(step[2] for step in lesson)))
        progress(i + 1, len(tasks))
    metrics = {}
    for who, results in (("", by_room), ("teacher_", teacher)):
        for r in ROOMS:
            docked = [n for ok, n, _ in results[r] if ok]
            metrics[f"{who}docked_{r}"] = len(docked) / len(results[r])
            metrics[f"{who}steps_{r}"] = float(np.mean(docked)) if docked else None
        plays = [x for r in ROOMS for x in results[r]]
        metrics[f"{who}performance"] = sum(t for _, _, t in plays) / sum(n for _, n, _ in plays)
    teacher_perf = metrics["teacher_performance"]  # 0 when the teacher cannot dock within max_steps (tiny profile)
    metrics["share_of_teacher"] = metrics["performance"] / teacher_perf if teacher_perf else None
    rows = [{"room": i, "docked": metrics[f"docked_{r}"], "teacher_docked": metrics[f"teacher_docked_{r}"]}
            for i, r in enumerate(ROOMS)]
    return RunResult([0, 1, 2], [metrics[f"docked_{r}"] for r in ROOMS], metrics, rows)


def _q(name, text, better="higher"):
    return Quantity(name, text, better, "6.6")


QUANTITIES = (*(_q(f"docked_{r}", f"share of the test tasks from room {r} the rule docks") for r in ROOMS),
              *(_q(f"steps_{r}", f"mean primitive steps of the rule's dockings from room {r}", "lower") for r in ROOMS),
              _q("performance", "the rule's reinforcement per primitive step over all test tasks"),
              _q("share_of_teacher", "the rule's performance as a share of the scripted teacher's"),
              *(_q(f"teacher_docked_{r}", f"share of the test tasks from room {r} the scripted teacher docks")
                for r in ROOMS),
              *(_q(f"teacher_steps_{r}", f"the scripted teacher's mean steps to dock from room {r}", "lower")
                for r in ROOMS),
              _q("teacher_performance", "the scripted teacher on the same test tasks"))

CHAPTER = 6  # the thesis chapter of these experiments (`connrl reproduce --chapters`)
EXPERIMENTS = [
    ExperimentSpec(
        name="recharge-bound", title="Ch. 6 bound: a fixed rule over the behaviour library on the learners' test "
        "tasks", section="6.6 (ours)", run="connrl.experiments.recharge_bound:run_bound", params=BoundParams(),
        profiles={"tiny": {"runs": 1, "tests_per_room": 1, "max_steps": 20}, "quick": {"runs": 2},
                  "full": {"runs": 7}},
        variants=(Variant("rule with position", {"position": True}),
                  Variant("rule without position", {"position": False}),
                  Variant("rule without position, with room history", {"position": False, "history": True}),
                  Variant("rule with position, best wall followers per task", {"position": True,
                                                                                "best_walls": True})),
        quantities=QUANTITIES, x_label="start room (0 = A, 1 = B, 2 = C)", y_label="share of test tasks docked",
        description="ours: what the shipped behaviours can do under a fixed rule that knows the room and position, "
                    "on the test tasks of recharge-behaviours (same seeds); separates 'the behaviours cannot' from "
                    "'the learner does not'"),
]
