"""CLI: help texts, clear errors before any work, and a tiny-profile smoke run of every experiment."""

import json

import pytest

from connrl import cli
from connrl.experiments.registry import all_experiments


@pytest.mark.parametrize("sub", ["list", "run", "plot", "show", "teach", "results"])
def test_every_command_has_help(sub, capsys):
    with pytest.raises(SystemExit) as e:
        cli.main([sub, "--help"])
    assert e.value.code == 0
    assert "usage: connrl" in capsys.readouterr().out


def test_list_names_every_experiment(capsys):
    cli.main(["list"])
    out = capsys.readouterr().out
    for name in all_experiments():
        assert name in out


def test_unknown_experiment_lists_the_allowed_ones():
    with pytest.raises(SystemExit) as e:
        cli.main(["run", "pole-fulll"])
    assert "unknown experiment 'pole-fulll'" in str(e.value) and "pole-full" in str(e.value)


@pytest.mark.parametrize("args, word", [(["--profile", "huge"], "invalid choice"), (["--runs", "0"], ">= 1"),
                                        (["--runs", "two"], "whole number"), (["--seed", "-3"], ">= 0")])
def test_invalid_parameters_are_refused_before_work(args, word, capsys, tmp_path):
    with pytest.raises(SystemExit) as e:
        cli.main(["run", "pole-full", "--out", str(tmp_path), *args])
    assert e.value.code == 2 and word in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_unknown_teach_target():
    with pytest.raises(SystemExit, match="unknown teach target 'chess'; available: survival"):
        cli.main(["teach", "chess"])


def test_plot_before_run_is_a_clear_error(tmp_path):
    with pytest.raises(SystemExit, match="run `connrl run pole-full` first"):
        cli.main(["plot", "pole-full", "--out", str(tmp_path)])


@pytest.mark.parametrize("name", sorted(all_experiments()))
def test_every_experiment_runs_on_the_tiny_profile(name, tmp_path, capsys):
    assert cli.main(["run", name, "--profile", "tiny", "--out", str(tmp_path), "--workers", "1", "--quiet"]) == 0
    summary = json.loads((tmp_path / name / "summary.json").read_text())
    assert summary["profile"] == "tiny" and summary["variants"]
    assert (tmp_path / name / "curve.png").exists()
    assert cli.main(["plot", name, "--out", str(tmp_path)]) == 0
    assert cli.main(["show", name, "--out", str(tmp_path)]) == 0
