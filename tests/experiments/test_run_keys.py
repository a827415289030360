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
    _run(spec(), tmp_path)
    (folder,) = (tmp_path / "toy" / "runs").iterdir()
    folder.rename(folder.with_name("tiny-0123456789"))
    other = _run(spec(), tmp_path, seed=9)  # another seed's runs: the earlier folder is not theirs
    assert (other.ran, other.reused) == (4, 0)
    assert sorted(p.name for p in (tmp_path / "toy" / "runs").iterdir())[0] == "tiny-0123456789"
    for p in (tmp_path / "toy" / "runs").iterdir():
        if p.name != "tiny-0123456789":
            for f in sorted(p.rglob("*"), reverse=True):
                f.unlink() if f.is_file() else f.rmdir()
            p.rmdir()
    back = _run(spec(), tmp_path)
    assert (back.ran, back.reused) == (0, 4)
    assert [p.name for p in (tmp_path / "toy" / "runs").iterdir()] == [folder.name]
