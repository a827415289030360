"""``connrl results``: a results page (OUT/RESULTS.md, or docs/RESULTS.md with ``--doc``) from the stored
``OUT/NAME/summary.json`` files.

Every number on the page comes from a summary written by ``connrl run``; the page says which command,
profile, runs and seeds produced it. Each chapter's section is a module of ``connrl.report`` (``SECTIONS``)
with ``EXPERIMENTS`` (the specs it reports) and ``results_section(out_dir, doc)``; figures go
in ``doc``'s folder. Hand-written paragraphs live in ``docs/notes/*.md`` and are included with ``note``.
"""

from __future__ import annotations

import csv
import importlib
import io
import math
import shutil
import sys
from pathlib import Path

from connrl.experiments import store
from connrl.experiments.registry import all_experiments
from connrl.experiments.runner import make_jobs, missing_runs, stored_runs
from connrl.experiments.store import DamagedFile
from connrl.report import verdicts
from connrl.report.wall import wall_text
from connrl.storage import FileError, atomic_write_text, read_limited_text


def fmt(v) -> str:
    """A number for a table: 4 significant digits, a dash for none."""
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def fixed(v, digits: int = 2) -> str:
    """A number with ``digits`` decimals (whole numbers without), a dash for none or a non-finite value."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "—"
    return f"{v:.{digits}f}" if isinstance(v, float) and not float(v).is_integer() else f"{v:g}"


def per_run(q: dict, diverged: list | None) -> str:
    """A quantity's per-run values; a run whose networks diverged shows as such, not as "not reached"."""
    div = diverged or [None] * len(q["per_run"])
    return ", ".join(f"diverged (trial {d})" if d is not None else fmt(x) for x, d in zip(q["per_run"], div,
                                                                                          strict=False))


def meets(q: dict, profile: str, markdown: bool = True, runs: int | None = None,
          protocol_runs: int | None = None) -> str:
    """Whether the mean beats the thesis; it says so when the profile, or fewer runs, is not the protocol."""
    word = {True: "yes", False: "**no**" if markdown else "no", None: "—"}[q.get("meets_thesis")]
    if q.get("meets_thesis") is None:
        return word
    if profile != "full":
        word += f" ({profile} profile: not the thesis's protocol)"
    elif runs is not None and protocol_runs is not None and runs < protocol_runs:
        word += f" ({runs} run(s); the protocol has {protocol_runs})"
    return word


def summary_table(summary: dict) -> str:
    """Our numbers beside the thesis's for one experiment's summary."""
    lines = [
        f"`connrl run {summary['experiment']} --profile {summary['profile']} --runs {summary['runs_per_variant']} "
        f"--seed {summary['base_seed']}` — {summary['runs_per_variant']} run(s) per variant, seeds "
        f"{summary['base_seed']}..{summary['base_seed'] + summary['runs_per_variant'] - 1}, "
        f"{wall_text(summary)}, commit "
        f"`{(summary['environment'].get('git_commit') or 'unknown')[:10]}`.",
        "",
        "| variant | quantity | better | ours (mean) | per run | thesis | meets thesis |",
        "|---|---|---|---|---|---|---|",
    ]
    runs = (summary["runs_per_variant"], summary.get("protocol_runs"))
    for label, v in summary["variants"].items():
        for name, q in v["quantities"].items():
            word = meets(q, summary["profile"], True, *runs)
            lines.append(f"| {label} | {name} | {q.get('better', '')} | {fmt(q['mean'])} | "
                         f"{per_run(q, v.get('diverged'))} | {fmt(q['thesis'])} | {word} |")
    return "\n".join(lines)


def figure(png: Path, doc: Path, name: str) -> str:
    """Copy a plot next to the results page (docs/figures/NAME.png) and return its Markdown image link."""
    if not png.exists():
        return ""
    dest = doc.parent / "figures" / f"{name}.png"
    dest.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(png, dest)
    return f"![{name}](figures/{dest.name})"


NOTES_DIR = Path(__file__).resolve().parents[2] / "docs" / "notes"
SECTIONS = ("connrl.report.pole", "connrl.report.survival", "connrl.report.hidden_state", "connrl.report.robot",
            "connrl.report.world_family", "connrl.report.td_depth", "connrl.report.recharge",
            "connrl.report.complexity",
            "connrl.report.integration", "connrl.report.before_after")


def note(name: str) -> str:
    """The hand-written paragraph(s) of ``docs/notes/NAME.md``, without a trailing newline."""
    path = NOTES_DIR / f"{name}.md"
    if not path.exists():
        return f"(note `docs/notes/{name}.md` not found: the notes ship with the source tree)"
    return path.read_text().strip()


def recheck_tag(summaries: list[dict], first: int, runs: int) -> str:
    """The label of a re-check on fresh seeds: those seeds when every summary is the full-profile check its note
    describes (``runs`` runs from seed ``first``), else what ran, marked as not the check, so that a smoke run at
    seed 0 never passes for it."""
    ran = sorted({(s["base_seed"], s["runs_per_variant"], s["profile"]) for s in summaries})
    if ran == [(first, runs, "full")]:
        return f" (fresh seeds {first}-{first + runs - 1})"
    return " (" + "; ".join(f"seeds {b}-{b + n - 1}, {p} profile" for b, n, p in ran) + ": not the check)"


def warn(message: str) -> None:
    print(f"connrl: warning: {message}", file=sys.stderr)


