"""The results page's one set of verdict rules: what a claim about two samples of runs may say.

- **Same** (the thesis's "about the same", "similar", "almost the same") is an *equivalence* test: two one-sided
  t-tests at ``alpha`` (TOST), i.e. the (1 - 2 alpha) confidence interval of the difference lies inside
  +-``margin``. Not finding a difference is not evidence of sameness.
- **Different** / **better** is a Welch t-test of the difference (two-sided at ``alpha``, or one-sided for a
  stated direction).
- Otherwise the verdict is **undetermined with N runs**, and ``runs_needed`` says how many runs a side would decide
  it if the observed means and spreads held (a projection, not a promise).

Orderings ("A learns fastest, then B, then C") are checked pair by pair (``ordering``). Every rule prints the numbers
it used (``Comparison.text``), so a reader can apply a rule of their own. The t quantiles are computed here (no
SciPy): the regularized incomplete beta function by its continued fraction (Numerical Recipes, 6.4) and bisection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

ALPHA = 0.05  # each one-sided test of TOST, and the two-sided difference test
REL_MARGIN = 0.10  # "about the same": within 10 % of the reference arm's mean, unless a claim states its own margin
MAX_RUNS_NEEDED = 1000  # a projection beyond this is reported as "more than 1000"


# ------------------------------------------------------------------------------------------ t distribution

def _betacf(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta function (modified Lentz)."""
    tiny, qab, qap, qam = 1e-300, a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 300):
        m2 = 2 * m
        for aa in (m * (b - m) * x / ((qam + m2) * (a + m2)), -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))):
            d = 1.0 + aa * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + aa / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < 1e-15:
            break
    return h


def _betainc(a: float, b: float, x: float) -> float:
    """The regularized incomplete beta function I_x(a, b)."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    front = math.exp(math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x))
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _betacf(a, b, x) / a
    return 1.0 - front * _betacf(b, a, 1.0 - x) / b


def t_cdf(t: float, df: float) -> float:
    """P(T <= t) for Student's t with ``df`` degrees of freedom (df may be fractional: Welch)."""
    tail = 0.5 * _betainc(df / 2.0, 0.5, df / (df + t * t))
    return 1.0 - tail if t >= 0 else tail


def t_quantile(p: float, df: float) -> float:
    """The t with P(T <= t) = p (bisection on ``t_cdf``; exact to ~1e-10)."""
    if not 0.0 < p < 1.0:
        raise ValueError(f"p must be in (0, 1), got {p}")
    if p < 0.5:
        return -t_quantile(1.0 - p, df)
    lo, hi = 0.0, 1.0
    while t_cdf(hi, df) < p:
        lo, hi = hi, hi * 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if t_cdf(mid, df) < p else (lo, mid)
        if hi - lo < 1e-12:
            break
    return 0.5 * (lo + hi)


# ------------------------------------------------------------------------------------------------ verdicts

SAME, DIFFERENT, UNDETERMINED = "same", "different", "undetermined"


@dataclass(frozen=True)
class Comparison:
    """``other`` against ``reference``: their difference (other - reference), its Welch SE and degrees of freedom,
    the (1 - 2 alpha) interval TOST uses, the margin, the verdict and (undetermined) the runs a side that would
    decide it."""

    n: tuple[int, int]  # runs: reference, other
    diff: float
    se: float
    df: float
    ci: tuple[float, float]
    margin: float
    p_difference: float  # Welch, two-sided
    verdict: str  # SAME, DIFFERENT or UNDETERMINED
    runs_needed: int | None = None

    @property
    def same(self) -> bool:
        return self.verdict == SAME

    @property
    def different(self) -> bool:
        return self.verdict == DIFFERENT

    def text(self) -> str:
        """A short account: the verdict, then the numbers behind it."""
        word = {SAME: "same within", DIFFERENT: "different", UNDETERMINED: "undetermined"}[self.verdict]
        head = f"{word} ±{self.margin:.3g}" if self.verdict == SAME else word
        if self.verdict == UNDETERMINED:
            head += f" with {min(self.n)} runs" + (f" (about {self.runs_needed} a side would decide)"
                                                     if self.runs_needed else " (more than "
                                                     f"{MAX_RUNS_NEEDED} a side would be needed)")
        return (f"{head}: difference {self.diff:+.3g}, 90 % CI [{self.ci[0]:+.3g}, {self.ci[1]:+.3g}], "
                f"margin ±{self.margin:.3g}, Welch {p_text(self.p_difference)}")


def p_text(p: float) -> str:
    """A p-value as the page prints it: one below double precision's resolution (a tail computed as 1 - (1 - p))
    is not printed as 0."""
    return "p < 1e-15" if p < 1e-15 else f"p = {p:.2g}"


