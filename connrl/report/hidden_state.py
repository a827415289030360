"""docs/RESULTS.md section for Ch. 7 (hidden state): ``connrl.experiments.hidden_state``, with Table 7.1's
best-5-of-6 measure (``best_k_mean``) and its spread over every 6-run subset."""

from __future__ import annotations

from itertools import combinations
from pathlib import Path

import numpy as np

from connrl.experiments.hidden_state import CUP_FIGURES, EXPERIMENTS, FRESH_SEED, STATED, STATED_WINDOW_Q
from connrl.report.checks import better_runs
from connrl.report.hidden_state_models import frozen_model, imperfect_model
from connrl.report.page import fixed, load_summary, note, recheck_tag
from connrl.report.verdicts import NOT_REPRODUCED, OPEN, PARTLY, REPRODUCED, claim, ordering, p_text


def best_k_mean(values, k: int = 5, fail_value: float | None = None) -> tuple[float | None, int]:
    """Table 7.1's summary: the mean of the best ``k`` runs (lower is better). A run that never reached
    the goal (None) ranks last and, if it is among the best k, counts as ``fail_value`` (a lower bound).
    Returns ``(mean, failures among the best k)``; mean is None when it cannot be formed."""
    vals = sorted(v for v in values if v is not None)
    best = vals[:k]
    n_fail = max(0, min(k, len(values)) - len(best))
    if (n_fail and fail_value is None) or not min(k, len(values)):
        return None, n_fail
    best = best + [fail_value] * n_fail
    return float(np.mean(best)), n_fail


def best5_of_6_distribution(values, fail_value: float) -> tuple[float, float, float]:
    """Table 7.1's best-5-of-6 mean (``best_k_mean``) over every 6-run subset of ``values`` (None counts as
    ``fail_value``): (mean, 5th percentile, 95th percentile)."""
    means = np.array([best_k_mean(c, 5, fail_value)[0] for c in combinations(values, 6)])
    return float(means.mean()), float(np.percentile(means, 5)), float(np.percentile(means, 95))


def _cmd(s: dict) -> str:
    return (f"`connrl run {s['experiment']} --profile {s['profile']} --runs {s['runs_per_variant']} "
            f"--seed {s['base_seed']}`")


_TASK_NOTES = {1: ["cups-task1"], 3: ["cups-task3"]}  # docs/notes/NAME.md
STABLE = 0.9  # "optimal" at the end: optimal in at least this share of the last 100 greedy tests
# what the thesis reports per task and architecture (lambda = 0.8): "most" = kept in more than half the runs,
# "all" = every run, "some" = at least one, "not" = at most half (oscillates)
_CUP_EXPECT = {1: {"window-Q": "most", "recurrent-Q": "most", "recurrent-model": "most"},
               2: {"window-Q": "most", "recurrent-Q": "most", "recurrent-model": "not"},
               3: {"window-Q": "some", "recurrent-Q": "all", "recurrent-model": "not"}}
# measured on development seeds (docs/notes/cups-task3.md); shown where the verdict is short of reproduced
_CUP_CAUSE = {3: "located, not explained (development seeds, `scripts/ch7/task3_probe.py`): recurrent-Q's greedy "
                 "episodes first leave the optimal path by a pick-up that collects nothing, at the start or right "
                 "after the first cup, and in some runs wander after it; the same learner without control errors "
                 "makes none there"}
_CUP_THESIS = {1: "all three optimal (λ = 0.8)", 2: "window-Q and recurrent-Q little affected; recurrent-model "
               "oscillates", 3: "window-Q optimal in 3 of 5 runs; recurrent-Q always; recurrent-model oscillates"}


WINDOW_OURS = "ours: window-Q's 1/T 5 → 30 (Table B.1: 10 → 30)"
WINDOW_CAUSE = ("with Table B.1's 10 → 30 window-Q's first policy is nearly deterministic and failed runs settle "
                "into a 19-28-step habit whose untried actions keep negative values (our reading, "
                "connrl/experiments/hidden_state.py); 5 → 30 is ours, chosen on development seeds")