def load_summary(out: Path, name: str) -> dict | None:
    """OUT/NAME/summary.json, or None when it is absent or damaged (said on stderr: one bad summary leaves out
    its own section, not the page)."""
    p = Path(out) / name / "summary.json"
    if not p.exists():
        return None
    try:
        return store.load_summary(p, name)
    except DamagedFile as exc:
        warn(f"{exc}; left out of the page")
        return None


def _value(v: str) -> float | str:
    try:
        return float(v)
    except ValueError:
        return v  # a label column (e.g. survival's kind: train / test)


def run_rows(spec, summary: dict, out_dir: Path, label: str) -> list[list[dict]]:
    """Each stored run's CSV rows (one per test: trials, performance, ...) of one variant, numbers as floats (empty
    cells left out); runs not stored yet are left out."""
    jobs = make_jobs(spec, summary["profile"], summary["runs_per_variant"], summary["base_seed"], out_dir)
    out = []
    for j in jobs:
        f = Path(f"{j.path}.csv")
        if j.variant == label and f.exists():
            try:
                text = read_limited_text(f, store.MAX_JSON_BYTES, "run CSV")
            except FileError as exc:  # one bad file leaves out its run, not the page
                warn(f"{exc}; left out")
                continue
            out.append([{k: _value(v) for k, v in row.items() if v not in ("", None)}
                        for row in csv.DictReader(io.StringIO(text))])
    return [r for r in out if r]


def stored(spec, out: Path) -> tuple[dict | None, list[dict]]:
    """``connrl.experiments.runner.stored_runs`` for a results section: a damaged summary is left out (and said),
    and a section drawn from fewer runs than its summary lists says so."""
    try:
        summary, records = stored_runs(spec, Path(out), lambda p, why: warn(f"{p} is damaged ({why}); left out"))
    except DamagedFile as exc:
        warn(f"{exc}; left out of the page")
        return None, []
    missing = missing_runs(spec.name, summary, records) if summary is not None else None
    if missing:
        warn(f"{missing}; its section shows the others")
    # a diverged run has no curve and no quantities: the section reads the others (diverged_lines lists it)
    return summary, [r for r in records if not r.get("diverged")]


def diverged_lines(out: Path, names) -> list[str]:
    """A line per run whose networks diverged (a failed run, not a slow one), for the chapter's section."""
    lines = []
    for name in names:
        try:
            summary = store.load_summary(Path(out) / name / "summary.json", name)
        except (OSError, DamagedFile):
            continue  # absent, or already reported by the section
        for label, v in summary["variants"].items():
            for seed, trial in zip(v.get("seeds", []), v.get("diverged") or [], strict=False):
                if trial is not None:
                    lines.append(f"- **Diverged:** `{name}`, {label}, seed {seed}: the networks diverged after "
                                 f"training trial {trial}; the run counts as failed.")
    return lines + [""] if lines else []


def redraw_missing_curves(out: Path, specs: dict) -> None:
    """Draw OUT/NAME/curve.png from the stored records where it is missing (a copy of the records without their
    plots, e.g. results/thesis as committed, gives the same page)."""
    from connrl.report.plots import plot_experiment

    for name, spec in specs.items():
        folder = Path(out) / name
        if (folder / "summary.json").exists() and not (folder / "curve.png").exists():
            summary, records = stored(spec, out)
            if summary is not None and records:
                plot_experiment(spec, records, folder)


def _plain_sections(out: Path, doc: Path, specs: dict, names: list[str], covered: set[str]) -> list[str]:
    """A summary table and curve for each of ``names`` with stored results (added to ``covered``)."""
    parts = []
    for name in names:
        summary = load_summary(out, name)
        if summary is None:
            continue
        spec = specs[name]
        parts += [f"## {name}: {spec.title} (thesis {spec.section})", "", summary_table(summary), "",
                  figure(out / name / "curve.png", doc, name), ""]
        covered.add(name)
    return parts


def write_results(out: Path, doc: Path) -> Path:
    specs = all_experiments()
    parts = [
        "# Results: connrl beside the thesis",
        "",
        f"Generated by `connrl results --out {out} --doc {doc}` from the `summary.json` files and run records that "
        "`connrl run` wrote (the same records give the same page). Do not edit by hand: re-run the experiments and "
        "this command.",
        "",
    ]
    verdicts.BOARD.clear()  # the sections put their claims on it
    redraw_missing_curves(out, specs)
    covered = set()
    for mod in SECTIONS:
        module = importlib.import_module(mod)
        names = [s.name for s in module.EXPERIMENTS]
        text = module.results_section(out, doc)
        if text:
            parts += [text, ""] + diverged_lines(out, names)
            covered.update(names)
            continue
        parts += _plain_sections(out, doc, specs, names, covered)
    # an experiment no section module reports (a new figure's, until it has one): its table and curve
    parts += _plain_sections(out, doc, specs, [n for n in specs if n not in covered], covered)
    missing = sorted(set(specs) - covered)
    if missing:
        parts += ["## Not yet run", "", "No stored results for: " + ", ".join(f"`{m}`" for m in missing) + ".", ""]
    board = verdicts.scoreboard(list(verdicts.BOARD))
    parts[4:4] = board + (["## Quantities we tuned, and where we depart from the thesis", "", note("tuned-quantities"),
                           "", note("prereg-fresh-checks"), ""] if board else [])
    atomic_write_text(doc, "\n".join(parts))
    return doc