def _stats(reference, other) -> tuple[np.ndarray, np.ndarray, float, float, float]:
    a, b = np.asarray(reference, float), np.asarray(other, float)
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if min(a.size, b.size) < 2:
        raise ValueError(f"a comparison needs at least 2 finite runs a side, got {a.size} and {b.size}")
    va, vb = a.var(ddof=1) / a.size, b.var(ddof=1) / b.size
    se = math.sqrt(va + vb)
    df = (va + vb) ** 2 / (va ** 2 / (a.size - 1) + vb ** 2 / (b.size - 1)) if se > 0 else float(a.size + b.size - 2)
    return a, b, float(b.mean() - a.mean()), se, df


def _runs_needed(a: np.ndarray, b: np.ndarray, diff: float, margin: float, alpha: float) -> int | None:
    """Runs a side at which, with these means and spreads, either test would decide: the smallest n whose t quantile
    (2n - 2 degrees of freedom) the observed difference, or its distance to the margin, would clear; always more than
    the runs there are, since with them it did not decide."""
    s2 = a.var(ddof=1) + b.var(ddof=1)
    if s2 == 0:
        return None
    gaps = [(abs(diff), 1 - alpha / 2)] if diff != 0 else []
    if abs(diff) < margin:
        gaps.append((margin - abs(diff), 1 - alpha))
    for n in range(max(len(a), len(b)) + 1, MAX_RUNS_NEEDED + 1):
        if any(n >= s2 * (t_quantile(p, 2 * n - 2) / gap) ** 2 for gap, p in gaps):
            return n
    return None


def compare(reference, other, *, margin: float | None = None, rel_margin: float = REL_MARGIN,
            alpha: float = ALPHA) -> Comparison:
    """Is ``other`` the same as ``reference`` (TOST within +-margin; default ``rel_margin`` times |mean(reference)|),
    different (Welch, two-sided), or undetermined? NaN runs are left out; fewer than 2 runs a side is refused."""
    a, b, diff, se, df = _stats(reference, other)
    margin = rel_margin * abs(float(a.mean())) if margin is None else float(margin)
    if se == 0:
        ci, p = (diff, diff), (1.0 if diff == 0 else 0.0)
    else:
        half = t_quantile(1 - alpha, df) * se
        ci, p = (diff - half, diff + half), 2 * (1 - t_cdf(abs(diff) / se, df))
    if ci[0] > -margin and ci[1] < margin:
        verdict = SAME
    elif p < alpha:
        verdict = DIFFERENT
    else:
        verdict = UNDETERMINED
    needed = _runs_needed(a, b, diff, margin, alpha) if verdict == UNDETERMINED else None
    return Comparison((a.size, b.size), diff, se, df, ci, margin, p, verdict, needed)


def better(reference, other, *, higher_is_better: bool = True, alpha: float = ALPHA) -> tuple[str, float]:
    """Is ``other`` better than ``reference``: ("yes" | "no" | "undetermined", one-sided Welch p). "no" means
    significantly worse; neither direction significant is undetermined."""
    _, _, diff, se, df = _stats(reference, other)
    gain = diff if higher_is_better else -diff
    if se == 0:
        return ("yes" if gain > 0 else "no" if gain < 0 else UNDETERMINED), (0.0 if gain > 0 else 1.0)
    p_better = 1 - t_cdf(gain / se, df)
    if p_better < alpha:
        return "yes", p_better
    if 1 - p_better < alpha:
        return "no", p_better
    return UNDETERMINED, p_better


def ordering(samples: dict[str, list[float]], expected: list[str], *, higher_is_better: bool = True,
             alpha: float = ALPHA) -> tuple[str, list[str]]:
    """Check an ordering ``expected`` (best first) pair by pair, each adjacent pair by a one-sided Welch test:
    ("agrees" when every pair is significantly in order, "contradicted" when some pair is significantly reversed,
    "undetermined" otherwise; a line per pair)."""
    lines, worst = [], "agrees"
    for first, second in zip(expected[:-1], expected[1:], strict=True):
        verdict, p = better(samples[second], samples[first], higher_is_better=higher_is_better, alpha=alpha)
        m1, m2 = float(np.nanmean(samples[first])), float(np.nanmean(samples[second]))
        word = {"yes": "in order", "no": "**reversed**", UNDETERMINED: "not separated"}[verdict]
        lines.append(f"{first} ({m1:.3g}) before {second} ({m2:.3g}): {word} (one-sided Welch {p_text(p)})")
        if verdict == "no":
            worst = "contradicted"
        elif verdict == UNDETERMINED and worst == "agrees":
            worst = UNDETERMINED
    return worst, lines


# ---------------------------------------------------------------------------------------------- scoreboard

REPRODUCED, PARTLY, NOT_REPRODUCED, NOT_BUILT, OPEN = "reproduced", "partly", "not reproduced", "not built", \
    "undetermined"
VERDICTS = (REPRODUCED, PARTLY, NOT_REPRODUCED, NOT_BUILT, OPEN)


