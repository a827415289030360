"""The page's verdict rules (``connrl.report.verdicts``) applied to the claims of Chs. 4 and 5: small helpers the
survival and robot sections share. Each returns the words it printed, so a section can put the claim on the
scoreboard with the same verdict its text gives."""

from __future__ import annotations

import numpy as np

from connrl.report import verdicts
from connrl.report.verdicts import DIFFERENT, SAME, Comparison, p_text

RULE_SAME = (f"same = equivalence within ±{verdicts.REL_MARGIN:.0%} of the reference's mean, two one-sided t-tests "
             f"(TOST) at {verdicts.ALPHA:g}; different = Welch t-test at {verdicts.ALPHA:g}; otherwise undetermined")
RULE_BETTER = f"one-sided Welch t-test at {verdicts.ALPHA:g}"


def finite(xs) -> list[float]:
    return [float(x) for x in xs if x is not None and np.isfinite(float(x))]


def compare_runs(reference, other, **kwargs) -> Comparison | None:
    """``verdicts.compare`` on per-run values (None runs left out); None when a side has fewer than 2 runs."""
    a, b = finite(reference), finite(other)
    if min(len(a), len(b)) < 2:
        return None
    return verdicts.compare(a, b, **kwargs)


def better_runs(reference, other, higher_is_better: bool = True) -> tuple[str, float | None]:
    """``verdicts.better`` on per-run values; ("undetermined", None) when a side has fewer than 2 runs."""
    a, b = finite(reference), finite(other)
    if min(len(a), len(b)) < 2:
        return verdicts.UNDETERMINED, None
    return verdicts.better(a, b, higher_is_better=higher_is_better)


def comparison_text(c: Comparison | None, reference, other) -> str:
    """``Comparison.text``, or why there is no test."""
    if c is None:
        return (f"no test: {len(finite(reference))} and {len(finite(other))} run(s), a test needs at least 2 a "
                "side (undetermined)")
    return c.text()


def same_word(c: Comparison | None) -> str:
    """same / different / undetermined with N runs (and the runs a side that would decide it)."""
    if c is None:
        return verdicts.UNDETERMINED + " (fewer than 2 runs a side)"
    if c.verdict == SAME:
        return "same"
    if c.verdict == DIFFERENT:
        return "different"
    need = f"about {c.runs_needed} a side would decide" if c.runs_needed else \
        f"more than {verdicts.MAX_RUNS_NEEDED} a side would be needed"
    return f"undetermined with {min(c.n)} runs ({need})"


AGREES, CONTRADICTED, OPEN = "agrees", "contradicted", verdicts.UNDETERMINED


def relation_check(xs, ys, symbol: str) -> tuple[str, str]:
    """Does X (``xs``, per run) stand to Y (``ys``) as the thesis's symbol says (higher is better)? ">" / "<": X
    significantly better / worse (one-sided Welch); "~": the same within 10 % of Y's mean (TOST); ">=" / "<=":
    slightly better / worse, i.e. not significantly the other way and either significantly this way or the same
    within 10 %. Returns (agrees | contradicted | undetermined, our account in a few words)."""
    if symbol == "~":
        c = compare_runs(ys, xs)
        word = {SAME: AGREES, DIFFERENT: CONTRADICTED}.get(c.verdict, OPEN) if c is not None else OPEN
        return word, same_word(c)
    up = symbol in (">", ">=")
    verdict, p = better_runs(ys, xs, higher_is_better=up)
    shown = "" if p is None else f" ({p_text(p)})"
    if verdict == "yes":
        return AGREES, ("better" if up else "worse") + shown
    if verdict == "no":
        return CONTRADICTED, ("worse" if up else "better") + f" ({p_text(1 - p)})"
    if symbol in (">=", "<="):
        c = compare_runs(ys, xs)
        if c is not None and c.verdict == SAME:
            return AGREES, "same"
        return OPEN, "not separated" + shown
    return OPEN, "not separated" + shown


def claim_verdict(words) -> str:
    """A scoreboard verdict from the verdicts of a claim's parts: all agree -> reproduced; some agree and some
    contradicted -> partly; none agree and some contradicted -> not reproduced; none contradicted but not all
    decided -> undetermined (parts that agree do not outvote parts that decide nothing)."""
    words = list(words)
    if not words:
        return verdicts.OPEN
    agree, contra = sum(w == AGREES for w in words), sum(w == CONTRADICTED for w in words)
    if agree == len(words):
        return verdicts.REPRODUCED
    if contra == 0:
        return verdicts.OPEN
    return verdicts.PARTLY if agree else verdicts.NOT_REPRODUCED


