"""benchmarks/gymnasium_report.py's numbers on small hand-made runs: the median steps to a held solve (a run that
never held counts as infinitely many), the first evaluation at the threshold, and the evaluations lost after it; and
the readings of scripts/own_task/curve_shape.py and action_gaps.py on hand-made curves and values."""

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from gymnasium_report import Run, first_reach, median_held, relapses, summarize  # noqa: E402


def _run(seed, held, values, learner="QCON-R"):
    curve = [[5000 * (k + 1), v] for k, v in enumerate(values)]
    return Run("T", learner, seed, {"held": held, "curve": curve, "wall": 2.0, "cpu": 4.0, "steps": 100,
                                    "diverged": None})


def test_median_counts_a_run_that_never_held_as_more_than_any_budget():
    assert median_held([_run(0, 10_000, []), _run(1, None, []), _run(2, 30_000, [])]) == 30_000
    assert median_held([_run(0, 10_000, []), _run(1, None, []), _run(2, None, [])]) == math.inf
    assert median_held([_run(0, 10_000, []), _run(1, 20_000, [])]) == 15_000


def test_first_reach_and_the_evaluations_lost_after_it():
    a, b = _run(0, None, [1, 5, 2, 6, 7]), _run(1, None, [1, 1, 1])
    assert first_reach(a, 5) == 10_000 and first_reach(b, 5) == math.inf
    assert relapses([a, b], 5) == (1, 3)  # after 10,000 steps: 2 (below), 6, 7


def test_the_table_states_who_met_the_goal():
    runs = [_run(s, 10_000, [9] * 4) for s in range(3)]  # 100 steps in 4 CPU s: 25 steps/s
    runs += [_run(s, 20_000 if s else None, [9] * 4, "SB3-zoo") for s in range(3)]
    runs = [r._replace(doc={**r.doc, "cpu": 100.0}) if r.learner == "SB3-zoo" else r for r in runs]  # 1 step/s
    text = summarize(runs, ["T"], ["QCON-R", "SB3-zoo"], {"T": (5.0, 20_000)}, [0, 1, 2])
    assert ("T               QCON-R: met      median steps 10,000 vs 20,000 (0.50x SB3-zoo's steps); steps/s 25.0x"
            in text)
    slow = [r._replace(doc={**r.doc, "cpu": 40.0}) if r.learner == "QCON-R" else r for r in runs]  # 2.5x
    assert "not met  median steps 10,000 vs 20,000" in summarize(slow, ["T"], ["QCON-R", "SB3-zoo"],
                                                                {"T": (5.0, 20_000)}, [0, 1, 2])


def test_no_verdict_unless_both_ran_every_seed():
    runs = [_run(s, 10_000, [9]) for s in range(3)] + [_run(s, 20_000, [9], "SB3-zoo") for s in range(2)]
    text = summarize(runs, ["T"], ["QCON-R", "SB3-zoo"], {"T": (5.0, 20_000)}, [0, 1, 2])
    assert "QCON-R: no verdict: it ran seeds [0, 1, 2], SB3-zoo [0, 1]" in text and " met " not in text


def test_a_held_solve_is_the_fifth_evaluation_in_a_row_at_the_threshold_and_the_first_such():
    from bench_gymnasium import _Curve

    curve = _Curve(threshold=5.0)
    values = [5, 6, 7, 8, 4, 5, 5, 5, 5, 9, 9, 9, 9, 9, 9]  # a streak of four broken, then five from the sixth
    for k, v in enumerate(values):
        assert curve.due(5000 * (k + 1)) and not curve.due(5000 * (k + 1) - 1)
        curve.add(5000 * (k + 1), lambda v=v: [v, v])
    assert curve.held == 5000 * 10  # evaluations 6-10; the longer streak after it does not move it
    assert [v for _, v in curve.points] == values