@dataclass(frozen=True)
class Claim:
    """One thesis result item (a figure, a table or a sentence) as the scoreboard lists it."""

    item: str  # "Fig. 6.5", "Table 4.5", "6.6: 'room B ...'"
    section: str  # thesis section, e.g. "6.6.3"
    thesis: str  # what the thesis reports, short
    ours: str  # our number(s), short
    criterion: str  # the rule the verdict applies
    verdict: str  # one of VERDICTS
    cause: str = ""  # the measured cause of a gap, where known
    anchor: str = ""  # the results page heading it links to (its text; the link is made from it)
    recheck: bool = False  # the same check again (e.g. on fresh seeds): tallied apart, not counted twice
    setting: str = ""  # "" = the thesis's stated values; else the departure from them this check runs at
    calibrated: str = ""  # what was chosen by measuring this very claim (on development seeds), if anything
    thesis_item: str = ""  # the thesis result item (connrl.report.items) where the item text alone is ambiguous

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {VERDICTS}, got {self.verdict!r}")


# thesis result items whose sections print our numbers beside the thesis's but state no rule, so no verdict
UNSCORED = ("Fig. 5.9 (lower / raise repairs)", "Fig. 5.10 (single-layer nets)", "Table 6.1 (complexity of learning)")
BOARD: list[Claim] = []  # filled by the page's sections while ``connrl results`` writes the page


def claim(*args, **kwargs) -> Claim:
    """Put a claim on the scoreboard of the page being written (and return it)."""
    c = Claim(*args, **kwargs)
    BOARD.append(c)
    return c


def _slug(heading: str) -> str:
    """GitHub's anchor for a Markdown heading."""
    text = "".join(ch for ch in heading.strip().lower() if ch.isalnum() or ch in " -_")
    return text.replace(" ", "-")


def _tally(group: list, verdicts=VERDICTS) -> str:
    counts = {v: sum(c.verdict == v for c in group) for v in verdicts}
    return ", ".join(f"{n} {v}" for v, n in counts.items() if n) + f" (of {len(group)})"


def scoreboard(claims: list[Claim]) -> list[str]:
    """The page's opening tables: the thesis's result items, each with one verdict derived from its checks
    (``connrl.report.items.RULE``), then every check, its setting, its verdict, linked to its section; tallies."""
    from connrl.report import items  # the item registry reads claims only; imported here to keep this module's core

    if not claims:
        return []
    rows = items.item_rows(claims)
    first = {}
    for c in claims:
        first.setdefault(items.item_of(c.item, c.section, c.thesis_item, strict=False), c)
    lines = ["## Scoreboard", "",
             f"**The thesis's result items**: one row per figure, table or reported sentence of Chs. 4-8 "
             f"({len(rows)}; `connrl/report/items.py`). {items.RULE}", "",
             "| thesis item | section | the thesis reports | checks: stated values / our departures / their re-checks "
             "| verdict | notes |", "|---|---|---|---|---|---|"]
    for r in rows:
        c = first.get(r.key)
        key = f"[{r.key}](#{_slug(c.anchor)})" if c is not None and c.anchor else r.key
        verdict = r.verdict if r.verdict == REPRODUCED else f"**{r.verdict}**"
        lines.append(f"| {key} | {r.section} | {r.statement} | {r.checks} / {r.departures} / {r.rechecks} | "
                     f"{verdict} | {r.note} |")
    lines += ["", f"Thesis items: {_tally(rows, items.ITEM_VERDICTS)}.", "",
              "### Checks", "",
              "Every check the page makes, with our number, the rule applied and the verdict (rules: "
              f"`connrl/report/verdicts.py`; \"same\" is an equivalence test, TOST at {ALPHA:g} within the stated "
              "margin, never the absence of a significant difference). The setting column says whether a check runs "
              "the thesis's stated values or departs from them (only the former decide an item); a check whose "
              "setting was chosen by measuring that very claim says so. Result items the page shows without a "
              f"verdict: {', '.join(UNSCORED)}. The quantities we tuned follow the table.", "",
              "| check | section | thesis | ours | setting | criterion | verdict |", "|---|---|---|---|---|---|---|"]
    for c in claims:
        item = f"[{c.item}](#{_slug(c.anchor)})" if c.anchor else c.item
        verdict = c.verdict if c.verdict == REPRODUCED else f"**{c.verdict}**"
        setting = c.setting or "stated values"
        mark = "a re-check of a setting **calibrated on this claim**" if c.recheck else "**calibrated on this claim**"
        criterion = (f"{mark}: {c.calibrated}; " if c.calibrated else "") + c.criterion
        lines.append(f"| {item} | {c.section} | {c.thesis} | {c.ours} | {setting} | {criterion} | {verdict}"
                     f"{': ' + c.cause if c.cause else ''} |")
    lines += [""]
    for kind, group in (("Checks at the thesis's stated values", [c for c in claims if not c.recheck and not
                                                                   c.setting]),
                        ("Checks at our departures from them (shown, not counted for an item)",
                         [c for c in claims if not c.recheck and c.setting]),
                        ("Re-checks on seeds never used in development, of stated-value checks (an item counts one "
                         "in place of the check it repeats)", [c for c in claims if c.recheck and not c.setting]),
                        ("Re-checks of departures (shown, not counted for an item)",
                         [c for c in claims if c.recheck and c.setting])):
        if group:
            lines.append(f"{kind}: {_tally(group)}.")
    return lines + [""]