# docs/RECONSTRUCTION.md, "Hidden-state agents": both were chosen by Task 1 runs stably optimal, Fig. 7.5's own claim
CUP_CALIBRATED = ("70 replays per trial and window-Q's linear output unit, chosen on development seeds 100-159 by "
                  "Task 1 runs optimal at the end")


def _kept(s: dict) -> tuple[dict, dict]:
    """Per variant: runs optimal at the end (≥ STABLE of the last 100 tests), and runs."""
    kept, n = {}, {}
    for label, v in s["variants"].items():
        per = [x for x in v["quantities"]["optimal_last100"]["per_run"] if x is not None]
        kept[label], n[label] = sum(x >= STABLE for x in per), len(per)
    return kept, n


def _cup_claims(s: dict, task: int, fig: str, section: str, title: str, tag: str = "") -> None:
    """The scoreboard's rows for one cup task: each architecture's end state against the thesis's, and for Task 1
    lambda = 0's gap; each at Table B.1's stated values and again with our window-Q schedule. ``tag`` marks a
    re-check (fresh seeds), tallied apart."""
    kept, n = _kept(s)
    anchor = f"{title} ({fig}, {section}){tag}"
    for window, setting in ((STATED_WINDOW_Q, ""), ("window-Q lambda=0.8", WINDOW_OURS)):
        if window not in kept:
            continue
        ok, shown = [], []
        for arch, want in _CUP_EXPECT[task].items():
            label = window if arch == "window-Q" else f"{arch} lambda=0.8"
            if label not in kept:
                continue
            k, m = kept[label], n[label]
            ok.append({"most": k > m / 2, "all": k == m, "some": k >= 1, "not": k <= m / 2}[want])
            shown.append(f"{arch} {k}/{m}")
        verdict = REPRODUCED if all(ok) else PARTLY if any(ok) else NOT_REPRODUCED
        causes = [_CUP_CAUSE.get(task, "")] + ([WINDOW_CAUSE] if not setting and not ok[0] else [])
        claim(f"{fig}: {title.split(': ')[1]}{tag}", section, _CUP_THESIS[task],
              "runs optimal at the end: " + ", ".join(shown),
              f"optimal in ≥ {STABLE:.0%} of the last 100 tests, in most / all / some / at most half of the runs as "
              "the thesis says", verdict, "; ".join(c for c in causes if c) if verdict != REPRODUCED else "",
              anchor=anchor, recheck=bool(tag), setting=setting,
              calibrated="" if task != 1 else CUP_CALIBRATED + ("; window-Q's 1/T 5 → 30 likewise" if setting else ""))
    if task == 1:
        _lambda_claims(s, fig, section, anchor, tag)


def _lambda_claims(s: dict, fig: str, section: str, anchor: str, tag: str) -> None:
    """Fig. 7.5's "lambda = 0 much worse", at Table B.1's window-Q schedule and at ours."""
    for window, setting in ((STATED, ""), ("", WINDOW_OURS)):
        votes = []
        for arch in _CUP_EXPECT[1]:
            end = window if arch == "window-Q" else ""
            hi, lo = s["variants"].get(f"{arch} lambda=0.8{end}"), s["variants"].get(f"{arch} lambda=0{end}")
            if hi and lo:
                v, p = better_runs(*(x["quantities"]["optimal_last100"]["per_run"] for x in (lo, hi)))
                if p is not None:
                    votes.append((arch, v, p))
        if not any(a == "window-Q" for a, _, _ in votes):
            continue  # a row without its window-Q pair would not be the claim
        yes = sum(v == "yes" for _, v, _ in votes)
        verdict = REPRODUCED if yes == len(votes) else NOT_REPRODUCED if all(v == "no" for _, v, _ in votes) else \
            PARTLY if yes else OPEN
        claim(f"{fig}: λ = 0 much worse than λ = 0.8{tag}", section, "much worse for each architecture",
              "; ".join(f"{a}: {'better' if v == 'yes' else v} ({p_text(p)})" for a, v, p in votes),
              "λ = 0.8 better, one-sided Welch on the share of optimal tests, last 100", verdict, anchor=anchor,
              recheck=bool(tag), setting=setting)