def test_issue_47s_goal_counts_held_seeds_and_compares_wall_clock_to_the_held_solve():
    # QCON-R: 100 steps in 2 s of training, held at 40 and 60 steps on 4 of 5 seeds -> 0.8 s and 1.2 s; median of
    # [0.8, 0.8, 1.2, 1.2, inf] = 1.2 s. SB3-zoo: held at 50 steps in 10 s per 100 -> 5 s each.
    ours = [_run(s, h, [9]) for s, h in enumerate([40, 40, 60, 60, None])]
    theirs = [_run(s, 50, [9], "SB3-zoo")._replace(doc={**_run(s, 50, [9]).doc, "wall": 10.0}) for s in range(5)]
    text = summarize(ours + theirs, ["T"], ["QCON-R", "SB3-zoo"], {"T": (5.0, 20_000)}, list(range(5)))
    assert "T               QCON-R: met      held 4/5; median wall-clock to it 1.2 s vs SB3-zoo's 5.0 s" in text
    three = [r._replace(doc={**r.doc, "held": None}) if r.seed == 0 else r for r in ours]  # 3 of 5 is short
    assert "QCON-R: not met  held 3/5;" in summarize(three + theirs, ["T"], ["QCON-R", "SB3-zoo"],
                                                     {"T": (5.0, 20_000)}, list(range(5)))


def test_issue_47s_goal_is_not_met_by_a_held_solve_slower_than_sb3_zoo_nor_on_other_than_five_seeds():
    ours = [_run(s, 40, [9])._replace(doc={**_run(s, 40, [9]).doc, "wall": 20.0}) for s in range(5)]  # 8 s each
    theirs = [_run(s, 50, [9], "SB3-zoo") for s in range(5)]  # 1 s each
    text = summarize(ours + theirs, ["T"], ["QCON-R", "SB3-zoo"], {"T": (5.0, 20_000)}, list(range(5)))
    assert "QCON-R: not met  held 5/5; median wall-clock to it 8.0 s vs SB3-zoo's 1.0 s" in text
    three = summarize(ours[:3] + theirs[:3], ["T"], ["QCON-R", "SB3-zoo"], {"T": (5.0, 20_000)}, [0, 1, 2])
    assert "no verdict: the goal is stated over 5 seeds, this run has 3" in three


def test_a_longer_connrl_budget_is_shown_and_a_solve_held_after_sb3s_budget_is_not_fewer_steps():
    # connrl ran 60,000 steps and held at 40,000 on every seed; SB3-zoo ran 20,000 and never held
    ours = [_run(s, 40_000, [9] * 12) for s in range(3)]
    ours = [r._replace(doc={**r.doc, "budget": 60_000}) for r in ours]
    theirs = [_run(s, None, [1] * 4, "SB3-zoo") for s in range(3)]
    theirs = [r._replace(doc={**r.doc, "cpu": 100.0}) for r in theirs]
    text = summarize(ours + theirs, ["T"], ["QCON-R", "SB3-zoo"], {"T": (5.0, 20_000)}, [0, 1, 2])
    assert "not met  median steps > 20,000 vs > 20,000" in text  # within SB3-zoo's budget neither held
    rows = [line for line in text.splitlines() if line.startswith("T  ")]
    assert "40,000" in rows[0] and "> 20,000" in rows[1]  # each learner's own budget
    assert median_held(ours, within=40_000) == 40_000 and median_held(ours, within=39_999) == math.inf


def test_issue_47s_goal_against_an_sb3_zoo_that_never_held_needs_a_solve_sooner_than_its_whole_training():
    # SB3-zoo never held in 100 steps of 10 s of training; connrl held at 40 steps of 100 on every seed
    theirs = [_run(s, None, [1], "SB3-zoo")._replace(doc={**_run(s, None, [1]).doc, "wall": 10.0}) for s in range(5)]
    for wall, verdict, seconds in ((20.0, "met    ", "8.0 s"), (30.0, "not met", "12.0 s")):
        ours = [_run(s, 40, [9])._replace(doc={**_run(s, 40, [9]).doc, "wall": wall}) for s in range(5)]
        text = summarize(ours + theirs, ["T"], ["QCON-R", "SB3-zoo"], {"T": (5.0, 20_000)}, list(range(5)))
        assert (f"QCON-R: {verdict}  held 5/5; median wall-clock to it {seconds} vs SB3-zoo's > 10.0 s (never held "
                "in its budget)") in text


