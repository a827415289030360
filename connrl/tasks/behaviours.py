"""The behaviour library of Ch. 6: DK, DP, WFL and WFR as trained QCON-T skills (Ch. 5's machinery), stored as plain
files, with the applicability test of 6.4.3.

A behaviour is its six OAON Q-nets plus what it needs to act: the task (which of Ch. 5's observations it reads), the
binary encoding and the provenance of its training. On disk it is ``NAME.npz`` (the weight arrays, read with
``allow_pickle=False``) beside ``NAME.json`` (format version, task, shapes, value range, provenance). Loading checks
the task and every shape and refuses a mismatch with one line.

Applicability (6.4.3): DP applies where the largest of its Q-values exceeds 30, DK where it exceeds 25, wall
following everywhere (``APPLICABLE_ABOVE``).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from connrl.envs.robot import OBS_SIZE, Layout, RobotSim
from connrl.envs.robot.recharge import BEHAVIOUR_TASKS, task_observations
from connrl.nets import OAON, NetConfig
from connrl.storage import (
    MAX_NPZ_BYTES,
    FileError,
    atomic_save_npz,
    atomic_write_text,
    check_array,
    check_number,
    read_json,
    read_limited,
    read_npz,
)

FORMAT = 1
APPLICABLE_ABOVE = {"DP": 30.0, "DK": 25.0, "WFL": -math.inf, "WFR": -math.inf}  # 6.4.3
LIBRARY_DIR = Path(__file__).resolve().parent.parent / "data" / "behaviours"


@dataclass
class Behaviour:
    """One learned skill: ``q_values(obs)`` on its own task's observation, ``act`` greedy (the test policy of 5.4)."""

    task: str
    q: OAON
    binary_low: float = -0.5
    meta: dict = field(default_factory=dict)

    def q_values(self, obs: np.ndarray) -> np.ndarray:
        return self.q.values(np.asarray(obs, dtype=np.float64))

    def act(self, obs: np.ndarray, info=None, *, greedy: bool = True) -> int:
        return int(np.argmax(self.q_values(obs)))

    # the agent protocol, so ``run_trial`` and ``evaluate`` can drive a stored behaviour (greedy, never learning)
    def begin_trial(self, obs, info=None, *, trial: int = 0, learning: bool = False) -> None:
        if learning:
            raise ValueError("a stored behaviour does not learn; train it with connrl.experiments.behaviours")

    def end_trial(self) -> None:
        pass

    def applicable(self, obs: np.ndarray) -> bool:
        """6.4.3: the largest Q-value above the task's threshold (always, for wall following)."""
        threshold = APPLICABLE_ABOVE[self.task]
        return threshold == -math.inf or bool(self.q_values(obs).max() > threshold)


def save_behaviour(b: Behaviour, path) -> tuple[Path, Path]:
    """Write ``path``.npz (weights) and ``path``.json (the rest), each atomically."""
    path = Path(path)
    c = b.q.config
    npz, meta = path.with_suffix(".npz"), path.with_suffix(".json")
    atomic_save_npz(npz, w1=b.q.w1, w2=b.q.w2)
    atomic_write_text(meta, json.dumps({
        "format": FORMAT, "kind": "connrl behaviour", "task": b.task, "n_inputs": c.n_inputs, "n_hidden": c.n_hidden,
        "n_actions": b.q.n_nets, "value_range": c.value_range, "binary_low": b.binary_low, "provenance": b.meta},
        indent=1) + "\n")
    return npz, meta