def results_section(out_dir: Path, doc: Path = Path("docs/RESULTS.md")) -> str:
    """Markdown for docs/RESULTS.md: Ch. 7 numbers beside the thesis's, from OUT/NAME/summary.json."""
    out_dir = Path(out_dir)
    parts = []
    for task, (name, fig, section, title) in CUP_FIGURES.items():
        s = load_summary(out_dir, name)
        if s is not None:
            parts += _cup_table(s, task, fig, section, title)
            _cup_claims(s, task, fig, section, title)
    parts += imperfect_model(out_dir, doc) + frozen_model(out_dir, doc)
    s = load_summary(out_dir, "cup-window")
    if s is not None:
        parts += _window_table(s)
    if load_summary(out_dir, "cup-task1") is not None:
        parts += [note("cups-compute"), ""]
        claim("7.5.1: recurrent-model costs 4x recurrent-Q's time", "7.5.1", "80 vs 20 min a run (4x)",
              "median of the per-round ratios 3.3x (2.7-4.0x over 5 rounds; 3.6x from the median times; 1.2x with "
              "recurrent-Q's Python lesson replay of before issue 32); the compiled arithmetic alone 3.5x "
              "(`python scripts/ch7/compute_time.py`)",
              "the order, and the median whole-run ratio within the page's ±10 % of 4", PARTLY,
              anchor="Computation time (7.5.1)")
    s = load_summary(out_dir, "cup-robustness") or load_summary(out_dir, "cup-task1")  # Task 1 probes too (lambda=0.8)
    if s is not None:
        parts += _robustness_table(s)
    s = load_summary(out_dir, "pole-hidden")
    if s is not None:
        parts += _pole_table(s)
    parts += _fresh(out_dir, doc)
    if not parts:
        parts = ["No Chapter 7 results stored yet: run `connrl run cup-task1 --profile full` etc.", ""]
    return "\n".join(["## Chapter 7: hidden state (window-Q, recurrent-Q, recurrent-model)", ""] + parts)


def fresh_tag(s: dict) -> str:
    """How a fresh-seed re-check is labelled: by the seeds, runs and profile its summary records, so that a smoke run
    (seed 0, tiny) never passes for the check."""
    return recheck_tag([s], FRESH_SEED, 20)


def _fresh(out_dir: Path, doc: Path) -> list[str]:
    """Issue 32's check: the cup tasks and the fixed model again on seeds never used in development, 20 runs each;
    their verdicts go on the scoreboard as re-checks."""
    parts = []
    for task, (name, fig, section, title) in CUP_FIGURES.items():
        s = load_summary(out_dir, f"{name}-fresh")
        if s is not None:
            parts += _cup_table(s, task, fig, section, title, fresh_tag(s))
            _cup_claims(s, task, fig, section, title, fresh_tag(s))
    parts += frozen_model(out_dir, doc, "cup-task2-frozen-fresh", fresh_tag)
    return [note("cups-fresh"), "", *parts] if parts else []


def _cup_table(s: dict, task: int, fig: str, section: str, title: str, tag: str = "") -> list[str]:
    lines = [f"### {title} ({fig}, {section}){tag}", "",
             f"Command: {_cmd(s)} (profile `{s['profile']}`, {s['runs_per_variant']} runs per variant, "
             f"seeds from {s['base_seed']}).", "",
             "| architecture | runs reaching 14 | first trial at 14 (mean) | steps after last trial "
             "(per run) | optimal in last 100 tests | mean steps, last 100 | wasted pick-ups per test, "
             "last 100 | thesis |",
             "|---|---|---|---|---|---|---|---|"]
    for label, v in s["variants"].items():
        q = v["quantities"]
        tto = q["trials_to_optimal"]
        thesis = {1: "optimal 14 (λ=0.8); λ=0 much worse", 2: "little impact on window-Q and recurrent-Q; "
                  "recurrent-model oscillates", 3: "window-Q optimal in 3/5; recurrent-Q always; "
                  "recurrent-model oscillates"}[task]
        if task == 1 and "lambda=0" in label and "0.8" not in label:
            thesis = "much worse than λ=0.8"
        finals = ", ".join(fixed(x, 1) for x in q["final_steps"]["per_run"])
        wasted = q.get("wasted_pickups_last100", {}).get("mean")
        lines.append(f"| {label} | {tto['runs_reaching']}/{len(tto['per_run'])} | {fixed(tto['mean'], 1)} | "
                     f"{finals} | {fixed(q['optimal_last100']['mean'], 2)} | "
                     f"{fixed(q['mean_steps_last100']['mean'], 2)} | {fixed(wasted, 2)} | {thesis} |")
    lines.append("")
    for name in [] if tag else _TASK_NOTES.get(task, []):
        lines += [note(name), ""]
    return lines


