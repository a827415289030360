"""The page's wording of an experiment's time: its wall time (alone or as a span in a pool) and its runs' own times,
a run copied from a twin counted where it ran."""

from connrl.report.wall import copies_text, run_seconds, wall_text


def _summary(**timing):
    return {"timing": {"wall_time_s": 120.0, "run_wall_time_s": [3.0, 4.0, 5.0], **timing}}


def test_run_seconds_leave_out_copied_runs_and_say_how_many():
    assert run_seconds(_summary()) == [3.0, 4.0, 5.0]  # summaries from before copies: every run its own
    s = _summary(run_copied=[False, True, True])
    assert run_seconds(s) == [3.0] and copies_text(s) == "; 2 runs copied from twin runs"
    assert copies_text(_summary(run_copied=[True, False, False])) == "; 1 run copied from twin runs"
    assert copies_text(_summary(run_copied=[False] * 3)) == ""


def test_wall_text_says_a_pooled_time_is_a_span():
    assert wall_text(_summary()) == "wall time 120 s"
    pooled = "2.0 min from its first run to its last in a pool with other experiments"
    assert wall_text(_summary(pooled=True), "min") == pooled
