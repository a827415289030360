"""Thesis 6.2 measured: action executions to learn a deterministic grid world, flat and hierarchical (Table 6.1).

Each run (one seed) takes d-dimensional grids of about n = 3^j states for j in ``j_min..j_max`` (side the nearest
integer to 3^(j/d)) and counts the action executions each learner needs before its policy is
optimal (flat) or its hierarchy is complete:
- flat (6.2.1): a complete model by exploration (``connrl.core.model_learning``); the policy then follows by
  planning, which costs no executions;
- single level (6.2.2): cubes of ``block`` states a side, their centres as subgoals, abstract actions learnt from
  resets within l = block steps, then the abstract level (``connrl.core.hierarchy.single_level``); the blocks of
  ``candidate_blocks`` are tried, the cheapest is run again on a fresh seed for its reported cost, and the thesis's
  optimal k is reported beside it;
- multi level (6.2.3): the nested hierarchy of 3 x 3 (x 3) regions up to one centre (``multi_level``), on the
  sides that are powers of 3;
- an additional task (6.2.2, end), on the hierarchy of the thesis's k: a new goal inside the abstract space (the
  abstract level learnt again) and outside it (a new abstract action for it, then the abstract level with it
  added).
The exploration ``rule`` is greedy mapping (a Koenig-style rule) or a random walk. The single level's policy (the
thesis's k) is checked against exact shortest paths (BFS): the mean ratio of its path length through subgoals (to
the nearest centre, then along the abstract level) to the shortest. Exponents are least-squares slopes of
log(executions) on log(n) over the sizes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from connrl.core.hierarchy import abstract_graph, ball, multi_level, overhead, single_level
from connrl.core.model_learning import RULES, learn_model
from connrl.envs.grid import GridWorld
from connrl.experiments.spec import ExperimentSpec, Quantity, RunResult, Variant, check_types, override, param

LEARNERS = ("flat", "single", "multi", "additional_inside", "additional_outside")


@dataclass(frozen=True)
class ComplexityParams:
    dim: int = param(2, ">=1", "grid dimension d (1 or 2)", choices=(1, 2))
    rule: str = param("greedy", note="exploration: 'greedy' mapping or 'random' walk", choices=RULES)
    j_min: int = param(4, ">=1", "n = 3^j_min .. 3^j_max states (81 .. 59049)")
    j_max: int = param(10, ">=1")
    block_max: int = param(9, ">=1", "single level: odd region sides 3..block_max (below the grid's side) tried")
    max_states: int = param(10**6, ">=1", "sizes above this are skipped (the tiny and quick profiles' cap)")

    def __post_init__(self):
        check_types(self)
        if self.j_max < self.j_min or self.j_max > 12:
            raise ValueError(f"parameters j_min..j_max must satisfy j_min <= j_max <= 12 (n = 3^j states), got "
                             f"{self.j_min}..{self.j_max}")



def thesis_block(n: int, dim: int) -> int:
    """The region side of the thesis's optimal k (6.2.2): k = 7.8 n^0.6 for d = 2; for d = 1 the same derivation
    (l = n/k, m = 4 n/k, cost 16 n^2/k + n k) gives k = 4 sqrt(n). Rounded to an odd side >= 3."""
    k = 7.8 * n ** 0.6 if dim == 2 else 4.0 * n ** 0.5
    side = (n / k) ** (1.0 / dim)
    return max(3, int(2 * round((side - 1) / 2) + 1))


def candidate_blocks(side: int, block_max: int, thesis: int) -> list[int]:
    """Region sides tried for the single level: every odd one 3..block_max, then odd sides growing by about half up
    to 4 sqrt(side) (so the cheapest is found beyond block_max too), and the thesis's."""
    out, b = set(range(3, min(block_max, side - 1) + 1, 2)), block_max
    while True:
        b = int(b * 1.5) | 1
        if b > min(side // 2, 4 * side ** 0.5):
            break
        out.add(b)
    if thesis < side:
        out.add(thesis)
    return sorted(x for x in out if 3 <= x < side)


def additional_task(g: GridWorld, centres: np.ndarray, block: int, rng: np.random.Generator, rule: str):
    """(inside, outside): executions for a new goal that is a centre (the abstract level again) and one that is not
    (its own abstract action from resets within ``block`` steps, then the abstract level with it added)."""
    a_succ, a_cost = abstract_graph(g.next_state, centres, block)
    inside = learn_model(a_succ, cost=a_cost, seed=int(rng.integers(2**31)), rule=rule)
    others = np.setdiff1d(np.arange(g.n), centres)
    goal = int(others[rng.integers(others.size)]) if others.size else int(centres[0])
    states, _ = ball(g.next_state, goal, block)
    target = np.zeros(g.n, dtype=bool)
    target[states] = True
    own = learn_model(g.next_state, target=target, starts=states, episode=block, stop_at=goal,
                      seed=int(rng.integers(2**31)), rule=rule)
    b_succ, b_cost = abstract_graph(g.next_state, np.append(centres, goal), block)
    return inside, own + learn_model(b_succ, cost=b_cost, seed=int(rng.integers(2**31)), rule=rule)


def _slope(ns, ys) -> tuple[float, float]:
    """Least-squares fit of log y = e log n + log c: (e, c)."""
    e, logc = np.polyfit(np.log(ns), np.log(ys), 1)
    return float(e), float(np.exp(logc))


def run_complexity(p: ComplexityParams, rng: np.random.Generator, progress=lambda done, total: None) -> RunResult:
    rows = []
    sides = sorted({max(2, round(3 ** (j / p.dim))) for j in range(p.j_min, p.j_max + 1) if 3 ** j <= p.max_states})
    for done, side in enumerate(sides):
        g = GridWorld(side, p.dim)
        h = round(np.log(side) / np.log(3))  # the multi-level regions nest only on sides 3^h
        flat = learn_model(g.next_state, seed=int(rng.integers(2**31)), rule=p.rule)
        singles = {}
        for b in candidate_blocks(g.side, p.block_max, thesis_block(g.n, p.dim)):
            singles[b] = single_level(g.next_state, g.regions(b)[1], b, seed=int(rng.integers(2**31)),
                                      rule=p.rule)["total"]
        best = min(singles, key=singles.get)
        # the cost reported for the cheapest block is a fresh run of it (the minimum itself is biased low)
        single = single_level(g.next_state, g.regions(best)[1], best, seed=int(rng.integers(2**31)),
                              rule=p.rule)["total"]
        fixed_block = thesis_block(g.n, p.dim) if thesis_block(g.n, p.dim) < g.side else best
        multi = None
        if side == 3 ** h:
            multi = sum(multi_level(g.next_state, g.nested_centres(3, h), [3 ** i for i in range(h + 1)],
                                    seed=int(rng.integers(2**31)), rule=p.rule))
        centres = g.regions(fixed_block)[1]  # the additional tasks reuse the hierarchy of the thesis's k
        inside, outside = additional_task(g, centres, fixed_block, rng, p.rule)
        goal = int(centres[len(centres) // 2])  # paths through subgoals (6.2.2) against exact BFS distances
        detour = overhead(g.next_state, centres, fixed_block, goal, g.distances_to(goal))
        centres = g.regions(best)[1]
        rows.append({"n": g.n, "flat": flat, "single": single, "multi": multi, "additional_inside": inside,
                     "additional_outside": outside, "overhead_single": detour, "best_block": best,
                     "best_k": len(centres),
                     "thesis_block": thesis_block(g.n, p.dim), "single_at_thesis_k": singles.get(
                         thesis_block(g.n, p.dim))})
        progress(done + 1, len(sides))
    ns = [r["n"] for r in rows]
    metrics = {}
    for name in LEARNERS:
        pts = [(n, r[name]) for n, r in zip(ns, rows, strict=True) if r[name] is not None and r[name] > 0]
        e, c = _slope(*zip(*pts, strict=True)) if len(pts) > 1 else (None, None)
        metrics[f"exponent_{name}"], metrics[f"constant_{name}"] = e, c
    metrics["best_k_largest"] = float(rows[-1]["best_k"])
    metrics["overhead_single_largest"] = float(rows[-1]["overhead_single"])
    return RunResult(ns, [float(r["flat"]) for r in rows], metrics, rows)


def _exp(name, thesis_text):
    return Quantity(f"exponent_{name}", f"exponent e of executions ~ c n^e, {name.replace('_', ' ')} "
                    f"(thesis: {thesis_text})", "lower", "6.2, Table 6.1")


QUANTITIES = (_exp("flat", "2"), _exp("single", "1.5; 1.4 in 2-D"), _exp("multi", "n log n in 1-D, 1 in 2-D"),
              _exp("additional_inside", "1.5; 1.4 in 2-D"), _exp("additional_outside", "1.5; 1.4 in 2-D"),
              Quantity("best_k_largest", "number of regions that was cheapest at the largest n", "lower", "6.2.2"),
              Quantity("overhead_single_largest", "single level, largest n: mean path length through subgoals / "
                       "shortest path length", "lower", "6.2.2"))

PROFILES = {"tiny": {"runs": 1, "max_states": 729, "block_max": 5},
            "quick": {"runs": 2, "max_states": 6561}, "full": {"runs": 3}}

CHAPTER = 6  # the thesis chapter of these experiments (`connrl reproduce --chapters`)
EXPERIMENTS = [
    ExperimentSpec(
        name="complexity", title="Learning a grid world flat, with one level of abstraction and with many: action "
        "executions against the number of states", section="6.2 Table 6.1", run="connrl.experiments.complexity:"
        "run_complexity", params=override(ComplexityParams(), {}, "experiment complexity"), profiles=PROFILES,
        # 1-D up to 3^9 states (a random walk needs ~n^2 executions), 2-D up to 3^10
        variants=(Variant("1-D, greedy mapping", {"dim": 1, "rule": "greedy", "j_max": 9}),
                  Variant("1-D, random walk", {"dim": 1, "rule": "random", "j_max": 9}),
                  Variant("2-D, greedy mapping", {"dim": 2, "rule": "greedy"}),
                  Variant("2-D, random walk", {"dim": 2, "rule": "random"})),
        quantities=QUANTITIES, x_label="states n", y_label="action executions (flat learner)",
        description="the thesis derived Table 6.1 and never measured it: flat O(n^2), single-level O(n^1.5), "
                    "multi-level O(n log n) (1-D) / O(n) (2-D)"),
]
