"""Per-task settings files (connrl.own.settings, RL Zoo's shape) and `connrl tune`'s input: every wrong value is one
line naming the file and entry, reading YAML never builds Python objects, the command line overrides the file."""

from __future__ import annotations

import dataclasses
import json

import pytest

from connrl import cli
from connrl.own.api import AgentOptions
from connrl.own.settings import SETTINGS_DIR, check_entry, read_settings, settings_yaml, task_settings
from connrl.own.tune import Dimension, parse_dimension


def test_a_settings_entry_is_read_and_the_command_line_overrides_it(tmp_path, capsys):
    f = tmp_path / "mine.yml"
    f.write_text("CartPole-v1:\n  n_timesteps: 400\n  hidden: 5\n  lr: 0.02\n")
    assert cli.main(["train", "CartPole-v1", "--hyperparams", str(f), "--option", "lr=0.03", "--quiet",
                     "--save", str(tmp_path / "a")]) == 0
    s = json.loads((tmp_path / "a" / "settings.json").read_text())
    assert (s["steps"], s["options"], s["settings_from"]) == (400, {"hidden": 5, "lr": 0.03}, f"{f} [CartPole-v1]")
    assert json.loads((tmp_path / "a" / "agent.json").read_text())["options"]["hidden"] == 5


@pytest.mark.parametrize("text, message", [
    ("CartPole-v1:\n  lr2: 0.1\n", "entry 'CartPole-v1': unknown option(s) 'lr2'"),
    ("CartPole-v1:\n  n_timesteps: -5\n", "n_timesteps must be a whole number from 1 to"),
    ("CartPole-v1:\n  env_kwargs: [1, 2]\n", "env_kwargs must be a mapping"),
    ("CartPole-v1: [1, 2]\n", "entry 'CartPole-v1' must be a mapping of settings"),
    ("- CartPole-v1\n", "must map environment ids to settings"),
    ("CartPole-v1:\n  lr: [\n", "is not valid YAML"),
    ("CartPole-v1: !!python/object/apply:os.system ['echo pwned']\n", "is not valid YAML"),  # never run code
    ("CartPole-v1:\n  env_kwargs: {day: 2020-01-01}\n", "env_kwargs must be plain values"),  # a YAML date
])
def test_a_bad_settings_file_is_one_line(text, message, tmp_path):
    f = tmp_path / "bad.yml"
    f.write_text(text)
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[")):
        read_settings(f)
    with pytest.raises(SystemExit, match="connrl: .*bad.yml"):
        cli.main(["train", "CartPole-v1", "--hyperparams", str(f), "--save", str(tmp_path / "x")])
    assert not (tmp_path / "x").exists()


def test_an_id_missing_from_a_given_file_is_refused_and_an_unlisted_id_uses_the_defaults(tmp_path):
    f = tmp_path / "mine.yml"
    f.write_text("Acrobot-v1:\n  hidden: 5\n")
    with pytest.raises(ValueError, match=r"has no entry for 'CartPole-v1' \(it has: Acrobot-v1\)"):
        task_settings("CartPole-v1", "QCON-R", f)
    assert task_settings("NoSuchTask-v0", "QCON-R") == (None, None)


def test_every_shipped_settings_file_is_valid_and_written_settings_read_back(tmp_path):
    files = sorted(SETTINGS_DIR.glob("*.yml"))
    assert files, "connrl ships settings for the tasks it measures"
    for f in files:
        assert read_settings(f)
    text = settings_yaml("CartPole-v1", 1000, {"sutton_barto_reward": True}, {"lr": 0.02, "hidden": 8}, "a\nb")
    (tmp_path / "s.yml").write_text(text)
    assert text.startswith("# a\n# b\n")
    assert read_settings(tmp_path / "s.yml") == {"CartPole-v1": {"n_timesteps": 1000, "env_kwargs": {
        "sutton_barto_reward": True}, "options": {"lr": 0.02, "hidden": 8}}}


def test_env_kwargs_reach_the_environment_and_a_bad_one_is_one_line(tmp_path, capsys):
    assert cli.main(["train", "CartPole-v1", "--steps", "200", "--quiet", "--save", str(tmp_path / "a"),
                     "--env-kwargs", "sutton_barto_reward=true"]) == 0
    assert json.loads((tmp_path / "a" / "settings.json").read_text())["env_kwargs"] == {"sutton_barto_reward": True}
    assert cli.main(["evaluate", str(tmp_path / "a"), "--episodes", "1"]) == 0  # made with the kwargs it trained on
    with pytest.raises(SystemExit, match="cannot make environment 'CartPole-v1'.*nope"):
        cli.main(["train", "CartPole-v1", "--steps", "200", "--save", str(tmp_path / "b"), "--env-kwargs", "nope=1"])


@pytest.mark.parametrize("text, dim", [
    ("lr=0.01:0.1:log", Dimension("lr", low=0.01, high=0.1, log=True)),
    ("hidden=4:32", Dimension("hidden", low=4, high=32)),
    ("lam=0.3,0.7", Dimension("lam", choices=(0.3, 0.7))),
])
def test_search_dimensions_parse(text, dim):
    assert parse_dimension(text) == dim


@pytest.mark.parametrize("args, message", [
    (["--space", "lr2=1,2"], "unknown option 'lr2'"),
    (["--space", "lr=0.1:0.01"], "a range needs two numbers low < high"),
    (["--space", "lr=0:1:log"], "a log range needs low > 0"),
    (["--space", "hidden=4:100000"], "option hidden must be a whole number from 0 to 1,024"),
    (["--space", "lr=0.01,0.1", "--option", "lr=0.05"], "lr is both searched (--space) and fixed (--option)"),
    (["--agent", "QCON-T"], "argument --agent: invalid choice"),
])
def test_tune_refuses_bad_input_in_one_line_before_training(args, message, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["tune", "CartPole-v1", "--out", str(tmp_path / "t"), *args])
    assert message in str(exc.value) + capsys.readouterr().err
    assert not (tmp_path / "t" / "trials.csv").exists()


def test_tune_with_optuna_tpe_runs_and_resumes_without_drawing_the_same_settings_again(tmp_path, capsys):
    pytest.importorskip("optuna")
    args = ["tune", "CartPole-v1", "--space", "lr=0.02:0.1:log", "--steps", "200", "--seeds", "1000",
            "--eval-episodes", "1", "--sampler", "tpe", "--out", str(tmp_path / "t"), "--trials"]
    assert cli.main([*args, "2"]) == 0
    first = (tmp_path / "t" / "trials.csv").read_text().splitlines()
    assert cli.main([*args, "3"]) == 0
    rows = (tmp_path / "t" / "trials.csv").read_text().splitlines()
    assert rows[:3] == first
    assert rows[3].split(",")[1] not in {r.split(",")[1] for r in rows[1:3]}  # a new setting, not trial 1's again


def test_a_search_folder_that_is_not_this_search_is_refused_in_one_line(tmp_path):
    args = ["tune", "CartPole-v1", "--space", "lr=0.02,0.1", "--steps", "100", "--seeds", "1000", "--eval-episodes",
            "1", "--trials", "1", "--out", str(tmp_path / "t")]
    (tmp_path / "t").mkdir()
    (tmp_path / "t" / "study.json").write_text("[]")
    with pytest.raises(SystemExit, match="holds another search"):
        cli.main(args)
    (tmp_path / "t" / "study.json").unlink()
    (tmp_path / "t" / "trials.csv").write_text("trial,params,scores,mean,seconds\n")
    with pytest.raises(SystemExit, match="has no study.json beside it"):
        cli.main(args)


def test_drawn_settings_stay_in_their_range_and_float_options_draw_floats():
    import numpy as np

    rng = np.random.default_rng(0)
    gamma = parse_dimension("gamma=0.999:0.99999")
    assert all(0.999 <= gamma.sample(rng) <= 0.99999 for _ in range(2000))
    lam = parse_dimension("lam=0:1")
    assert len({lam.sample(rng) for _ in range(50)}) > 2  # not only 0 and 1
    assert isinstance(parse_dimension("hidden=4:8").sample(rng), int)


def _count_fields() -> list[str]:
    """Every option that holds a count (an int field of ``AgentOptions``), and the settings file's own n_timesteps."""
    return [f.name for f in dataclasses.fields(AgentOptions) if f.type in ("int", int, "int | None")] + ["n_timesteps"]


@pytest.mark.parametrize("name", _count_fields())
@pytest.mark.parametrize("value", [True, False, 8.0, 8.5])
def test_a_boolean_or_a_float_where_a_count_belongs_is_refused_by_name(name, value):
    """YAML's ``true`` is an int subclass in Python and ``8.0`` equals 8: neither is taken as a count (issue 46)."""
    with pytest.raises(ValueError, match=rf"{name} must be a whole number") as info:
        check_entry("own.yml", "CartPole-v1", {name: value})
    assert str(info.value).startswith("own.yml: entry 'CartPole-v1': ")
    assert len(_count_fields()) >= 8  # the fields are found: this test cannot pass on an empty list


def test_qcon_t_uses_qcon_rs_shipped_settings_as_the_benchmark_does():
    entry, source = task_settings("CartPole-v1", "QCON-T")
    assert source == "connrl/data/hyperparams/qcon-r.yml [CartPole-v1]"
    assert entry == read_settings(SETTINGS_DIR / "qcon-r.yml")["CartPole-v1"]
    assert task_settings("CartPole-v1", "AHCON-T") == (None, None)  # no file shipped for AHC's learners
