"""Training budgets, episode caps and callbacks of the own-task API (connrl.own.api, connrl.own.callbacks): learn(N)
takes exactly N steps with the cut trial truncated and replayed, an env without a time limit is still learnt from and
evaluated, evaluation leaves learning as it was, a checkpoint resumes, progress.csv holds every trial."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import connrl
from connrl.own.api import MAX_EPISODE_STEPS, episode_cap
from connrl.own.callbacks import CheckpointCallback, EvalCallback, ProgressLog, read_progress


class Endless(gym.Env):
    """A corridor with no time limit and no end: reward 1 for action 1; the observation is the step count mod 4."""

    observation_space = spaces.Discrete(4)
    action_space = spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return 0, {}

    def step(self, a):
        self.t += 1
        return self.t % 4, float(a == 1), False, False, {}


def _weights(agent):
    return {k: v.copy() for k, v in agent.nets.state_dict().items()}


def test_learn_takes_exactly_the_steps_asked_and_the_cut_trial_is_truncated_and_replayed():
    env = gym.make("CartPole-v1")
    agent = connrl.make_agent(env, "QCON-R", seed=3, hidden=4)
    lengths = []
    agent.learn(777, callback=lambda a, r: lengths.append(a.steps_done))
    assert agent.steps_done == 777 == lengths[-1]
    last = agent.learner.book.memory.lessons[-1]
    assert last.truncated and not last.terminated  # the budget's cut is a timeout, not a failure
    assert len(last.actions) == 777 - lengths[-2]
    agent.learn(23)
    assert agent.steps_done == 800


def test_an_env_without_a_time_limit_is_learnt_from_and_evaluated_in_capped_episodes():
    env = Endless()
    assert episode_cap(env) == MAX_EPISODE_STEPS and episode_cap(gym.make("CartPole-v1")) == 500
    assert episode_cap(gym.wrappers.TimeLimit(Endless(), 7)) == 7 and episode_cap(env, 12) == 12
    trials = []
    agent = connrl.make_agent(env, "QCON-R", seed=0, hidden=4, warmup_steps=50)
    agent.learn(2500, callback=lambda a, r: trials.append(a.steps_done))
    assert np.diff([0, *trials]).tolist() == [1000, 1000, 500]  # three trials, each replayed after it ended
    assert connrl.evaluate(agent, env, 2, max_episode_steps=30) == [30.0, 30.0]  # learnt: action 1 every step
    assert connrl.evaluate(agent, env, 1) == [float(MAX_EPISODE_STEPS)]
    with pytest.raises(ValueError, match="max_episode_steps must be a whole number >= 1"):
        connrl.evaluate(agent, env, 1, max_episode_steps=0)


def test_evaluation_during_training_changes_nothing_that_is_learnt(tmp_path):
    runs = []
    for with_eval in (False, True):
        env = gym.make("CartPole-v1")
        agent = connrl.make_agent(env, "QCON-R", seed=1, hidden=4)
        cbs = [EvalCallback(gym.make("CartPole-v1"), every=300, episodes=2, best_path=tmp_path / "best")] \
            if with_eval else []
        agent.learn(1500, callback=cbs)
        runs.append((_weights(agent), agent.steps_done, agent.rng.bit_generator.state))
        if with_eval:
            results = cbs[0].results
    assert runs[0][1:] == runs[1][1:]
    assert all(np.array_equal(runs[0][0][k], runs[1][0][k]) for k in runs[0][0])
    assert [s // 300 for s, *_ in results] == [1, 2, 3, 4, 5]
    best = connrl.load(tmp_path / "best")
    assert best.steps_done == max(results, key=lambda e: e[1])[0]  # the first evaluation of the best mean


def test_stop_at_ends_training_at_the_evaluation_that_reaches_it():
    env = gym.make("CartPole-v1")
    ev = EvalCallback(gym.make("CartPole-v1"), every=200, episodes=1, stop_at=-1e9)  # any return reaches it
    agent = connrl.make_agent(env, "QCON-R", seed=0, hidden=4).learn(5000, callback=ev)
    assert len(ev.results) == 1 and 200 <= agent.steps_done < 5000


def test_a_checkpoint_loads_and_learns_on_as_the_agent_would_have(tmp_path):
    env = gym.make("CartPole-v1")
    agent = connrl.make_agent(env, "QCON-R", seed=2, hidden=4)
    ends = []
    agent.learn(700, callback=[CheckpointCallback(400, tmp_path / "ck"), lambda a, r: ends.append(a.steps_done)])
    resumed = connrl.load(tmp_path / "ck", gym.make("CartPole-v1"))
    assert resumed.steps_done == min(s for s in ends if s >= 400)  # one checkpoint: the first trial end past 400
    twin = connrl.make_agent(gym.make("CartPole-v1"), "QCON-R", seed=2, hidden=4).learn(resumed.steps_done)
    for a in (resumed, twin):  # the checkpoint is the agent as it was at that step: both learn on the same
        a.learn(300)
    assert all(np.array_equal(v, _weights(twin)[k]) for k, v in _weights(resumed).items())


def test_progress_csv_has_a_row_per_trial_and_a_resumed_log_drops_rows_past_the_checkpoint(tmp_path):
    env = gym.make("CartPole-v1")
    ev = EvalCallback(gym.make("CartPole-v1"), every=250, episodes=1)
    log = ProgressLog(tmp_path / "progress.csv", ev)
    agent = connrl.make_agent(env, "QCON-R", seed=0, hidden=4).learn(600, callback=[ev, log])
    rows = read_progress(tmp_path / "progress.csv")
    assert len(rows) == agent.trials_done and sum(r["length"] for r in rows) == 600
    header, columns, *lines = (tmp_path / "monitor.csv").read_text().splitlines()  # SB3's Monitor format
    assert json.loads(header[1:])["env_id"] == "CartPole-v1" == agent.env_id and columns == "r,l,t"
    assert [(float(r), int(n)) for r, n, _ in (line.split(",") for line in lines)] == [
        (row["return"], row["length"]) for row in rows]
    assert [r["steps"] for r in rows if r["eval_mean"] is not None] == [s for s, *_ in ev.results]
    # the temperature the trial was played at, in Q units: t_start 0.05 to t_end 0.005 over 50,000 steps, from the
    # steps before it, times the range
    for r in rows[:3]:
        t = (0.05 - 0.045 * (r["steps"] - r["length"]) / 50_000) * agent.value_range
        assert r["temperature"] == pytest.approx(t, rel=1e-5)
    agent.steps_done = rows[2]["steps"]  # as if the checkpoint were at the third trial
    resumed = ProgressLog(tmp_path / "progress.csv", resume=True)
    resumed.on_training_start(agent, 1000)
    assert resumed.rows == rows[:3]
    (tmp_path / "bad.csv").write_text("steps,oops\n1,2\n")
    with pytest.raises(ValueError, match="is not a connrl progress.csv"):
        read_progress(tmp_path / "bad.csv")


def test_sb3s_load_results_reads_monitor_csv(tmp_path):
    monitor = pytest.importorskip("stable_baselines3.common.monitor")
    log = ProgressLog(tmp_path / "progress.csv")
    connrl.make_agent(gym.make("CartPole-v1"), "QCON-R", seed=1, hidden=4).learn(300, callback=log)
    frame = monitor.load_results(str(tmp_path))
    rows = read_progress(tmp_path / "progress.csv")
    assert frame["r"].tolist() == [r["return"] for r in rows] and frame["l"].tolist() == [r["length"] for r in rows]


def test_keep_n_keeps_the_last_n_checkpoints_numbered(tmp_path):
    ends = []
    agent = connrl.make_agent(gym.make("CartPole-v1"), "QCON-R", seed=2, hidden=4)
    keeper = CheckpointCallback(200, tmp_path / "ck", keep=2)
    agent.learn(1000, callback=[keeper, lambda a, r: ends.append(a.steps_done)])
    due = sorted({min(s for s in ends if s >= k) for k in range(200, 1001, 200) if any(s >= k for s in ends)})
    kept = sorted((tmp_path / "ck" / "checkpoints").iterdir())
    assert [p.name for p in kept] == [f"step-{s:011d}" for s in due[-2:]]
    assert [connrl.load(p).steps_done for p in kept] == due[-2:]
    assert connrl.load(tmp_path / "ck").steps_done == due[-1]


@pytest.mark.parametrize("make, message", [
    (lambda: EvalCallback(gym.make("CartPole-v1"), every=0), "every must be a whole number of steps >= 1"),
    (lambda: EvalCallback(gym.make("CartPole-v1"), episodes=0), "episodes must be a whole number >= 1"),
    (lambda: EvalCallback(gym.make("CartPole-v1"), stop_at=float("nan")), "stop_at must be a finite number"),
    (lambda: CheckpointCallback(2.5, "x"), "every must be a whole number of steps >= 1"),
    (lambda: CheckpointCallback(10, "x", keep=True), "keep must be a whole number of checkpoints >= 0"),
])
def test_bad_callback_settings_are_one_line(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_a_callback_of_another_kind_is_refused_before_training():
    agent = connrl.make_agent(gym.make("CartPole-v1"), "QCON-R", seed=0, hidden=4)
    with pytest.raises(ValueError, match="callback must be a connrl Callback"):
        agent.learn(100, callback=42)
    assert agent.steps_done == 0


def _tensorboard_scalars(logdir) -> dict[str, list[tuple[int, float]]]:
    """The scalars of the event files in ``logdir``, read by hand (TFRecord framing: length, its CRC, the Event
    proto, its CRC), not by the writer."""
    import struct

    from tensorboardX.proto.event_pb2 import Event

    out: dict[str, list[tuple[int, float]]] = {}
    for f in sorted(logdir.glob("events.out.tfevents.*")):
        data, i = f.read_bytes(), 0
        while i < len(data):
            (n,) = struct.unpack("<Q", data[i:i + 8])
            event = Event.FromString(data[i + 12:i + 12 + n])
            i += 12 + n + 4
            for v in event.summary.value:
                out.setdefault(v.tag, []).append((event.step, v.simple_value))
    return out


def test_tensorboard_logs_the_trials_and_evaluations_of_progress_csv(tmp_path):
    pytest.importorskip("tensorboardX")
    from connrl import cli

    assert cli.main(["train", "CartPole-v1", "--steps", "600", "--eval-every", "300", "--eval-episodes", "1",
                     "--quiet", "--save", str(tmp_path / "a"), "--tensorboard", str(tmp_path / "tb")]) == 0
    rows = read_progress(tmp_path / "a" / "progress.csv")
    tb = _tensorboard_scalars(tmp_path / "tb")
    assert tb["rollout/ep_rew"] == [(r["steps"], pytest.approx(r["return"])) for r in rows]
    assert tb["eval/mean_reward"] == [(r["steps"], pytest.approx(r["eval_mean"], rel=1e-5)) for r in rows
                                      if r["eval_mean"] is not None]


class _InterruptAt(gym.Wrapper):
    """Ctrl-C at the ``at``-th step of the wrapped env."""

    def __init__(self, env, at: int):
        super().__init__(env)
        self.at, self.n = at, 0

    def step(self, action):
        self.n += 1
        if self.n == self.at:
            raise KeyboardInterrupt
        return self.env.step(action)


def test_ctrl_c_inside_a_trial_counts_its_steps_and_the_next_learn_starts_a_trial_of_its_own():
    env = _InterruptAt(gym.make("CartPole-v1"), at=300)
    agent = connrl.make_agent(env, "QCON-R", seed=0, hidden=4, warmup_steps=20)
    env.n = 0  # the warm-up's steps do not count
    ends = []
    with pytest.raises(KeyboardInterrupt):
        agent.learn(5000, callback=lambda a, r: ends.append(a.steps_done))
    assert agent.steps_done == 299  # the 300th step never happened
    lessons = agent.learner.book.memory.lessons
    n_before = len(lessons)
    assert lessons[-1].actions.size == ends[-1] - (ends[-2] if len(ends) > 1 else 0)  # the last whole trial
    agent.learn(100)
    assert agent.steps_done == 399
    assert sum(x.actions.size for x in agent.learner.book.memory.lessons[n_before:]) == 100  # nothing stitched on


def test_a_multi_file_write_holds_ctrl_c_until_both_files_are_in_place(tmp_path, monkeypatch):
    import os
    import signal
    import threading

    from connrl import storage

    storage.atomic_write_files({tmp_path / "a": b"old", tmp_path / "b": b"old"})
    real, moves = os.replace, []

    def replace_and_signal(src, dst):
        if not moves:
            signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)  # between the two moves
        moves.append(dst)
        real(src, dst)

    monkeypatch.setattr(storage.os, "replace", replace_and_signal)
    # as in a foreground process: another test in this pytest worker, or a library it loaded, may have left SIGINT
    # handled otherwise or blocked (tests/test_cli_faults.py's _terminal_sigint)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    mask = signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    try:
        with pytest.raises(KeyboardInterrupt):
            storage.atomic_write_files({tmp_path / "a": b"new", tmp_path / "b": b"new"})
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        signal.signal(signal.SIGINT, before)
    assert len(moves) == 2 and (tmp_path / "a").read_bytes() == (tmp_path / "b").read_bytes() == b"new"
