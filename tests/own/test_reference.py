"""docs/API.md is the own-task API's docstrings as they stand (connrl.own.reference)."""

from pathlib import Path

from connrl.own.reference import AGENT_METHODS, ENTRIES, reference


def test_docs_api_md_is_current():
    doc = (Path(__file__).parents[2] / "docs" / "API.md").read_text()
    assert reference() == doc, "docs/API.md is stale: run `python -m connrl.own.reference > docs/API.md`"


def test_every_entry_is_documented_and_the_public_names_are_all_there():
    import connrl

    text = reference()
    assert "(no docstring)" not in text
    for name in connrl._API:
        assert f"### `connrl.{name}(" in text
    assert len(ENTRIES) == len({name for _, _, name in ENTRIES})
    assert all(f"#### `Agent.{m}(" in text for m in AGENT_METHODS)