def _window_table(s: dict) -> list[str]:
    """7.5.1's N = 2 claim: the optimal policy found "only occasionally"."""
    lines = ["### Window size N = 2 (7.5.1)", "", f"Command: {_cmd(s)} (profile `{s['profile']}`, "
             f"{s['runs_per_variant']} runs per variant, seeds from {s['base_seed']}). The thesis: \"the optimal "
             "policy could be learned (but only occasionally) with N = 2\" (Fig. 7.5a used N = 5).", "",
             "| window | runs with an optimal test | runs optimal in ≥ 90 % of the last 100 tests "
             "| optimal in last 100 tests (mean) | mean steps, last 100 |", "|---|---|---|---|---|"]
    reached, kept = {}, {}
    for label, v in s["variants"].items():
        q = v["quantities"]
        n = len(q["optimal_last100"]["per_run"])
        reached[label] = q["trials_to_optimal"]["runs_reaching"]
        kept[label] = sum(x >= 0.9 for x in q["optimal_last100"]["per_run"])
        lines.append(f"| {label} | {reached[label]}/{n} | {kept[label]}/{n} | "
                     f"{fixed(q['optimal_last100']['mean'], 2)} | {fixed(q['mean_steps_last100']['mean'], 2)} |")
    lines.append("")
    for five, two, setting in ((f"N=5 (Table B.1),{STATED}", f"N=2,{STATED}", ""),
                               ("N=5 (Table B.1)", "N=2", WINDOW_OURS)):
        if two not in reached or five not in reached:
            continue
        n = len(s["variants"][two]["quantities"]["optimal_last100"]["per_run"])
        verdict = ("reproduced" if 0 < kept[two] <= n / 2 else "partly" if kept[two] == 0 and reached[two] > 0
                   else "**not reproduced**")  # "learned, but only occasionally": kept in some runs, a minority
        claim("7.5.1: window-Q with N = 2 learns only occasionally", "7.5.1", "optimal policy only occasionally",
              f"optimal at some test in {reached[two]}/{n} runs, kept in {kept[two]}/{n} (N = 5: {kept[five]})",
              "kept (≥ 90 % of the last 100 tests) in some runs, at most half", verdict.strip("*"),
              anchor="Window size N = 2 (7.5.1)", setting=setting)
        lines += [f"**Verdict{', ' + setting if setting else ', at Table B.1' + chr(39) + 's schedule'}:** {verdict}: "
                  f"with N = 2 the greedy policy is optimal at some test in {reached[two]} of {n} runs but stays "
                  f"optimal (≥ 90 % of the last 100 tests) in {kept[two]}, against {kept[five]} with N = 5: found "
                  f"often, kept {'never' if not kept[two] else 'sometimes'}.", ""]
    return lines


