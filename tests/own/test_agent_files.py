"""A saved agent is a file people share: loading checks every field and array before any net or kernel sees it,
never imports code, and `connrl train` loses nothing when it is stopped, diverges or cannot write."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import connrl
from connrl import cli
from connrl.core.lessons import Lesson
from connrl.core.replay import ReplayParams, replay_q
from connrl.nets import OAON, NetConfig
from connrl.own.callbacks import read_progress


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    path = tmp_path_factory.mktemp("agent") / "good"
    connrl.make_agent(gym.make("CartPole-v1"), "QCON-R", seed=0, warmup_steps=200).learn(600).save(path)
    return path


def _copy(saved, tmp_path, arrays=None, record=None, keep_digest=False):
    path = tmp_path / "agent"
    shutil.copytree(saved, path)
    if arrays is not None:
        z = dict(np.load(path / "agent.npz"))
        arrays(z)
        np.savez(path / "agent.npz", **z)
    m = json.loads((path / "agent.json").read_text())
    if record is not None:
        record(m)
    if not keep_digest:  # an adversary edits both files: the checks, not the digest, must refuse the arrays
        m.pop("npz_sha256")
    (path / "agent.json").write_text(json.dumps(m))
    return path


def _set(key, f):
    return lambda z: z.__setitem__(key, f(z[key]))


@pytest.mark.parametrize("arrays, message", [
    (_set("lesson0_actions", lambda a: a + 7), "lesson0_actions: holds values in [7, 8]; they must lie in [0, 1]"),
    (_set("lesson0_actions", lambda a: a + 10**6), "lesson0_actions: holds values in [1e+06, 1e+06]"),
    (_set("lesson2_actions", lambda a: a - 5), "lesson2_actions: holds values in [-5, -4]"),
    (_set("lesson1_actions", lambda a: a.astype(float)), "lesson1_actions: holds float64 data"),
    (_set("lesson0_inputs", lambda a: a[:, :3]), "lesson0_inputs: has shape"),
    (_set("lesson0_inputs", lambda a: a[1:]), "lesson0_inputs: has shape"),
    (_set("lesson0_rewards", lambda a: a * np.nan), "lesson0_rewards: holds NaN or infinite values"),
    (_set("w1", lambda a: a * np.inf), "w1: holds NaN or infinite values"),
    (_set("w2", lambda a: a[:, :3]), "w2: has shape"),
    (lambda z: z.pop("d1"), "has no array 'd1'"),
    (lambda z: z.pop("lesson1_rewards"), "has no array lesson1_rewards"),
    (lambda z: z.__setitem__("extra", np.zeros(3)), "holds arrays extra that this agent does not have"),
])
def test_damaged_arrays_are_refused_before_any_net_sees_them(saved, tmp_path, arrays, message):
    path = _copy(saved, tmp_path, arrays=arrays)
    with pytest.raises(ValueError) as e:
        connrl.load(path, gym.make("CartPole-v1"))
    assert str(e.value).startswith(f"{path / 'agent.npz'}: ") and message in str(e.value)


@pytest.mark.parametrize("record, message", [
    (lambda m: m["scaler"]["scale"].__setitem__(0, 0), "scaler.scale: holds 0; a scale must be a non-zero"),
    (lambda m: m["scaler"]["offset"].__setitem__(0, None), "scaler.offset: is None; it must be a finite number"),
    (lambda m: m["scaler"].__setitem__("n", 9), "scaler.n: is 9; it must be 4"),
    (lambda m: m.__setitem__("value_range", 0), "value_range: is 0; it must be a finite number > 0"),
    (lambda m: m["options"].__setitem__("hidden", 10**8), "options: option hidden must be a whole number from 0"),
    (lambda m: m["options"].__setitem__("evil", 1), "options: unknown option(s) 'evil'"),
    (lambda m: m.__setitem__("agent", "DQN"), "agent: is 'DQN'; it must be one of QCON"),
    (lambda m: m["action_space"].__setitem__("n", 10**9), "action_space.n: is 1000000000"),
    (lambda m: m["observation_space"].__setitem__("shape", [2, 3]), "observation_space.low: must be a list of 6"),
    (lambda m: m["observation_space"].__setitem__("shape", [4, 0]), "observation_space.shape: is 0"),
    (lambda m: m["observation_space"].__setitem__("type", "Graph"), "observation_space: must be an object with"),
    (lambda m: m["scaler"].__setitem__("kind", "flat"), "scaler.kind: is 'flat'; it must be 'affine' for a Box"),
    (lambda m: m.__setitem__("rng", {"bit_generator": "PCG64", "state": "x"}), "rng: is not a NumPy PCG64 state"),
    (lambda m: m.__setitem__("steps_done", -1), "steps_done: is -1"),
    (lambda m: m.__setitem__("lesson_ends", m["lesson_ends"] + [[True, False]]), "has no array lesson"),
    (lambda m: m.__setitem__("lesson_ends", [[1, 0]]), "lesson_ends: must be a list of at most"),
    (lambda m: m.__setitem__("env_id", ["x"]), "env_id: must be null or an environment id"),
])
def test_damaged_records_are_refused_naming_the_field(saved, tmp_path, record, message):
    path = _copy(saved, tmp_path, record=record)
    with pytest.raises(ValueError) as e:
        connrl.load(path)
    assert str(e.value).startswith(f"{path}/agent.") and message in str(e.value) and "\n" not in str(e.value)


def test_an_npz_changed_after_the_save_is_told_by_its_digest(saved, tmp_path):
    path = _copy(saved, tmp_path, arrays=_set("w1", lambda a: a + 1e-3), keep_digest=True)
    with pytest.raises(ValueError, match="is not the file agent.json was saved with"):
        connrl.load(path)
    assert connrl.load(_copy(saved, tmp_path / "b", keep_digest=True)).steps_done >= 600


def test_a_tampered_agent_cannot_crash_the_interpreter_when_it_learns(saved, tmp_path):
    """The reported exploit (actions + 7 in the replay memory; a segfault in learn()) in a child process: it must
    end with a normal exit and the one-line error, not a signal."""
    path = _copy(saved, tmp_path, arrays=_set("lesson0_actions", lambda a: a + 7))
    code = (f"import gymnasium as gym, connrl\ntry:\n    connrl.load({str(path)!r}, gym.make('CartPole-v1'))"
            ".learn(500)\nexcept ValueError as e:\n    raise SystemExit(f'connrl: {e}')")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and r.stderr.startswith(f"connrl: {path / 'agent.npz'}: lesson0_actions")


def test_the_kernels_refuse_an_action_or_width_they_would_index_out_of_bounds():
    q = OAON(NetConfig(3, 4), 2, np.random.default_rng(0))
    bad = Lesson(np.zeros((3, 3)), np.array([0, 7]), np.zeros(2), terminated=True)
    with pytest.raises(ValueError, match=r"actions in \[0, 7\] and 3 inputs does not fit nets of actions 0..1"):
        replay_q(q, bad, ReplayParams(gamma=0.9, lam=0.5, temperature=0.1))
    with pytest.raises(ValueError, match="not fit"):
        replay_q(q, Lesson(np.zeros((2, 5)), np.array([1]), np.zeros(1), terminated=True),
                 ReplayParams(gamma=0.9, lam=0.5, temperature=0.1))
    for call in (lambda: q.update(np.zeros(3), 2, 1.0), lambda: q.update(np.zeros(3), -1, 1.0),
                 lambda: q.value(np.zeros(3), 5), lambda: q.values(np.zeros(4))):
        with pytest.raises(ValueError, match="the nets are 0..1 on 3 inputs"):
            call()


def test_an_environment_id_in_a_file_never_imports_code(saved, tmp_path, monkeypatch, capsys):
    (tmp_path / "evilmod.py").write_text(f"open({str(tmp_path / 'PWNED')!r}, 'w').write('ran')\n")
    monkeypatch.syspath_prepend(str(tmp_path))  # as `python -m connrl.cli` run in that folder would have it
    path = _copy(saved, tmp_path, record=lambda m: m.__setitem__("env_id", "evilmod:Evil-v0"))
    with pytest.raises(SystemExit) as e:
        cli.main(["evaluate", str(path), "--episodes", "1"])
    assert str(e.value.code).startswith(f"connrl: {path / 'agent.json'}: env_id: is 'evilmod:Evil-v0', not a "
                                        "registered Gymnasium environment")
    assert not (tmp_path / "PWNED").exists() and "evilmod" not in sys.modules
    unknown = _copy(saved, tmp_path / "u", record=lambda m: m.__setitem__("env_id", "NoSuchEnv-v9"))
    with pytest.raises(SystemExit, match="'NoSuchEnv-v9', not a registered"):
        cli.main(["evaluate", str(unknown)])
    assert cli.main(["evaluate", str(path), "--env", "CartPole-v1", "--episodes", "1"]) == 0  # the user's choice


def test_train_never_saves_a_diverged_agent_and_says_so(tmp_path, capsys):
    out = tmp_path / "div"
    code = cli.main(["train", "CartPole-v1", "--steps", "2000", "--quiet", "--save", str(out),
                     "--option", "lr=100", "--option", "value_range=0.000001"])  # a huge step on a tiny scale
    err = capsys.readouterr().err.strip()
    assert code == 1 and err.startswith("connrl: training diverged by step ") and "it was not saved" in err
    assert "\n" not in err and not (out / "agent.json").exists()
    assert read_progress(out / "progress.csv")[-1]["steps"] <= 2000  # the log of what diverged is kept
    agent = connrl.make_agent(gym.make("CartPole-v1"), lr=100, value_range=1e-6, warmup_steps=100).learn(300)
    with pytest.raises(ValueError, match="the agent diverged after"):
        agent.save(tmp_path / "api")


def test_train_checkpoints_as_it_goes(tmp_path, monkeypatch, capsys):
    saves = []
    real = connrl.own.api.Agent.save
    monkeypatch.setattr(connrl.own.api.Agent, "save", lambda self, p: saves.append(self.steps_done) or real(self, p))
    out = tmp_path / "ck"
    assert cli.main(["train", "CartPole-v1", "--steps", "1500", "--quiet", "--save", str(out),
                     "--checkpoint-every", "500", "--eval-every", "0", "--option", "warmup_steps=100"]) == 0
    assert len(saves) >= 3 and all(b - a >= 500 for a, b in zip(saves[:-2], saves[1:-1], strict=True))
    assert saves[-1] >= 1500 and connrl.load(out).steps_done == saves[-1]


def test_a_failed_save_says_what_was_lost_and_leaves_no_temporary_file(tmp_path, monkeypatch, capsys):
    import connrl.storage as storage

    def disk_full(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(storage.os, "fsync", disk_full)
    out = tmp_path / "full"
    code = cli.main(["train", "CartPole-v1", "--steps", "600", "--quiet", "--save", str(out),
                     "--option", "warmup_steps=100"])
    err = capsys.readouterr().err.strip()
    assert code == 1 and err.startswith("connrl: the agent trained for ") and "was NOT saved: cannot write" in err
    assert "No space left on device" in err and not out.exists()  # nothing could be written: not even the log


def test_train_keeps_the_best_by_default_where_success_is_defined_and_evaluate_says_which(tmp_path, capsys):
    from connrl.own.cli import auto_eval_every

    cup = gym.make("connrl/CupCollection-v0")  # no reward threshold
    assert auto_eval_every(gym.make("CartPole-v1"), None, 2500) == 1000 == auto_eval_every(cup, 3.0, 2500)
    assert auto_eval_every(cup, None, 50_000) == 0 and auto_eval_every(gym.make("CartPole-v1"), None, 60_000) == 3000
    out = tmp_path / "cp"
    assert cli.main(["train", "CartPole-v1", "--steps", "2500", "--quiet", "--save", str(out),
                     "--option", "hidden=4", "--option", "warmup_steps=100"]) == 0  # no --eval-every: every 1000
    rows = read_progress(out / "progress.csv")
    evals = [r for r in rows if r["eval_mean"] is not None]
    assert len(evals) == 2 and 1000 <= evals[0]["steps"] < 2000 <= evals[1]["steps"]
    best = max(evals, key=lambda r: r["eval_mean"])
    kept = connrl.load(out / "best")
    assert kept.steps_done == best["steps"] and kept.evaluation["mean"] == pytest.approx(best["eval_mean"])
    assert kept.evaluation["best"] is True and kept.evaluation["episodes"] == 5
    assert repr(kept) == (f"<connrl Agent QCON-R on CartPole-v1, trained {best['steps']} steps; evaluated at step "
                          f"{best['steps']}: mean return {kept.evaluation['mean']:.2f} over 5 episodes (best)>")
    capsys.readouterr()
    assert cli.main(["evaluate", str(out / "best"), "--episodes", "1"]) == 0
    said = capsys.readouterr().out
    assert f"trained {best['steps']} steps; evaluated at step {best['steps']}: mean return" in said
    assert "(the run's best so far then)" in said
    assert cli.main(["evaluate", str(out), "--episodes", "1"]) == 0
    assert f"{out / 'best'} holds the run's best agent" in capsys.readouterr().out
    meta = json.loads((out / "best" / "agent.json").read_text())
    meta["evaluation"]["episodes"] = 0
    (out / "best" / "agent.json").write_text(json.dumps(meta))
    with pytest.raises(ValueError, match=r"evaluation.episodes.*is 0; it must be a whole number >= 1"):
        connrl.load(out / "best")


def test_a_best_agent_that_cannot_be_kept_stops_training_and_says_so_in_one_line(tmp_path, monkeypatch, capsys):
    real = connrl.own.api.Agent.save

    def save(self, path):
        if Path(path).name == "best":
            raise OSError(28, "No space left on device")
        return real(self, path)

    monkeypatch.setattr(connrl.own.api.Agent, "save", save)
    out = tmp_path / "cp"
    code = cli.main(["train", "CartPole-v1", "--steps", "2500", "--quiet", "--save", str(out), "--option", "hidden=4",
                     "--option", "warmup_steps=100"])
    err = capsys.readouterr().err.strip()
    assert code == 1 and "\n" not in err and "the best agent could not be kept in" in err and "No space left" in err
    assert 1000 <= connrl.load(out).steps_done < 2000  # stopped at the first evaluation, the trained agent saved
