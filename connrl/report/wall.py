"""How the page words an experiment's wall time: alone (``connrl run``) it is the command's; in one pool with other
experiments (``connrl reproduce``, issue 45) it is the span of its runs there, shared with the others' runs."""

from __future__ import annotations


def wall_text(summary: dict, unit: str = "s") -> str:
    t = summary["timing"]
    value = f"{t['wall_time_s']:.0f} s" if unit == "s" else f"{t['wall_time_s'] / 60:.1f} min"
    return f"{value} from its first run to its last in a pool with other experiments" if t.get("pooled") else (
        f"wall time {value}")


def run_seconds(summary: dict) -> list[float]:
    """The run times an experiment spent: its runs' own, without those copied from a twin run in another experiment
    (``timing.run_copied``; their time is counted where they ran)."""
    t = summary["timing"]
    copied = t.get("run_copied") or [False] * len(t["run_wall_time_s"])
    return [w for w, c in zip(t["run_wall_time_s"], copied, strict=True) if not c]


def copied_runs(summary: dict) -> int:
    """How many of an experiment's runs were copied from a twin run (``timing.run_copied``)."""
    return sum(summary["timing"].get("run_copied") or [])


def copies_text(summary: dict) -> str:
    """``; N runs copied from twin runs`` when some were, else nothing."""
    n = copied_runs(summary)
    return f"; {n} run{'s' if n > 1 else ''} copied from twin runs" if n else ""
