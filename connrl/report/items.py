"""The thesis's result items (Lin 1993, Chs. 4-8, with 7.5.4 fn. 4 and 8.5 fn. 1): one per figure, table or reported
sentence, and the scoreboard's checks (``verdicts.Claim``) mapped onto them, so that the page can give each thesis
item one verdict derived from its checks by a stated rule (``item_rows``) and no thesis cell counts twice.

An item is one figure, one table, or one reported paragraph of results. Keys read "<section> / <figure or table>"
where the thesis numbers one, else "<section> <short name>". ``item_of`` raises on a check it cannot place rather than
guess (``strict=False`` gives it a row of its own instead): a new check needs its line here, and
tests/report/test_items.py places every check of the committed docs/RESULTS.md.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

# (key, thesis section, what the thesis reports) -- in thesis order
ITEMS = [
    # ---------------------------------------------------------------- Chapter 4: the survival task
    ("4.2.1 food reward", "4.2.1",
     "Food reward 0.4 chosen empirically: of a few values tried for AHCON, 0.4 gave roughly the best performance."),
    ("4.2.7 replay thresholds", "4.2.7",
     "Only policy actions replayed: P_t = 0.2 roughly the best for AHCON-R; for QCON-R, P_t = 0.1, 0.01 and 0.001 "
     "similar and P_t = 0 poor (AHCON-R sensitive to replaying non-policy actions, QCON-R much less)."),
    ("4.3.2 / Fig. 4.3", "4.3.2",
     "Study 1 (global action representation, action symmetry): learning curves of the eight agents, food per test "
     "play every 20 of 300 plays, mean of 7 experiments (the curves are lost; their content survives in the 4.4 "
     "tables)."),
    ("4.3.2 / Table 4.1", "4.3.2",
     "Table 4.1's settings were chosen empirically to give roughly the best performance for AHCON and QCON (little "
     "search for the others); fixed low temperatures seemed to work as well as the cooling ones."),
    ("4.3.3 / Fig. 4.4", "4.3.3",
     "Study 2 (local action representation, no symmetry, learning rates doubled): learning curves of the eight "
     "agents, mean of 7 experiments (lost; read through the 4.4 tables)."),
    ("4.3.4 QCON-T on 8000 environments", "4.3.4",
     "QCON-T (roughly the best agent) after 300 plays, on 8000 random environments: got all food 39.9 %, killed "
     "31.9 %, out of energy 28.2 %; 12.1 food per play on average; the distribution of food per play (0-15)."),
    ("4.3.4 curve spread", "4.3.4",
     "The curves' point-by-point SD is roughly 2 food early and 1 at the end; better agents vary less between "
     "experiments; the agents' relative performance was consistent most of the time."),
    ("4.4.1 table", "4.4.1",
     "AHC- vs Q-agents, learning speed and final performance: global Q > AHC in both; local Q ~ AHC in both."),
    ("4.4.1 representations", "4.4.1",
     "Q-agents' final performance basically unaffected by the action representation; AHC-agents' final performance "
     "apparently better with the local one."),
    ("4.4.2 table", "4.4.2",
     "Experience replay: -R learns faster than the plain agent in both studies; final performance ~ under the global "
     "representation, AHCON-R >= AHCON and QCON-R > QCON under the local one."),
    ("4.4.3 table", "4.4.3",
     "Action models (perfect / learned model, global / local representation), speed and final performance, 16 cells: "
     "a perfect model always helps; a learned one hurts QCON under the global representation and helps under the "
     "local one."),
    ("4.4.3 model accuracy", "4.4.3",
     "In both studies the learned model's prediction accuracy approached its asymptote after about 50 plays; the "
     "model was never nearly perfect, even after hundreds of plays (enemy predictions often wrong, 4.2.5)."),
    ("4.4.3 / Fig. 4.5", "4.4.3",
     "Hypothetical actions per step of the -M agents, Study 2 (max 4): dropped very quickly as the learning curves "
     "levelled off, but not close to zero."),
    ("4.4.4 table", "4.4.4",
     "Teaching (-T vs -R): global ~ in every cell; local AHCON-T >= AHCON-R and QCON-T > QCON-R in speed, ~ in final "
     "performance."),
    ("4.4.5 table", "4.4.5",
     "Experience replay vs action models, 16 cells: against a learned model replay is clearly, consistently better; "
     "against a perfect model neither is consistently better."),
    ("4.5 speedup table", "4.5",
     "Study 2 Q-agents, plays to reach 8 food per play: QCON 200; learned model 140 (1.4x); perfect model 95 (2.1x); "
     "experience replay 80 (2.5x); replay + teaching 60 (3.3x)."),
    # ---------------------------------------------------------------- Chapter 5: robot skills
    ("5.1.1 / Fig. 5.2", "5.1.1",
     "D = -1/ln(lambda) against lambda: D grows gradually up to lambda = 0.9 and rapidly above it."),
    ("5.4.1 / Fig. 5.4a (DP)", "5.4.1",
     "Door passing with 0 / 3 / 10 taught lessons (lambda = 0.7): teaching clearly useful; without teaching little is "
     "learned in the first 100 trials and 1 of 7 runs fails totally; 3 lessons significantly better than none; with "
     "10 a quite good skill after 100 trials."),
    ("5.4.1 / Fig. 5.4b (DK)", "5.4.1",
     "Docking with 0 / 3 / 10 lessons: the more teaching, the better; without teaching 2 of 7 runs fail totally, "
     "but once successes come the final performance is often as good as with teaching."),
    ("5.4.1 / Fig. 5.4c (WFL)", "5.4.1",
     "Left wall following with 0 / 2 / 5 lessons: teaching reduces the actions needed, less than for DP and DK; "
     "almost no difference in speed between 2 and 5 lessons."),
    ("5.4.1 / Figs 5.5-5.7", "5.4.1",
     "Solution paths after 300 trials with 10 (DP, DK) or 5 (WFL) taught lessons are nearly optimal."),
    ("5.4.2 / Fig. 5.8a (DP)", "5.4.2",
     "TD(lambda) on DP with 10 lessons: lambda = 0 clearly the worst; TD(0.9) ~ TD(1), better than TD(0.3); TD(0.9) "
     "and TD(1) slightly better than TD(0.7)."),
    ("5.4.2 / Fig. 5.8b (WFL)", "5.4.2",
     "TD(lambda) on WFL without teaching: lambda = 0 clearly the worst; TD(0.9) ~ TD(1), better than TD(0.3); TD(0.7) "
     "better than TD(0.9) and TD(1)."),
    ("5.4.3 / Fig. 5.9", "5.4.3",
     "Lower / raise repairs on DP (lambda = 0.7): with 3 lessons both tended to improve performance; with 10 the "
     "improvement, if any, was marginal (their utility limited, 5.5)."),
    ("5.4.4 / Fig. 5.10", "5.4.4",
     "With single-layer Q-nets the robot cannot accomplish DP, DK or WFL (multi-layer nets can): the Q-functions are "
     "nonlinear, and TD with back-propagation learns them."),
    ("5.5 noise", "5.5",
     "The robot's performance in the noisy world was almost the same as in a noise-free world."),
    ("5.6 teaching table", "5.6",
     "DP, lambda = 0.7, trials to reach 2.5: no teaching 280; 3 lessons 20 (speedup 14); 10 lessons 10 (speedup 28)."),
    ("5.6 lambda table", "5.6",
     "DP, 10 lessons, trials to reach 5: lambda = 0 280; lambda = 0.3 140 (speedup 2.0); lambda = 0.7 65 (speedup "
     "4.3)."),
    # ---------------------------------------------------------------- Chapter 6: hierarchical learning
    ("6.2.4 / Table 6.1", "6.2.4",
     "Complexity of learning in d-dimensional grid worlds (analysis; deterministic, tabular): first task O(n^2) flat, "
     "O(n^1.5) single-level, O(n log n) (d = 1) or O(n) (d > 1) multi-level; an additional task O(n^2), O(n^1.5), "
     "O(n^(1/d)); the 2-D constants of 6.2.2-6.2.3 (55 n^1.4 at k = 7.8 n^0.6; 1728 n at k = 4n/9)."),
    ("6.4.3 / Figs 6.3-6.4", "6.4.3",
     "Q-value maps of the learned DP and DK behaviours: applicable where Q > 30 (DP) and Q > 25 (DK); spots of "
     "abnormally high Q far from doors caused no serious problem; the threshold is not critical unless it rules out "
     "the optimal behaviour."),
    ("6.6.1 / Fig. 6.5", "6.6.1",
     "Exp. 1, no hierarchy (monolithic Q-nets, 10 lessons): after 300 trials generally unable to dock from rooms B "
     "and C, colliding on more than 5 % of steps; a collision penalty is only slightly better; no systematic way "
     "learned."),
    ("6.6.2 / Fig. 6.6, Exp. 2", "6.6.2",
     "Exp. 2, behaviours without an exploration rule: no good policy after 150 trials (switches too often); from room "
     "A generally docks within as few as 10 trials; from part of room C within 50."),
    ("6.6.3 / Fig. 6.6, Exp. 3", "6.6.3",
     "Exp. 3, persistence rule: within 20 trials docks from most places in rooms A and C; a nearly optimal skill for "
     "all situations generally within 60 trials."),
    ("6.6.3 / Fig. 6.7", "6.6.3",
     "Solution paths found by Exp. 3 after 150 trials, from every room."),
    ("6.6.4 / Fig. 6.6, Exp. 4", "6.6.4",
     "Exp. 4, steps a fifth as long (reward delay ~500 steps): without state grouping (lambda 0.8-0.97) unable to "
     "dock from room B; with grouping (about 11 states a group) comparable to Exp. 3."),
    ("6.6.5 / Fig. 6.6, Exp. 5", "6.6.5",
     "Exp. 5, behaviours pre-trained ~300 steps, then learned alongside the high level: little progress for 50 "
     "trials, then rapid; at the end docks from any room, slightly worse than Exp. 3."),
    ("6.7 equal cost", "6.7",
     "Exps 1 and 3 used about the same teaching steps (~500) and experimental steps (~40,000, the behaviours' "
     "training included), so at equal cost the hierarchical robot was apparently superior."),
    # ---------------------------------------------------------------- Chapter 7: hidden state
    ("7.5 / Table B.1", "7.5 / B",
     "Table B.1's settings (Tasks 1-4, each architecture) were chosen to give roughly the best performance; they are "
     "the settings behind Figs 7.5, 7.7, 7.8 and Table 7.1."),
    ("7.5.1 / Fig. 7.5", "7.5.1",
     "Task 1, 2-cup collection: with lambda = 0.8 all three architectures learned the optimal policy; lambda = 0.8 "
     "much better than lambda = 0."),
    ("7.5.1 window size N = 2", "7.5.1",
     "Window-Q with N = 2 (Fig. 7.5a used N = 5) learned the optimal policy, but only occasionally, its own actions "
     "carrying the information."),
    ("7.5.1 robustness", "7.5.1",
     "Interrupted and pushed the wrong way, window-Q's policy does not resume optimally (not robust); "
     "recurrent-model's acts on the world state (more robust); recurrent-Q's in between."),
    ("7.5.1 imperfect model", "7.5.1",
     "Recurrent-model never learned a perfect model within 500 trials (e.g. a cup unseen for 10+ steps), yet its "
     "Q-learning found the optimal policy."),
    ("7.5.1 computation time", "7.5.1",
     "Recurrent-Q and recurrent-model found the optimal policy after about as many trials, but a run took 20 vs 80 "
     "minutes of CPU."),
    ("7.5.2 / Fig. 7.7", "7.5.2",
     "Task 2, two random sensation bits: little impact on window-Q and recurrent-Q; noticeable on recurrent-model, "
     "which found the optimal policy many times after 300 trials but oscillated."),
    ("7.5.2 fixed model", "7.5.2",
     "With recurrent-model's model fixed part-way (only the Q-net learning), the agent found the optimal policy and "
     "stuck to it."),
    ("7.5.3 / Fig. 7.8", "7.5.3",
     "Task 3, 15 % control errors: window-Q optimal in 3 of 5 runs; recurrent-Q always optimal, little instability; "
     "recurrent-model found it after 500 trials but oscillated."),
    ("7.5.4 / Table 7.1", "7.5.4",
     "Pole balancing from (x, theta), trials to a satisfactory policy, best 5 of 6 runs: window-Q 206, recurrent-Q "
     "552, recurrent-model 247; not always found within 1000 trials."),
    ("7.5.4 fn. 4", "7.5.4",
     "Memoryless Q-learning took 119 trials on full-state pole balancing."),
    # ---------------------------------------------------------------- Chapter 8: integration
    ("8.2 / Fig. 8.1, Exp. 1", "8.2",
     "Exp. 1, memoryless robot without X-Y: generally failed to dock when starting from room B."),
    ("8.3 / Fig. 8.1, Exp. 2", "8.3",
     "Exp. 2, recurrent-Q without X-Y: significantly better than the memoryless robot; after 150 trials it had "
     "developed history features and its policy was acceptably good."),
    ("8.4 / Fig. 8.2", "8.4",
     "Exp. 3, changed layout (obstacles, charger and doors moved or added), learning off: the recurrent policy adapted "
     "reasonably well (three solution paths)."),
    ("8.5 table", "8.5",
     "Teaching steps DK 100, DP 100, WFR 150, WFL 150, CHG 0 (500 in all); experimental steps to a good policy 2,000, "
     "2,000, 1,500, 1,500, 15,000 (22,000)."),
    ("8.5 fn. 1", "8.5",
     "With X-Y (Ch. 6 Exp. 3) the recharging task took only 7,000 steps."),
]

KEYS = [k for k, _, _ in ITEMS]

# every Claim.item the page's code produces, re-check suffix stripped -> item key.
CHECK_TO_ITEM = {
    # survival.py, survival_speedup.py, survival_accuracy.py
    "4.2.1: food reward 0.4 roughly the best for AHCON": "4.2.1 food reward",
    "4.2.7: AHCON-R P_t = 0.2 roughly the best": "4.2.7 replay thresholds",
    "4.2.7: QCON-R similar at P_t = 0.1, 0.01, 0.001": "4.2.7 replay thresholds",
    "4.2.7: QCON-R poor at P_t = 0": "4.2.7 replay thresholds",
    "4.3.4: QCON-T on 8000 random environments": "4.3.4 QCON-T on 8000 environments",
    "Table of 4.4.1 (AHC- vs Q-agents)": "4.4.1 table",
    "4.4.1: Q-agents' final performance unaffected by the representation": "4.4.1 representations",
    "4.4.1: AHC-agents' final performance better with the local representation": "4.4.1 representations",
    "Table of 4.4.2 (experience replay)": "4.4.2 table",
    "Table of 4.4.3 (action models)": "4.4.3 table",
    "4.4.3: model accuracy near its asymptote after ~50 plays": "4.4.3 model accuracy",
    "4.4.3: the learned model never nearly perfect": "4.4.3 model accuracy",
    "Fig. 4.5: planning drops as learning levels off, not to zero": "4.4.3 / Fig. 4.5",
    "Table of 4.4.4 (teaching)": "4.4.4 table",
    "Table of 4.4.5 (experience replay vs action models)": "4.4.5 table",
    "Table 4.5: the ordering of the speedups": "4.5 speedup table",
    "Table 4.5: plays to reach 8": "4.5 speedup table",
    # td_depth.py
    "Fig. 5.2: D = -1/ln(lambda)": "5.1.1 / Fig. 5.2",
    # robot.py (_chapter_claims)
    "Fig. 5.4a: teaching helps (DP)": "5.4.1 / Fig. 5.4a (DP)",
    "Fig. 5.4b: teaching helps (DK)": "5.4.1 / Fig. 5.4b (DK)",
    "Fig. 5.4c: teaching helps (WFL)": "5.4.1 / Fig. 5.4c (WFL)",
    "Fig. 5.8a: lambda = 0 clearly the worst (DP)": "5.4.2 / Fig. 5.8a (DP)",
    "Fig. 5.8b: lambda = 0 clearly the worst (WFL)": "5.4.2 / Fig. 5.8b (WFL)",
    # robot.py via checks.meets_claims: f"{item}: {variant}, {quantity}"; trials_to_2.5 is a cell of 5.6's
    # teaching table, trials_to_5 of its lambda table (10 lessons = lambda 0.7 = the same cell, 65)
    "Fig. 5.4a / 5.6: no teaching, trials_to_2.5": "5.6 teaching table",
    "Fig. 5.4a / 5.6: 3 lessons, trials_to_2.5": "5.6 teaching table",
    "Fig. 5.4a / 5.6: 10 lessons, trials_to_2.5": "5.6 teaching table",
    "Fig. 5.4a / 5.6: 10 lessons, trials_to_5": "5.6 lambda table",
    "Fig. 5.8a / 5.6: lambda=0, trials_to_5": "5.6 lambda table",
    "Fig. 5.8a / 5.6: lambda=0.3, trials_to_5": "5.6 lambda table",
    "Fig. 5.8a / 5.6: lambda=0.7, trials_to_5": "5.6 lambda table",
    "5.5: noisy and noise-free performance almost the same": "5.5 noise",
    "5.6 table: speedup from teaching": "5.6 teaching table",
    "5.6 table: speedup from lambda": "5.6 lambda table",
    # recharge_claims.py (each repeated string is one paragraph of the thesis: one item)
    "Fig. 6.5": "6.6.1 / Fig. 6.5",
    "Fig. 6.6, Exp. 2": "6.6.2 / Fig. 6.6, Exp. 2",
    "Fig. 6.6, Exps 2 / 3": "6.6.2 / Fig. 6.6, Exp. 2",  # 6.6.2's "fails to learn a good policy after 150 trials"
    "Fig. 6.6, Exp. 3": "6.6.3 / Fig. 6.6, Exp. 3",
    "Fig. 6.7": "6.6.3 / Fig. 6.7",
    "Fig. 6.6, Exp. 4": "6.6.4 / Fig. 6.6, Exp. 4",
    "Fig. 6.6, Exp. 5": "6.6.5 / Fig. 6.6, Exp. 5",
    "6.7 (equal cost)": "6.7 equal cost",
    # hidden_state.py, hidden_state_models.py
    "Fig. 7.5: 2-cup collection": "7.5.1 / Fig. 7.5",
    "Fig. 7.5: λ = 0 much worse than λ = 0.8": "7.5.1 / Fig. 7.5",
    "7.5.1: window-Q with N = 2 learns only occasionally": "7.5.1 window size N = 2",
    "7.5.1: robustness, recurrent-model > recurrent-Q > window-Q": "7.5.1 robustness",
    "7.5.1: the model is never perfect, yet the policy is optimal": "7.5.1 imperfect model",
    "7.5.1: recurrent-model costs 4x recurrent-Q's time": "7.5.1 computation time",
    "Fig. 7.7: Task 1 with two random sensation bits": "7.5.2 / Fig. 7.7",
    "7.5.2: fixing the model keeps the optimal policy": "7.5.2 fixed model",
    "Fig. 7.8: Task 1 with 15% control errors": "7.5.3 / Fig. 7.8",
    "Table 7.1: pole balancing from (x, θ)": "7.5.4 / Table 7.1",
    # pole.py via checks.meets_claims
    "7.5.4 fn. 4: QCON-R, trials_to_satisfactory": "7.5.4 fn. 4",
    # integration.py ("Fig. 8.1" is in _BY_SECTION: two items)
    "Fig. 8.2": "8.4 / Fig. 8.2",
    "8.5 table: DK": "8.5 table",
    "8.5 table: DP": "8.5 table",
    "8.5 table: WFL": "8.5 table",
    "8.5 table: WFR": "8.5 table",
    "8.5 table: CHG (no X-Y, recurrent-Q at 8.3's lr 0.08, 100 lessons)": "8.5 table",
    "8.5 table: CHG (no X-Y, recurrent-Q, ours)": "8.5 table",
    "8.5 table: CHG with X-Y (Ch. 6 Exp. 3; 8.5 fn. 1)": "8.5 fn. 1",
}

# one Claim.item string, two thesis items: the check's section tells them apart
_BY_SECTION = {
    ("Fig. 8.1", "8.2"): "8.2 / Fig. 8.1, Exp. 1",
    ("Fig. 8.1", "8.3"): "8.3 / Fig. 8.1, Exp. 2",
}

# Claim.thesis_item labels (connrl.report.integration) -> item key
THESIS_ITEM_TO_ITEM = {
    "Fig. 8.1: memoryless": "8.2 / Fig. 8.1, Exp. 1",
    "Fig. 8.1: room B": "8.3 / Fig. 8.1, Exp. 2",
    "Fig. 8.1: acceptably good": "8.3 / Fig. 8.1, Exp. 2",
    "8.5 table: CHG": "8.5 table",
}

# families the f-strings can produce beyond the literal list (another variant given a thesis number, a future
# re-check, ...): first match wins
_PATTERNS = [
    (r"^Fig\. 5\.[48]a / 5\.6: .*, trials_to_2\.5$", "5.6 teaching table"),
    (r"^Fig\. 5\.[48]a / 5\.6: .*, trials_to_5$", "5.6 lambda table"),
    (r"^7\.5\.4 fn\. 4: ", "7.5.4 fn. 4"),
    (r"^Table 4\.5: plays to reach 8 within ", "4.5 speedup table"),  # the fresh check's looser rule, a row apart
    (r"^8\.5 table: CHG with X-Y", "8.5 fn. 1"),
    (r"^8\.5 table: ", "8.5 table"),
    (r"^Fig\. 7\.5: ", "7.5.1 / Fig. 7.5"),
    (r"^Fig\. 7\.7: ", "7.5.2 / Fig. 7.7"),
    (r"^Fig\. 7\.8: ", "7.5.3 / Fig. 7.8"),
]

# a re-check's suffix (page.recheck_tag): " (fresh seeds 2000-2006)" or " (seeds 0-0, tiny profile: not the check)"
_RECHECK = re.compile(r" \((?:fresh )?seeds [^()]*\)$")


def strip_recheck(check_item: str) -> str:
    return _RECHECK.sub("", check_item)


UNPLACED = "not placed: "  # a check no line here places; the page lists it under this prefix instead of failing


def item_of(check_item: str, section: str, thesis_item: str = "", strict: bool = True) -> str:
    """The ITEMS key of a scoreboard check (its Claim.item, Claim.section and, where set, Claim.thesis_item); with
    ``strict=False`` an unknown check gets an ``UNPLACED`` key of its own rather than an error."""
    if thesis_item in THESIS_ITEM_TO_ITEM:
        return THESIS_ITEM_TO_ITEM[thesis_item]
    base = strip_recheck(check_item)
    if base in CHECK_TO_ITEM:
        return CHECK_TO_ITEM[base]
    if (base, section) in _BY_SECTION:
        return _BY_SECTION[(base, section)]
    for pattern, key in _PATTERNS:
        if re.search(pattern, base):
            return key
    if not strict:
        return UNPLACED + base
    raise KeyError(f"no thesis item for check {check_item!r} (section {section!r})")


# verdicts.UNSCORED -> item
UNSCORED_TO_ITEM = {
    "Fig. 5.9 (lower / raise repairs)": "5.4.3 / Fig. 5.9",
    "Fig. 5.10 (single-layer nets)": "5.4.4 / Fig. 5.10",
    "Table 6.1 (complexity of learning)": "6.2.4 / Table 6.1",
}

# items no check reaches, and what the page does with them today
UNCHECKED = {
    "7.5 / Table B.1": "not built as a check of its own (the settings are used; window-Q's Task 1-3 schedule, the one "
                       "we depart from, is tested inside the stated-value rows of Figs 7.5, 7.7 and 7.8)",
    "4.3.2 / Fig. 4.3": "shown without a rule (survival-study1's curves and table; checked through the 4.4 tables)",
    "4.3.2 / Table 4.1": "not built (the settings are used, their near-optimality is not measured)",
    "4.3.3 / Fig. 4.4": "shown without a rule (survival-study2's curves and table; checked through the 4.4 tables)",
    "4.3.4 curve spread": "shown without a rule (± SD over runs in the study tables)",
    "5.4.1 / Figs 5.5-5.7": "shown without a rule (solution-path figures of robot-teaching-*)",
    "5.4.3 / Fig. 5.9": "shown without a rule (robot-repairs-3 / -10; verdicts.UNSCORED)",
    "5.4.4 / Fig. 5.10": "shown without a rule (robot-single-layer, robot-dk-geometry; verdicts.UNSCORED)",
    "6.2.4 / Table 6.1": "shown without a rule (complexity section; verdicts.UNSCORED)",
    "6.4.3 / Figs 6.3-6.4": "shown without a rule (behaviour Q-maps and applicable shares, Ch. 6 intro)",
}

# parts of checked items that no check tests (for the item's page text; not exhaustive of wording)
PARTS_UNCHECKED = {
    "4.3.4 QCON-T on 8000 environments": "killed / out-of-energy shares and the 0-15 distribution",
    "4.4.3 model accuracy": "4.2.5's enemy predictions often wrong",
    "5.4.1 / Fig. 5.4a (DP)": "1 of 7 no-teaching runs fails totally; 3 lessons > none; good skill after 100 trials "
                              "with 10 (the 5.6 table covers the speeds)",
    "5.4.1 / Fig. 5.4b (DK)": "2 of 7 no-teaching runs fail; final often as good as with teaching",
    "5.4.1 / Fig. 5.4c (WFL)": "2 vs 5 lessons almost the same speed; smaller impact than DP / DK",
    "5.4.2 / Fig. 5.8a (DP)": "TD(0.9) ~ TD(1) > TD(0.3); TD(0.9), TD(1) slightly > TD(0.7)",
    "5.4.2 / Fig. 5.8b (WFL)": "TD(0.9) ~ TD(1) > TD(0.3); TD(0.7) > TD(0.9), TD(1)",
    "6.6.1 / Fig. 6.5": "the collision-penalty variant",
    "6.6.2 / Fig. 6.6, Exp. 2": "docks from part of room C within 50 trials",
    "6.6.4 / Fig. 6.6, Exp. 4": "lambda 0.8-0.97 never good without grouping; ~11 states a group (a tuned quantity)",
    "6.6.5 / Fig. 6.6, Exp. 5": "little progress for the first 50 trials",
    "6.7 equal cost": "teaching steps ~500 each",
    "7.5.2 / Fig. 7.7": "recurrent-model finds the optimal policy many times after 300 trials",
    "7.5.3 / Fig. 7.8": "recurrent-model finds the optimal policy after 500 trials (oscillating)",
    "8.3 / Fig. 8.1, Exp. 2": "history features developed (shown: 'The hidden state made visible')",
    "8.5 table": "the teaching-steps row (shown, not scored)",
}




# ------------------------------------------------------------------------------------------ verdict per item

NOT_BUILT = "not built"
# the items some check is placed on: one without any stored is "not run", not "not built"
PLACED = set(CHECK_TO_ITEM.values()) | set(_BY_SECTION.values()) | {k for _, k in _PATTERNS} | set(
    THESIS_ITEM_TO_ITEM.values())
NOT_THE_CHECK = "not the check"  # connrl.report.page.recheck_tag's mark on a re-check run at other seeds or profile
ITEM_VERDICTS = ("reproduced", "partly", "not reproduced", "undetermined", NOT_BUILT)
RULE = ("An item's verdict comes from its checks at the thesis's stated values (rows at our departures are shown, "
        "never counted). A check with a re-check on seeds never used in development counts by the re-check; a check "
        "whose setting was chosen on its own claim and has no re-check cannot count as reproduced (it counts as "
        "undetermined). Then: every check reproduced → reproduced; none contradicted but not all decided → "
        "undetermined; some reproduced (or partly) and some not → partly; none reproduced and some not → not "
        "reproduced. An item the page shows without a rule, or only at a departure, is undetermined; one it does "
        "not show is not built.")


def check_key(c) -> tuple[str, str, str]:
    """What a re-check shares with the check it repeats: the item text without its seed label, the thesis's words
    and the setting."""
    return strip_recheck(c.item), c.thesis, c.setting


@dataclass
class ItemRow:
    key: str
    section: str
    statement: str
    verdict: str
    checks: int  # at the stated values
    departures: int
    rechecks: int
    note: str  # why no rule, what was calibrated, what is not tested


def _combine(verdicts: list[str]) -> str:
    agree = sum(v in ("reproduced", "partly") for v in verdicts)
    contra = sum(v in ("not reproduced", "partly") for v in verdicts)
    if all(v == "reproduced" for v in verdicts):
        return "reproduced"
    if contra == 0:
        return "undetermined"
    return "partly" if agree else "not reproduced"


def item_rows(claims) -> list[ItemRow]:
    """Every thesis item with its verdict by ``RULE`` from ``claims`` (the page's scoreboard)."""
    by_item: dict[str, list] = {k: [] for k in KEYS}
    for c in claims:
        by_item.setdefault(item_of(c.item, c.section, c.thesis_item, strict=False), []).append(c)
    unscored = {v: k for k, v in UNSCORED_TO_ITEM.items()}
    unplaced = [(k, by_item[k][0].section, "(a check of ours not placed among the thesis's items)")
                for k in by_item if k.startswith(UNPLACED)]
    rows = []
    for key, section, statement in [*ITEMS, *unplaced]:
        cs = by_item[key]
        stated = [c for c in cs if not c.setting and not c.recheck]
        again = {check_key(c): c for c in cs if c.recheck and NOT_THE_CHECK not in c.item}
        words, notes = [], []
        for c in stated:
            r = again.get(check_key(c))
            if r is not None:
                words.append(r.verdict)
                if c.calibrated:
                    notes.append(f"calibrated on its own claim ({c.calibrated}); counted by its re-check")
            elif c.calibrated:
                words.append("undetermined" if c.verdict == "reproduced" else c.verdict)
                notes.append(f"calibrated on its own claim, not re-checked: {c.calibrated}")
            else:
                words.append(c.verdict)
        if words:
            verdict = _combine(words)
        elif cs:
            verdict, notes = "undetermined", ["checked only at departures from the stated values"]
        elif key in PLACED:
            verdict, notes = "undetermined", ["not run: no stored results for its checks"]
        elif key in UNCHECKED:
            verdict = NOT_BUILT if UNCHECKED[key].startswith("not built") else "undetermined"
            notes.append(UNCHECKED[key] + (f" ({unscored[key]})" if key in unscored else ""))
        else:
            verdict = NOT_BUILT
        if key in PARTS_UNCHECKED and cs:
            notes.append("not tested: " + PARTS_UNCHECKED[key])
        rows.append(ItemRow(key, section, statement, verdict, len(stated), sum(bool(c.setting) for c in cs
                                                                               if not c.recheck),
                            sum(c.recheck and not c.setting for c in cs),  # re-checks of stated-value checks
                            "; ".join(dict.fromkeys(notes))))
    return rows
