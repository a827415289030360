"""Ch. 6's bound: the fixed rule's choices on hand-made states, and the learners' own test tasks."""

import numpy as np
import pytest

import connrl.experiments.recharge as recharge
from connrl.experiments.recharge import RechargeParams, run_recharge
from connrl.experiments.recharge_bound import BoundParams, choose, fixed_test_tasks, run_bound

DOOR_B, DOOR_A = (246.0, 300.0), (114.0, 300.0)  # the doors' centres in the default layout (Fig. 5.3)


def info(room, x, y, dk=False, dp=False):
    return {"room": room, "pose": (x, y, 0.0), "applicable": np.array([dk, dp, True, True])}


@pytest.mark.parametrize("state, position, expected", [
    (info("B", 250, 200, dk=True, dp=True), True, "DK"),  # docking first, wherever it applies
    (info("B", DOOR_B[0], DOOR_B[1] - 40, dp=True), True, "DP"),  # near the door that leads on
    (info("B", DOOR_B[0], DOOR_B[1] - 80, dp=True), True, "WFL"),  # door passing applies, but far from that door
    (info("B", DOOR_B[0], DOOR_B[1] - 80, dp=True), False, "DP"),  # without position: wherever it applies
    (info("C", DOOR_A[0], DOOR_A[1] + 30, dp=True), True, "DP"),  # room C leads on through door A
    (info("C", DOOR_B[0], DOOR_B[1] + 30, dp=True), True, "WFR"),  # ... not back through door B
    (info("A", DOOR_A[0], DOOR_A[1] - 30, dp=True), True, "WFL"),  # in room A the charger is here: no door
    (info("A", DOOR_A[0], DOOR_A[1] - 30, dp=True), False, "WFL"),
])
def test_the_rule_chooses_as_written(state, position, expected):
    assert choose(BoundParams(position=position), state) == expected


def test_the_bound_plays_the_learners_own_test_tasks(monkeypatch):
    seen = []
    monkeypatch.setattr(recharge, "_test", lambda env, agent, tasks, seeds: seen.append((tasks, seeds)) or
                        {r: (0.0, 1, 0, 0) for r in "ABC"})
    monkeypatch.setattr(recharge, "_teacher", lambda world, tasks, seeds: 1.0)
    run_recharge(RechargeParams(trials=1, test_every=1, tests_per_room=2, lessons_per_trial=1, max_steps=5),
                 np.random.default_rng(7))
    tasks, seeds = fixed_test_tasks(2, np.random.default_rng(7))
    assert seen[0][0] == tasks and np.array_equal(seen[0][1], seeds)


def test_the_bound_reports_each_room_beside_the_teacher():
    m = run_bound(BoundParams(tests_per_room=1, max_steps=30), np.random.default_rng(0)).metrics
    for who in ("", "teacher_"):
        assert all(0 <= m[f"{who}docked_{r}"] <= 1 for r in "ABC")
    assert m["share_of_teacher"] == pytest.approx(m["performance"] / m["teacher_performance"])


def test_the_best_wall_followers_are_never_worse_than_the_fixed_ones():
    from connrl.experiments.recharge_bound import play, play_best_walls
    from connrl.tasks.recharge import make_recharge_env

    p = BoundParams(max_steps=120)
    env = make_recharge_env(p)
    tasks, seeds = fixed_test_tasks(1, np.random.default_rng(3))
    for (_, start), s in zip(tasks, seeds, strict=True):
        fixed, best = play(env, p, start, int(s)), play_best_walls(env, p, start, int(s))
        assert (best[0], -best[1]) >= (fixed[0], -fixed[1])


def test_the_history_rule_does_not_pass_back_through_the_door_it_came_in_by():
    from connrl.experiments.recharge_bound import RoomHistory

    p, h = BoundParams(position=False, history=True), RoomHistory()
    steps = [(info("B", *DOOR_B, dp=True), "DP"),  # room B: its only door leads on
             (info("C", DOOR_B[0], DOOR_B[1] + 20, dp=True), "WFR"),  # just out of B, door B still in sight
             (info("C", DOOR_B[0] - 30, DOOR_B[1] + 20, dp=True), "WFR"),  # still the same door
             (info("C", 180, 330), "WFR"),  # door out of sight
             (info("C", DOOR_A[0], DOOR_A[1] + 20, dp=True), "DP")]  # the next door seen: through it
    for state, expected in steps:
        h.update(state)
        assert choose(p, state, h) == expected
    for first in (None, info("A", DOOR_A[0], DOOR_A[1] - 20, dp=True)):  # a start in C, or come from A (a mistake):
        h = RoomHistory()  # DP where it applies, door A's way back included
        if first is not None:
            h.update(first)
        state = info("C", DOOR_A[0], DOOR_A[1] + 20, dp=True)
        h.update(state)
        assert choose(p, state, h) == "DP"
    with pytest.raises(ValueError, match="history applies without position"):
        BoundParams(history=True)
    with pytest.raises(ValueError, match="needs the trial's RoomHistory"):
        choose(p, info("C", *DOOR_A, dp=True))


def test_the_history_rule_remembers_along_a_played_trial(monkeypatch):
    """play() updates the memory before each choice: the rule sees the room change on the step it happens."""
    import connrl.experiments.recharge_bound as rb

    seen = []

    class World:
        def __init__(self):
            self.states = [info("B", *DOOR_B, dp=True), info("C", DOOR_B[0], DOOR_B[1] + 20, dp=True),
                           info("C", 180, 330)]

        def reset(self, seed, options):
            self.k = 0
            return None, self.states[0]

        def step(self, b):
            seen.append(BEHAVIOUR_TASKS[b])
            self.k += 1
            return None, 0.0, False, self.k == len(self.states), {**self.states[min(self.k, 2)], "success": False}

    from connrl.envs.robot.recharge import BEHAVIOUR_TASKS

    rb.play(World(), BoundParams(position=False, history=True), None, 0)
    assert seen == ["DP", "WFR", "WFR"]