def _robustness_table(s: dict) -> list[str]:
    lines = ["### Robustness probe (7.5.1)", "", f"Command: {_cmd(s)}.", "",
             "| architecture | share of interruptions resumed optimally (per run; — = policy not optimal) "
             "| thesis |", "|---|---|---|"]
    samples: dict[str, list[float]] = {}
    thesis = {"window-Q": "not robust (follows its recent actions)",
              "recurrent-Q": "between the two", "recurrent-model": "robust (acts on the world state)"}
    for label, v in s["variants"].items():
        arch = label.split(" ")[0]
        if label not in (arch, f"{arch} lambda=0.8", f"window-Q{STATED}"):
            continue
        runs = v["quantities"]["robust_fraction"]["per_run"]
        samples[label.replace(" lambda=0.8", "")] = [np.nan if x is None else x for x in runs]
        per = ", ".join(fixed(x, 2) for x in runs)
        lines.append(f"| {label.replace(' lambda=0.8', '')} | {per} | {thesis.get(arch, '')} |")
    for window, setting in ((f"window-Q{STATED}", ""), ("window-Q", WINDOW_OURS)):
        expected = [a for a in ("recurrent-model", "recurrent-Q", window) if a in samples]
        if len(expected) == 3 and np.isfinite(samples[window]).sum() < 2:  # too few optimal policies to probe
            k, n = int(np.isfinite(samples[window]).sum()), len(samples[window])
            claim("7.5.1: robustness, recurrent-model > recurrent-Q > window-Q", "7.5.1",
                  "window-Q not robust, recurrent-model robust", f"window-Q's policy optimal in {k} of {n} runs: "
                  "too few to test", "each pair in order, one-sided Welch", OPEN,
                  anchor="Robustness probe (7.5.1)", setting=setting)
        elif len(expected) == 3 and all(np.isfinite(samples[a]).sum() >= 2 for a in expected):
            worst, pairs = ordering(samples, expected)
            lines += ["", f"Ordering, most robust first (runs whose policy was optimal; {setting or 'Table B.1'}): "
                      + "; ".join(pairs) + f". **{worst}**."]
            claim("7.5.1: robustness, recurrent-model > recurrent-Q > window-Q", "7.5.1",
                  "window-Q not robust, recurrent-model robust", "; ".join(pairs),
                  "each pair in order, one-sided Welch", {"agrees": REPRODUCED, "contradicted": NOT_REPRODUCED}.get(
                      worst, OPEN), anchor="Robustness probe (7.5.1)", setting=setting)
    return lines + [""]


def _pole_table(s: dict) -> list[str]:
    spec = next(e for e in EXPERIMENTS if e.name == "pole-hidden")
    limit = spec.resolve(s["profile"])[0].trials
    n_runs = s["runs_per_variant"]
    lines = ["### Task 4: pole balancing from (x, θ) (Table 7.1)", "", f"Command: {_cmd(s)}.", "",
             "Table 7.1's measure is the mean of the best 5 of 6 runs; a run without a satisfactory policy "
             f"within {limit} trials counts as {limit} (marked ≥). With more than 6 runs stored, the "
             "first 6 (seeds in order) give the protocol's number, and the expected value of that number "
             "over every 6-run subset of all runs shows how much it depends on which 6 seeds are drawn.",
             "", "| architecture | trials per run | satisfactory | best 5 of first 6 | best 5 of 6, "
             f"mean over all 6-subsets of {n_runs} (5-95 %) | thesis | thesis within 5-95 % |",
             "|---|---|---|---|---|---|---|"]
    verdicts_in = []  # per architecture with a thesis number and a spread: is the thesis's number inside it
    for label, v in s["variants"].items():
        q = v["quantities"]["trials_to_satisfactory"]
        runs = q["per_run"]
        mean, n_fail = best_k_mean(runs[:6], 5, fail_value=limit)
        per = ", ".join(fixed(x, 1) if x is not None else f">{limit}" for x in runs)
        shown = ("≥ " if n_fail else "") + fixed(mean, 1)
        spread, inside = "—", "—"
        if len(runs) > 6:
            m, lo, hi = best5_of_6_distribution(runs, limit)
            spread = f"{fixed(m, 1)} ({fixed(lo, 1)}-{fixed(hi, 1)})"
            if q["thesis"] is not None:
                verdicts_in.append(lo <= q["thesis"] <= hi)
                inside = "yes" if verdicts_in[-1] else "no"
        ok = sum(x is not None for x in runs)
        lines.append(f"| {label} | {per} | {ok}/{len(runs)} | {shown} | {spread} | {fixed(q['thesis'], 1)} "
                     f"| {inside} |")
    if verdicts_in:
        n_in = sum(verdicts_in)
        claim("Table 7.1: pole balancing from (x, θ)", "7.5.4", "best 5 of 6 runs per architecture",
              f"thesis inside our 5-95 % range for {n_in} of {len(verdicts_in)} architectures",
              "the thesis's number inside the spread of the best-5-of-6 mean over 6-run subsets",
              REPRODUCED if n_in == len(verdicts_in) else PARTLY if n_in else NOT_REPRODUCED,
              anchor="Task 4: pole balancing from (x, θ) (Table 7.1)")
    return lines + ["", note("pole-hidden-subsets"), ""]
