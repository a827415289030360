"""Run folders are keyed by the values that differ from their declared defaults (``connrl.core.params.run_key``):
declaring a parameter moves no stored run, a changed default is redone, and a folder named by an earlier key is
adopted when its records are these runs'."""

from connrl.experiments import runner
from tests.experiments.toy import ToyParamsGrown, ToyParamsNewDefault, grown_spec, spec


def _run(s, out, seed=0):
    return runner.run_experiment(s, profile="tiny", seed=seed, out=out, workers=1, show_progress=False)


def test_a_parameter_declared_later_moves_no_stored_run(tmp_path):
    first = _run(spec(), tmp_path)
    again = _run(grown_spec(), tmp_path)  # the records lack m: they are read at m's default
    assert (again.ran, again.reused) == (0, 4)
    assert again.summary["variants"] == first.summary["variants"]
    changed = _run(grown_spec(ToyParamsGrown(m=4)), tmp_path)  # m away from its default: new runs
    assert (changed.ran, changed.reused) == (4, 0)


def test_a_changed_default_is_redone(tmp_path):
    _run(spec(), tmp_path)
    redone = _run(grown_spec(ToyParamsNewDefault()), tmp_path)  # same folder (no value off its default) ...
    assert (redone.ran, redone.reused) == (2, 2)  # ... but variant "a" ran n = 5: its records are not these runs'
    assert {r["params"]["n"] for r in redone.records} == {6}


def test_a_folder_of_an_earlier_key_is_adopted_when_its_records_fit(tmp_path):
    """Runs stored before a parameter was declared, in a folder named by an earlier key, are these runs'."""
    _run(spec(), tmp_path)  # ToyParams's records: no field m
    (folder,) = (tmp_path / "toy" / "runs").iterdir()
    earlier = folder.rename(folder.with_name("tiny-0123456789"))
    other = _run(grown_spec(), tmp_path, seed=9)  # another seed's runs: the earlier folder is not theirs
    assert (other.ran, other.reused) == (4, 0) and earlier.exists()
    (mine,) = [p for p in (tmp_path / "toy" / "runs").iterdir() if p != earlier]
    assert mine.name == folder.name
    mine.rename(tmp_path / "elsewhere")  # out of the way: the earlier folder is the only candidate
    back = _run(grown_spec(), tmp_path)
    assert (back.ran, back.reused) == (0, 4) and not earlier.exists()
    assert [p.name for p in (tmp_path / "toy" / "runs").iterdir()] == [folder.name]


def test_a_folder_written_under_the_current_key_for_other_settings_is_left_alone(tmp_path):
    """Two bases that differ only in a value every variant sets: their runs are the same, their folders are not,
    and the second run must not take the first one's folder away from it."""
    import dataclasses

    from connrl.experiments.spec import Variant

    variants = (Variant("a", {"n": 5}), Variant("b/c", {"n": 6}))
    first = dataclasses.replace(grown_spec(ToyParamsGrown(n=7)), variants=variants)
    _run(first, tmp_path)
    (theirs,) = (tmp_path / "toy" / "runs").iterdir()
    second = _run(dataclasses.replace(grown_spec(ToyParamsGrown(n=8)), variants=variants), tmp_path)
    assert (second.ran, second.reused) == (4, 0) and theirs.exists()
