"""The thesis's result items (connrl.report.items): the registry is whole, every check on the committed page is
placed, and an item's verdict follows the stated rule on small cases worked by hand."""

import re
from pathlib import Path

from connrl.report import items
from connrl.report.verdicts import NOT_REPRODUCED, OPEN, PARTLY, REPRODUCED, Claim

T45, FIG43 = "Table 4.5: plays to reach 8", "4.4.3: the learned model never nearly perfect"


def _verdicts(claims) -> dict[str, str]:
    return {r.key: r.verdict for r in items.item_rows(claims)}


def test_registry_is_whole():
    assert len(set(items.KEYS)) == len(items.KEYS)
    placed = set(items.CHECK_TO_ITEM.values()) | set(items._BY_SECTION.values()) | {k for _, k in items._PATTERNS}
    placed |= set(items.THESIS_ITEM_TO_ITEM.values())
    assert placed <= set(items.KEYS) and set(items.UNCHECKED) <= set(items.KEYS)
    for key in items.KEYS:  # every item has checks or says why not, never both
        assert (key in placed) != (key in items.UNCHECKED), key


def test_every_check_on_the_committed_page_is_placed():
    page = (Path(__file__).parents[2] / "docs" / "RESULTS.md").read_text()
    rows = re.findall(r"^\| \[(.+?)\]\(#[^)]*\) \| ([^|]+?) \|", page, flags=re.M)
    checks = [(i, s) for i, s in rows if not any(i == k for k in items.KEYS)]
    assert len(checks) > 50
    for item, section in checks:
        items.item_of(item, section)  # raises on a check it cannot place


def test_a_departure_is_shown_but_never_decides_an_item():
    v = _verdicts([Claim(T45, "4.5", "t", "o", "c", REPRODUCED),
                   Claim(T45, "4.5", "t", "o", "c", NOT_REPRODUCED, setting="ours: lr 0.03")])
    assert v["4.5 speedup table"] == REPRODUCED
    only = _verdicts([Claim(T45, "4.5", "t", "o", "c", REPRODUCED, setting="ours: lr 0.03")])
    assert only["4.5 speedup table"] == OPEN


def test_a_recheck_counts_in_place_of_the_check_it_repeats():
    base = Claim(T45, "4.5", "t", "o", "c", REPRODUCED)
    fresh = Claim(T45 + " (fresh seeds 2000-2006)", "4.5", "t", "o", "c", NOT_REPRODUCED, recheck=True)
    other = Claim(T45 + " (fresh seeds 2000-2006)", "4.5", "another sentence", "o", "c", NOT_REPRODUCED, recheck=True)
    assert _verdicts([base, fresh])["4.5 speedup table"] == NOT_REPRODUCED
    assert _verdicts([base, other])["4.5 speedup table"] == REPRODUCED  # it repeats another check


def test_a_check_calibrated_on_its_own_claim_needs_a_recheck_to_reproduce():
    cal = Claim(T45, "4.5", "t", "o", "c", REPRODUCED, calibrated="the door width")
    row = next(r for r in items.item_rows([cal]) if r.key == "4.5 speedup table")
    assert row.verdict == OPEN and "calibrated on its own claim, not re-checked" in row.note
    fresh = Claim(T45 + " (fresh seeds 1000-1006)", "4.5", "t", "o", "c", REPRODUCED, recheck=True)
    assert _verdicts([cal, fresh])["4.5 speedup table"] == REPRODUCED
    failed = Claim(T45, "4.5", "t", "o", "c", NOT_REPRODUCED, calibrated="the door width")
    assert _verdicts([failed])["4.5 speedup table"] == NOT_REPRODUCED


def test_combining_checks():
    def item(*verdicts):
        return _verdicts([Claim(T45, "4.5", f"t{i}", "o", "c", v) for i, v in enumerate(verdicts)])[
            "4.5 speedup table"]

    assert item(REPRODUCED, REPRODUCED) == REPRODUCED
    assert item(REPRODUCED, OPEN) == OPEN  # agreeing parts do not outvote an undecided one
    assert item(REPRODUCED, NOT_REPRODUCED) == PARTLY
    assert item(PARTLY) == PARTLY
    assert item(NOT_REPRODUCED, OPEN) == NOT_REPRODUCED
    assert item(OPEN, OPEN) == OPEN


def test_items_without_checks_say_why():
    rows = {r.key: r for r in items.item_rows([Claim(FIG43, "4.4.3", "t", "o", "c", REPRODUCED)])}
    assert rows["4.4.3 model accuracy"].verdict == REPRODUCED
    assert rows["4.3.2 / Table 4.1"].verdict == items.NOT_BUILT
    assert rows["6.2.4 / Table 6.1"].verdict == OPEN and "without a rule" in rows["6.2.4 / Table 6.1"].note
    assert rows["4.5 speedup table"].verdict == OPEN and rows["4.5 speedup table"].note.startswith("not run")


def test_an_unplaced_check_gets_a_row_of_its_own_instead_of_failing_the_page():
    rows = items.item_rows([Claim("A new claim", "9.9", "t", "o", "c", REPRODUCED)])
    assert rows[-1].key == items.UNPLACED + "A new claim" and rows[-1].verdict == REPRODUCED