def test_curve_shape_reads_a_hand_made_curve():
    """scripts/own_task/curve_shape.py: first reach, count at the threshold, quartiles from the first reach on,
    block means, on CartPole-v1's threshold (475)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts" / "own_task"))
    from curve_shape import shape_line
    curve = [[10, 100.0], [20, 480.0], [30, 200.0], [40, 500.0], [50, 300.0]]
    line = shape_line({"task": "CartPole-v1", "seed": 7, "wall": 3.0, "curve": curve}, block=20)
    # from the first reach on: 480, 200, 500, 300 -> quartiles 275, 390, 485; blocks (0,20], (20,40], (40,60]
    assert "first at        20    2 of 5 at it" in line
    assert "from first on: median 390 (quartiles 275, 485)" in line
    assert line.endswith("block means: 290 350 300")
    never = shape_line({"task": "CartPole-v1", "seed": 7, "wall": 3.0, "curve": [[10, 1.0], [20, 5.0]]}, block=50)
    assert "first at     never    0 of 2 at it" in never and "all: median 3 (quartiles 2, 4)" in never


def test_curve_shape_reads_a_run_over_its_first_steps():
    """curve_shape.py --until: the held solve (five evaluations in a row at 475), the area and the wall-clock at the
    run's mean rate, counted over the evaluations up to the given step only."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts" / "own_task"))
    from curve_shape import until_line
    curve = [[k * 10, v] for k, v in enumerate([480, 100, 480, 490, 500, 475, 476, 0, 0], start=1)]
    doc = {"task": "CartPole-v1", "seed": 7, "wall": 90.0, "steps": 90, "curve": curve}
    line, held, area = until_line(doc, 70)  # 480 100 480 490 500 475 476: in a row from 30, the fifth at 70
    assert held == 70 and area == (480 + 100 + 480 + 490 + 500 + 475 + 476) / 7
    assert line == f"seed    7  held at        70  area {area:.1f}  wall 70 s"
    line, held, _ = until_line(doc, 60)  # four in a row only
    assert held is None and "held at     never" in line


def test_action_gaps_are_best_minus_second_at_each_visited_state():
    """scripts/own_task/action_gaps.py's gaps_of on a stub agent and a two-step world (values written by hand)."""
    from contextlib import nullcontext
    from types import SimpleNamespace

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts" / "own_task"))
    from action_gaps import gaps_of
    table = {0: [1.0, 4.0, 2.5], 1: [-3.0, -1.0, -1.5]}  # gaps 1.5 and 0.5

    class World:
        def reset(self, seed=None):
            self.t = 0
            return 0, {}

        def step(self, action):
            self.t += 1
            return self.t, 10.0 * action, self.t == 2, False, {}

    agent = SimpleNamespace(greedy_weights=nullcontext, scaler=SimpleNamespace(encode=lambda o: o),
                            learner=SimpleNamespace(q=SimpleNamespace(values=lambda x: np.array(table[x]))))
    gaps, returns = gaps_of(agent, World(), episodes=2)
    assert gaps.tolist() == [1.5, 0.5, 1.5, 0.5] and returns == [20.0, 20.0]  # greedy: action 1 then 1


def test_input_spread_reads_each_unit_under_both_codes():
    """scripts/own_task/input_spread.py on CartPole-v1: by the spread every moving unit's code has standard deviation
    0.5 (two standard deviations reach 1); by the bounds, a bounded unit's is its raw spread over the half-range (cart
    position +-4.8, pole angle +-0.418) and an unbounded one's is 0.5 again."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts" / "own_task"))
    from input_spread import spreads
    raw, coded = spreads("CartPole-v1", 3)
    np.testing.assert_allclose(coded["spread"], 0.5, rtol=1e-9)
    half = np.array([4.8, np.nan, 0.41887903, np.nan])
    np.testing.assert_allclose(coded["bounds"][[0, 2]], raw[[0, 2]] / half[[0, 2]], rtol=1e-6)
    np.testing.assert_allclose(coded["bounds"][[1, 3]], 0.5, rtol=1e-9)
