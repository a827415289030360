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
from connrl.storage import atomic_save_npz, atomic_write_text

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
    """Read a behaviour written by ``save_behaviour``; ``task`` (if given) must match. ValueError on any mismatch."""
    path = Path(path)
    npz, meta = path.with_suffix(".npz"), path.with_suffix(".json")
    try:
        m = json.loads(meta.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{meta}: not a readable behaviour file ({exc})") from None
    if not isinstance(m, dict) or m.get("kind") != "connrl behaviour" or m.get("format") != FORMAT:
        raise ValueError(f"{meta}: not a connrl behaviour file of format {FORMAT}")
    if m.get("task") not in BEHAVIOUR_TASKS or (task is not None and m["task"] != task):
        wanted = task or f"one of {', '.join(BEHAVIOUR_TASKS)}"
        raise ValueError(f"{meta}: holds behaviour {m.get('task')!r}, expected {wanted}")
    n_in, n_hid, n_act = m.get("n_inputs"), m.get("n_hidden"), m.get("n_actions")
    if (n_in, n_act) != (OBS_SIZE[m["task"]], 6) or not isinstance(n_hid, int) or n_hid < 1:
        raise ValueError(f"{meta}: task {m['task']} needs {OBS_SIZE[m['task']]} inputs, 6 actions and >= 1 hidden "
                         f"unit, the file says {n_in} inputs, {n_act} actions, {n_hid} hidden")
    vr, low, prov = m.get("value_range"), m.get("binary_low", -0.5), m.get("provenance", {})
    if not (isinstance(vr, (int, float)) and not isinstance(vr, bool) and 0 < vr < math.inf) or low not in (-0.5, 0.0) \
            or not isinstance(prov, dict):
        raise ValueError(f"{meta}: value_range must be a number > 0, binary_low -0.5 or 0 and provenance an object; "
                         f"got {vr!r}, {low!r}, {type(prov).__name__}")
    try:
        z = np.load(npz, allow_pickle=False)
        if not isinstance(z, np.lib.npyio.NpzFile):
            raise ValueError("an .npy array, not an .npz archive")
        with z:
            w1, w2 = np.asarray(z["w1"], dtype=np.float64), np.asarray(z["w2"], dtype=np.float64)
    except Exception as exc:  # any unreadable archive (missing, truncated, pickled, wrong keys) is one clear line
        raise ValueError(f"{npz}: not a readable weight file ({type(exc).__name__}: {exc})") from None
    if w1.shape != (n_act, n_hid, n_in + 1) or w2.shape != (n_act, n_hid + 1) or not (
            np.isfinite(w1).all() and np.isfinite(w2).all()):
        raise ValueError(f"{npz}: weights of shape {w1.shape} / {w2.shape} do not match the {n_in}-{n_hid}-1 nets of "
                         f"{meta.name}, or are not finite")
    q = OAON(NetConfig(n_in, n_hid, value_range=float(vr)), n_act, np.random.default_rng(0))
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
            h.update(f.read_bytes() if f.exists() else b"missing")
    return h.hexdigest()[:12]


def load_library(directory=LIBRARY_DIR) -> dict[str, Behaviour]:
    """The four behaviours of a library folder (the shipped one by default)."""
    return {t: load_behaviour(p, t) for t, p in library_paths(directory).items()}
