"""How the page words an experiment's wall time: alone (``connrl run``) it is the command's; in one pool with other
experiments (``connrl reproduce``, issue 45) it is the span of its runs there, shared with the others' runs."""

from __future__ import annotations


def wall_text(summary: dict, unit: str = "s") -> str:
    t = summary["timing"]
    value = f"{t['wall_time_s']:.0f} s" if unit == "s" else f"{t['wall_time_s'] / 60:.1f} min"
    return f"{value} from its first run to its last in a pool with other experiments" if t.get("pooled") else (
        f"wall time {value}")