def load_behaviour(path, task: str | None = None) -> Behaviour:
    """Read a behaviour written by ``save_behaviour``; ``task`` (if given) must match. FileError (a ValueError, one
    line naming the file and field) on anything else: every field and weight is checked before the nets see it."""
    path = Path(path)
    npz, meta = path.with_suffix(".npz"), path.with_suffix(".json")
    m = read_json(meta, "behaviour file", max_bytes=2**20)
    if not isinstance(m, dict) or m.get("kind") != "connrl behaviour" or m.get("format") != FORMAT:
        raise FileError(meta, f"is not a connrl behaviour file of format {FORMAT}")
    if m.get("task") not in BEHAVIOUR_TASKS or (task is not None and m["task"] != task):
        wanted = task or f"one of {', '.join(BEHAVIOUR_TASKS)}"
        raise FileError(meta, f"is {m.get('task')!r}; this file must hold behaviour {wanted}", "task")
    n_in = OBS_SIZE[m["task"]]
    check_number(meta, "n_inputs", m.get("n_inputs"), n_in, n_in, integer=True)
    check_number(meta, "n_actions", m.get("n_actions"), 6, 6, integer=True)
    n_hid = check_number(meta, "n_hidden", m.get("n_hidden"), 1, 1024, integer=True)
    vr = check_number(meta, "value_range", m.get("value_range"), 0, 1e6, low_open=True)
    low, prov = m.get("binary_low", -0.5), m.get("provenance", {})
    if low not in (-0.5, 0.0) or isinstance(low, bool):
        raise FileError(meta, f"is {low!r}; it must be -0.5 or 0", "binary_low")
    if not isinstance(prov, dict):
        raise FileError(meta, f"is {type(prov).__name__}; it must be an object", "provenance")
    z = read_npz(npz, "behaviour weight file")
    for key in ("w1", "w2"):
        if key not in z:
            raise FileError(npz, f"has no array {key!r}; a behaviour's weights are w1 and w2")
    w1 = check_array(npz, "w1", z["w1"], (6, n_hid, n_in + 1))
    w2 = check_array(npz, "w2", z["w2"], (6, n_hid + 1))
    q = OAON(NetConfig(n_in, n_hid, value_range=float(vr)), 6, np.random.default_rng(0))
    q.w1, q.w2 = w1, w2
    return Behaviour(m["task"], q, float(low), dict(prov))


def q_value_map(b: Behaviour, layout: Layout, spacing: float = 12.0,
                headings: tuple[float, ...] = (0.0, 90.0, 180.0, 270.0)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Figs. 6.3 / 6.4: at each grid point where the robot fits, the largest Q-value over actions and the given
    headings (noise-free scans, so the map is deterministic); NaN where the robot does not fit. Returns (xs, ys, grid)
    with ``grid[i, j]`` at ``(xs[j], ys[i])``."""
    w, h = layout.size
    xs, ys = np.arange(spacing / 2, w, spacing), np.arange(spacing / 2, h, spacing)
    grid = np.full((ys.size, xs.size), np.nan)
    sim = RobotSim(layout, np.random.default_rng(0), sensor_noise=False, control_noise=False)
    for i, y in enumerate(ys):
        for j, x in enumerate(xs):
            if not layout.is_free(float(x), float(y)):
                continue
            best = -np.inf
            for heading in headings:
                sim.place(float(x), float(y), heading)
                best = max(best, float(b.q_values(task_observations(sim.sense(), b.binary_low)[b.task]).max()))
            grid[i, j] = best
    return xs, ys, grid


def library_paths(directory=LIBRARY_DIR) -> dict[str, Path]:
    return {t: Path(directory) / t.lower() for t in BEHAVIOUR_TASKS}


def library_digest(directory=LIBRARY_DIR) -> str:
    """A short SHA-256 of the four behaviours' files: runs record it, so a retrained library gives new runs."""
    h = hashlib.sha256()
    for path in library_paths(directory).values():
        for f in (path.with_suffix(".json"), path.with_suffix(".npz")):
            h.update(f.name.encode())
            h.update(read_limited(f, MAX_NPZ_BYTES, "behaviour file") if f.exists() else b"missing")
    return h.hexdigest()[:12]


def load_library(directory=LIBRARY_DIR) -> dict[str, Behaviour]:
    """The four behaviours of a library folder (the shipped one by default)."""
    return {t: load_behaviour(p, t) for t, p in library_paths(directory).items()}
