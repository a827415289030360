"""docs/RESULTS.md: number formatting, the per-experiment table, figures beside the page, the whole page."""

import json

from connrl.report.page import figure as figure_link
from connrl.report.page import fmt, note, summary_table, write_results
from tests.tiny_runs import run_tiny


def test_fmt():
    assert (fmt(None), fmt(0.123456), fmt(12345.6), fmt(3)) == ("-", "0.1235", "1.235e+04", "3")


def test_summary_table_has_one_row_per_variant_and_quantity(tiny_runs):
    out = tiny_runs("pole-full")
    summary = json.loads((out / "pole-full" / "summary.json").read_text())
    table = summary_table(summary)
    assert table.startswith("`connrl run pole-full --profile tiny --runs 1 --seed 0`")
    rows = [line for line in table.splitlines() if line.startswith("| QCON-R |")]
    assert len(rows) == 1 and rows[0].split("|")[2].strip() == "trials_to_satisfactory"
    assert rows[0].split("|")[3].strip() == "lower"  # which way is better
    assert rows[0].split("|")[6].strip() == "119"  # the thesis's number beside ours


def test_figure_is_copied_next_to_the_page(tiny_runs, tmp_path):
    out = tiny_runs("pole-full")
    doc = tmp_path / "docs" / "RESULTS.md"
    assert figure_link(out / "pole-full" / "curve.png", doc, "pole-full") == "![pole-full](figures/pole-full.png)"
    assert (tmp_path / "docs" / "figures" / "pole-full.png").exists()
    assert figure_link(out / "nothing.png", doc, "x") == ""


def test_notes_are_read_from_docs_notes():
    assert note("pole-intro") and "not found" not in note("pole-intro")
    assert "not found" in note("no-such-note")


def test_write_results_has_every_chapter_and_names_its_source(tmp_path):
    out = tmp_path / "runs"
    for name in ("pole-full", "cup-task1"):
        run_tiny(name, out)
    doc = write_results(out, tmp_path / "RESULTS.md")
    text = doc.read_text()
    assert text.startswith("# Results: connrl beside the thesis")
    assert f"`connrl results --out {out} --doc {tmp_path / 'RESULTS.md'}`" in text
    for heading in ("## Pole balancing, full state", "## Chapter 7: hidden state", "## Chapter 5: robot skills"):
        assert heading in text
    assert "connrl run pole-full --profile tiny" in text and "Command: `connrl run cup-task1" in text
    assert "## Not yet run" in text and "`survival-study1`" in text
    # the scoreboard opens the page (pole-full and the cup tasks put claims on it), the tuned quantities follow it
    board, tuned, first = (text.index(h) for h in ("## Scoreboard", "## Quantities we tuned", "## Pole balancing"))
    assert "Re-checks fixed before they ran" in text[tuned:first]
    assert board < tuned < first and "Fig. 7.5: 2-cup collection" in text[board:tuned]


def test_the_page_is_the_same_from_the_same_records_even_without_their_plots(tmp_path):
    """The records alone make the page: written twice, or after the run's own plot is deleted, it is the same."""
    out = tmp_path / "runs"
    run_tiny("pole-full", out)
    first = write_results(out, tmp_path / "a" / "RESULTS.md").read_text()
    (out / "pole-full" / "curve.png").unlink()
    second = write_results(out, tmp_path / "a" / "RESULTS.md").read_text()
    assert first == second and (out / "pole-full" / "curve.png").exists()


def test_an_experiment_no_section_reports_gets_its_table_not_not_yet_run(tmp_path, monkeypatch):
    """A new figure needs no report module: once run, the page shows its summary table and curve."""
    import dataclasses

    from connrl.experiments.registry import all_experiments
    from connrl.experiments.runner import run_experiment
    from connrl.report import page
    from tests.experiments.toy import spec

    toy = dataclasses.replace(spec(), name="toy-figure", title="A toy figure")
    monkeypatch.setattr(page, "all_experiments", lambda: {**all_experiments(), "toy-figure": toy})
    out = tmp_path / "runs"
    run_experiment(toy, profile="tiny", out=out, workers=1, show_progress=False)
    text = write_results(out, tmp_path / "RESULTS.md").read_text()
    assert "## toy-figure: A toy figure (thesis -)" in text and "`connrl run toy-figure --profile tiny" in text
    assert "`toy-figure`" not in text[text.index("## Not yet run"):]