def tally(words) -> str:
    words = list(words)
    return ", ".join(f"{sum(w == k for w in words)} {k}" for k in (AGREES, CONTRADICTED, OPEN)) + \
        f" (of {len(words)})"


def ordering_check(samples: dict[str, list], expected: list[str], higher_is_better: bool = True
                   ) -> tuple[str, list[str]]:
    """``verdicts.ordering`` on per-run values (None runs left out); a pair with fewer than 2 runs a side is not
    tested (undetermined)."""
    clean = {k: finite(v) for k, v in samples.items()}
    if all(len(clean[k]) >= 2 for k in expected):
        return verdicts.ordering(clean, expected, higher_is_better=higher_is_better)
    lines = [f"{a} before {b}: not tested ({len(clean[a])} and {len(clean[b])} run(s))"
             for a, b in zip(expected[:-1], expected[1:], strict=True)]
    return verdicts.UNDETERMINED, lines


def ordering_verdict(word: str) -> str:
    """The scoreboard's verdict for an ordering's: agrees -> reproduced, contradicted -> not reproduced."""
    return {"agrees": verdicts.REPRODUCED, "contradicted": verdicts.NOT_REPRODUCED}.get(word, verdicts.OPEN)


def value_at(xs, ys, x) -> float:
    """ys at the x in xs (NaN when x is not one of them)."""
    xs = [float(v) for v in xs]
    return float(ys[xs.index(float(x))]) if float(x) in xs else float("nan")


def matched_passes(copy_curves, rl_xs, rl_runs, margin: float | None = None
                   ) -> list[tuple[int, float, float, Comparison | None]]:
    """The copy after k epochs (k passes over the taught lessons) beside QCON-T after k trials (it replays each
    taught lesson once a trial, so also k passes), at every k >= 1 some copy run and QCON-T were measured at:
    (k, copy mean, QCON-T mean, ``compare`` of QCON-T against the copy over runs, or None with fewer than 2 runs a
    side). ``copy_curves`` holds each copy run's own (x, y): a copy stops at full agreement, so its curves differ in
    length. ``margin``: the equivalence margin (default ``verdicts.compare``'s, relative to the copy's mean)."""
    rl_xs = [float(x) for x in rl_xs]
    at = [{float(x): float(y) for x, y in zip(xs, ys, strict=True)} for xs, ys in copy_curves]
    out = []
    for k in sorted(set().union(*at) & set(rl_xs)) if at else []:
        if k < 1:
            continue
        a = [run[k] for run in at if k in run]
        b = [float(r[rl_xs.index(k)]) for r in rl_runs if len(r) == len(rl_xs)]
        if a and b:
            out.append((int(k), float(np.mean(a)), float(np.mean(b)), compare_runs(a, b, margin=margin)))
    return out


def meets_claims(summary: dict, item: str, section: str, anchor: str, labels=None, tag: str = "",
                 item_for=None, calibrated=None) -> list[verdicts.Claim]:
    """A scoreboard claim per quantity of ``summary`` with a thesis number (``meets_thesis``): our mean over runs
    against it (a run that never reaches a level fails the claim). ``labels`` limits the variants; ``tag`` marks a
    re-check (its seeds), ``item_for(label, quantity)`` names the check it repeats (default "ITEM: label,
    quantity"); ``calibrated``: (label, quantity) -> what was chosen on that very claim."""
    out = []
    runs = summary["runs_per_variant"]
    for label, v in summary["variants"].items():
        if labels is not None and label not in labels:
            continue
        for name, q in v["quantities"].items():
            if q.get("thesis") is None:
                continue
            word = "≤" if q.get("better") == "lower" else "≥"
            met = q.get("meets_thesis")
            verdict = (verdicts.REPRODUCED if met else verdicts.NOT_REPRODUCED) if met is not None else verdicts.OPEN
            mean = "—" if q.get("mean") is None else f"{q['mean']:.4g}"
            reached = q.get("runs_reaching", len(q["per_run"]))
            ours = f"{mean} (mean of {reached}/{len(q['per_run'])} runs reaching; {summary['profile']} profile)"
            cause = "" if summary["profile"] == "full" else f"{summary['profile']} profile, not the protocol"
            name_of = item_for(label, name) if item_for else f"{item}: {label}, {name}"
            out.append(verdicts.claim(
                name_of + tag, section, f"{q['thesis']:g}", ours,
                f"mean over {runs} run(s) {word} the thesis's number, every run reaching (no test of spread)",
                verdict, cause, anchor, recheck=bool(tag), calibrated=(calibrated or {}).get((label, name), "")))
    return out
