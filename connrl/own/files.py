"""The own-task API's files (connrl.own.api): an agent as ``agent.json`` + ``agent.npz`` (no pickle), and lesson files
of a teacher's episodes on any Gymnasium task (``record_lessons``, read back by ``make_agent(env, "QCON-T",
lessons=...)``).

An agent folder holds the JSON record (format, kind, connrl version, env id, spaces, options, scales, counters,
random state) and one NPZ of arrays: the nets' weights and momentum (``v.``, ``policy.`` prefixes for AHCON's two
nets), the replay memory (``lesson<k>_*``) and the taught lessons (``taught<k>_*``), so a loaded agent learns on
exactly as the saved one would have.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
from gymnasium import spaces

from connrl.core.lesson_files import LessonFileError, load_lessons, save_lessons
from connrl.core.lessons import Lesson
from connrl.own.options import MAX_VALUE_RANGE
from connrl.own.spaces import COMPOSITE, binary_units, check_single, check_space, flatten
from connrl.storage import (
    MAX_NPZ_BYTES,
    FileError,
    atomic_write_files,
    check_array,
    check_number,
    npz_arrays,
    npz_bytes,
    read_json,
    read_limited,
)

FORMAT = 1
_FIELDS = ("inputs", "actions", "rewards")


def version() -> str:
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version
    try:
        return dist_version("connrl")
    except PackageNotFoundError:
        return "unknown"


def _lesson_arrays(prefix: str, lessons) -> dict:
    return {f"{prefix}{k}_{name}": getattr(lesson, name) for k, lesson in enumerate(lessons) for name in _FIELDS}


def write_agent(path: Path, record: dict, state: dict, memory: list[Lesson], taught: list[Lesson]) -> None:
    """``path/agent.npz`` (``state`` plus the lessons) and ``path/agent.json`` (``record`` plus the format, the
    lessons' ends and the NPZ's SHA-256), written as one: a failed save leaves the old pair as it was."""
    arrays = npz_bytes(**state, **_lesson_arrays("lesson", memory), **_lesson_arrays("taught", taught))
    ends = {key: [[bool(x.terminated), bool(x.truncated)] for x in lessons]
            for key, lessons in (("lesson_ends", memory), ("taught_ends", taught))}
    text = json.dumps({"format": FORMAT, "kind": "connrl agent", "connrl": version(), **record, **ends,
                       "npz_sha256": hashlib.sha256(arrays).hexdigest()}, indent=1,
                      allow_nan=False) + "\n"  # strict JSON: any reader can parse it
    atomic_write_files({path / "agent.npz": arrays, path / "agent.json": text.encode()})


def read_agent(path: Path, kinds: tuple[str, ...]) -> tuple[dict, dict[str, np.ndarray]]:
    """(record, arrays) of an agent folder, the record's every field checked (``check_record``); FileError (one
    line naming the file and field) when it is not a connrl agent of this format or is damaged. The arrays are
    checked against the agent they belong to by ``check_arrays``."""
    meta = path / "agent.json"
    m = read_json(meta, "connrl agent file", max_bytes=MAX_RECORD_BYTES, constants=True)  # old files: Infinity
    if not isinstance(m, dict) or m.get("kind") != "connrl agent":
        raise FileError(meta, "is not a connrl agent file (its 'kind' must be \"connrl agent\")")
    if m.get("format") != FORMAT or isinstance(m.get("format"), bool):
        raise FileError(meta, f"agent file format {m.get('format')!r}; this connrl reads format {FORMAT}")
    check_record(meta, m, kinds)
    npz = path / "agent.npz"
    raw = read_limited(npz, MAX_NPZ_BYTES, "connrl agent weight file")  # read once: the bytes checked are those used
    digest = m.get("npz_sha256")  # files written before it was recorded have none
    if digest is not None and hashlib.sha256(raw).hexdigest() != digest:
        raise FileError(npz, "is not the file agent.json was saved with (its SHA-256 differs): it was changed or "
                        "damaged after the save")
    return m, npz_arrays(raw, npz, "connrl agent weight file")


MAX_RECORD_BYTES = 16 * 2**20
MAX_LESSONS = 100_000
MAX_INPUTS, MAX_ACTIONS = 100_000, 10_000  # observation width and actions an agent file may declare
KINDS_OF_SCALER = {"Discrete": "onehot", "Box": "affine"}  # the scaler kind of each space type; others: "flat"


def _field(meta: Path, m: dict, key: str, types: tuple, allowed: str):
    if key not in m:
        raise FileError(meta, f"is missing; it must be {allowed}", key)
    v = m[key]
    if not isinstance(v, types) or (isinstance(v, bool) and bool not in types):
        raise FileError(meta, f"is {type(v).__name__}; it must be {allowed}", key)
    return v


def check_evaluation(meta: Path, v, steps_done: int) -> dict | None:
    """An agent file's optional ``evaluation`` (``EvalCallback``'s record of its latest greedy evaluation: steps,
    mean, std, min, episodes, eval_seed, best), checked; None where the file has none."""
    if v is None:
        return None
    if not isinstance(v, dict) or set(v) != {"steps", "mean", "std", "min", "episodes", "eval_seed", "best"}:
        raise FileError(meta, "must hold steps, mean, std, min, episodes, eval_seed and best", "evaluation")
    check_number(meta, "evaluation.steps", v["steps"], 0, steps_done, integer=True)
    check_number(meta, "evaluation.episodes", v["episodes"], 1, 10**6, integer=True)
    check_number(meta, "evaluation.eval_seed", v["eval_seed"], 0, 2**63 - 1, integer=True)
    for key in ("mean", "min"):
        check_number(meta, f"evaluation.{key}", v[key], -1e15, 1e15)
    check_number(meta, "evaluation.std", v["std"], 0, 1e15)
    if v["min"] > v["mean"] + 1e-9 * max(1.0, abs(v["mean"])):
        raise FileError(meta, f"min {v['min']!r} is above the mean {v['mean']!r}", "evaluation")
    if not isinstance(v["best"], bool):
        raise FileError(meta, "must be true or false", "evaluation.best")
    return dict(v)


def check_record(meta: Path, m: dict, kinds: tuple[str, ...]) -> None:
    """Every field of an agent.json that loading reads: types, finite numbers, sizes inside their bounds, the scaler
    matching the observation space; ``kinds`` are the agents allowed. FileError naming the field otherwise."""
    kind = _field(meta, m, "agent", (str,), f"one of {', '.join(kinds)}")
    if kind not in kinds:
        raise FileError(meta, f"is {kind!r}; it must be one of {', '.join(kinds)}", "agent")
    width = check_space(meta, m.get("observation_space"), "observation_space", MAX_INPUTS)
    a = m.get("action_space")
    if not isinstance(a, dict) or a.get("type") != "Discrete" or a.get("start", 0) != 0:
        raise FileError(meta, "must be a Discrete space that starts at 0", "action_space")
    check_number(meta, "action_space.n", a.get("n"), 1, MAX_ACTIONS, integer=True)
    _field(meta, m, "options", (dict,), "an object of AgentOptions fields")
    sc = _field(meta, m, "scaler", (dict,), "an object with kind, n, offset and scale")
    kind_needed = KINDS_OF_SCALER.get(m["observation_space"]["type"], "flat")
    if sc.get("kind") != kind_needed:
        raise FileError(meta, f"is {sc.get('kind')!r}; it must be {kind_needed!r} for a "
                        f"{m['observation_space']['type']} observation space", "scaler.kind")
    if sc.get("n") != width or isinstance(sc.get("n"), bool):
        raise FileError(meta, f"is {sc.get('n')!r}; it must be {width}, the observation space's width", "scaler.n")
    for key in ("offset", "scale"):
        values = sc.get(key)
        if not isinstance(values, list) or len(values) != width:
            raise FileError(meta, f"must be a list of {width} finite numbers", f"scaler.{key}")
        for v in values:
            check_number(meta, f"scaler.{key}", v)
            if key == "scale" and not abs(v) > 1e-12:
                raise FileError(meta, f"holds {v!r}; a scale must be a non-zero finite number", "scaler.scale")
    check_number(meta, "value_range", m.get("value_range"), 0, MAX_VALUE_RANGE, low_open=True)
    if not isinstance(m.get("range_set", True), bool):  # absent in files before it was saved: set
        raise FileError(meta, "must be true or false (false: no non-zero reward seen yet)", "range_set")
    check_number(meta, "seed", m.get("seed"), 0, 2**63 - 1, integer=True)
    for key in ("steps_done", "trials_done"):
        check_number(meta, key, m.get(key), 0, 2**53, integer=True)
    env_id = m.get("env_id")
    if env_id is not None and (not isinstance(env_id, str) or not 0 < len(env_id) <= 200):
        raise FileError(meta, "must be null or an environment id of at most 200 characters", "env_id")
    _field(meta, m, "rng", (dict,), "a NumPy bit generator state")
    for key in ("lesson_ends", "taught_ends"):
        ends = m.get(key, [])
        if not isinstance(ends, list) or len(ends) > MAX_LESSONS or not all(
                isinstance(e, list) and len(e) == 2 and all(isinstance(b, bool) for b in e) for e in ends):
            raise FileError(meta, f"must be a list of at most {MAX_LESSONS} [terminated, truncated] pairs of "
                            "booleans", key)


def check_arrays(path: Path, arrays: dict[str, np.ndarray], expected: dict[str, np.ndarray], m: dict,
                 n_inputs: int, n_actions: int) -> tuple[dict, list[Lesson], list[Lesson]]:
    """The agent.npz's arrays against the agent built from its record: exactly the nets' arrays (``expected``, a
    state dict) in their shapes and finite, and every lesson with ``n_inputs``-wide finite inputs, one more row than
    actions, actions in 0..n_actions-1 and finite rewards. Returns (net state, replay memory, taught lessons)."""
    npz = path / "agent.npz"
    lesson_keys = {f"{p}{k}_{f}" for p, key in (("lesson", "lesson_ends"), ("taught", "taught_ends"))
                   for k in range(len(m.get(key, []))) for f in _FIELDS}
    unknown = sorted(set(arrays) - set(expected) - lesson_keys)
    if unknown:
        raise FileError(npz, f"holds arrays {', '.join(unknown[:3])} that this agent does not have")
    state = {}
    for key, want in expected.items():
        if key not in arrays:
            raise FileError(npz, f"has no array {key!r}; a {m['agent']} agent needs {', '.join(expected)}")
        state[key] = check_array(npz, key, arrays[key], want.shape)
    found = [_lessons(npz, prefix, arrays, m.get(key, []), prefix == "taught", n_inputs, n_actions)
             for prefix, key in (("lesson", "lesson_ends"), ("taught", "taught_ends"))]
    return state, found[0], found[1]


def _lessons(npz: Path, prefix: str, arrays: dict, ends: list, taught: bool, n_inputs: int,
             n_actions: int) -> list[Lesson]:
    out = []
    for k, (terminated, truncated) in enumerate(ends):
        for name in _FIELDS:
            if f"{prefix}{k}_{name}" not in arrays:
                raise FileError(npz, f"has no array {prefix}{k}_{name}; agent.json lists {len(ends)} {prefix}s")
        actions = check_array(npz, f"{prefix}{k}_actions", arrays[f"{prefix}{k}_actions"], (-1,), low=0,
                              high=n_actions - 1, integer=True)
        n = len(actions)
        inputs = check_array(npz, f"{prefix}{k}_inputs", arrays[f"{prefix}{k}_inputs"], (n + 1, n_inputs))
        rewards = check_array(npz, f"{prefix}{k}_rewards", arrays[f"{prefix}{k}_rewards"], (n,))
        if n < 1:
            raise FileError(npz, "holds no actions; a lesson has at least one", f"{prefix}{k}_actions")
        out.append(Lesson(inputs, actions, rewards, terminated=terminated, truncated=truncated, taught=taught))
    return out


def observation_row(space, obs) -> list[float]:
    """An observation as a lesson file's input row: a Box flattened, a Discrete as its one integer, a composite space
    as ``gymnasium.spaces.flatten`` gives it (one-hots and bits as 0 / 1)."""
    if isinstance(space, spaces.Discrete):
        return [float(int(obs))]
    return (flatten(space, obs) if isinstance(space, COMPOSITE) else np.asarray(obs, float).ravel()).tolist()


def record_lessons(env, teacher, episodes: int, path, seed: int = 0) -> list[Lesson]:
    """Play ``episodes`` episodes with ``teacher(observation) -> action`` and write them as a lesson file (plain
    JSON, connrl.core.lesson_files) whose input rows are the raw observations; returns the lessons.

    ``make_agent(env, "QCON-T", lessons=path)`` replays them after every trial beside its own (3.7), scaled by the
    agent's own input code, so one file serves any agent on that task."""
    check_single(env)
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes must be a whole number >= 1, got {episodes!r}")
    lessons = []
    for k in range(episodes):
        obs, _ = env.reset(seed=seed + k)
        rows, actions, rewards = [observation_row(env.observation_space, obs)], [], []
        terminated = truncated = False
        while not (terminated or truncated):
            a = teacher(obs)
            if isinstance(a, bool) or not isinstance(a, (int, np.integer)) or not env.action_space.contains(int(a)):
                raise ValueError(f"the teacher chose {a!r}; it must return one of the task's actions, a whole number "
                                 f"in {env.action_space}")
            a = int(a)
            obs, r, terminated, truncated, _ = env.step(a)
            rows.append(observation_row(env.observation_space, obs))
            actions.append(a)
            rewards.append(float(r))
        lessons.append(Lesson(np.array(rows), np.array(actions), np.array(rewards), terminated=bool(terminated),
                              truncated=bool(truncated), taught=True))
    spec = getattr(env, "spec", None)
    save_lessons(Path(path), lessons, env_id=spec.id if spec is not None else "",
                 env_kwargs=_plain(spec.kwargs) if spec is not None else {},
                 source=f"connrl.record_lessons: {episodes} episodes, seeds {seed}..{seed + episodes - 1}")
    return lessons


def read_taught(path, env) -> list[Lesson]:
    """A lesson file's lessons for ``env``, each input row as ``observation_row`` wrote it (a Discrete observation as
    its integer); LessonFileError (a ValueError) in one line when the file is not for this task: another env id or
    env options, another input width, an action or a Discrete observation outside the spaces."""
    spec = getattr(env, "spec", None)
    space = env.observation_space
    discrete = isinstance(space, spaces.Discrete)
    width = 1 if discrete else spaces.flatdim(space)
    lessons = load_lessons(path, input_dim=width, n_actions=int(env.action_space.n),
                           **({"env_id": spec.id, "env_kwargs": _plain(spec.kwargs)} if spec is not None else {}))
    for k, lesson in enumerate(lessons):
        rows = lesson.inputs[:, 0] if discrete else None
        if discrete and not np.all((rows == np.round(rows)) & (rows >= space.start) & (rows < space.start + space.n)):
            raise LessonFileError(f"{path}: lesson {k} holds observations outside {space} (whole numbers "
                                  f"{space.start}..{space.start + space.n - 1} are allowed)")
        if isinstance(space, COMPOSITE) and not all(_is_flat_observation(space, row) for row in lesson.inputs):
            raise LessonFileError(f"{path}: lesson {k} holds rows that are not observations of {space} as "
                                  "gymnasium.spaces.flatten writes them (one-hots and bits as 0 / 1)")
    return [Lesson(x.inputs, x.actions, x.rewards, terminated=x.terminated, truncated=x.truncated, taught=True)
            for x in lessons]  # rows as written (a Discrete observation: one column); InputScaler.encode_row codes them


def _is_flat_observation(space, row: np.ndarray) -> bool:
    """Whether ``row`` is a flattened observation: each one-hot has one 1, each bit is 0 or 1 (a Box entry is any
    finite number, as for a plain Box)."""
    bits = binary_units(space)
    try:
        again = flatten(space, spaces.unflatten(space, row))
    except (ValueError, TypeError, IndexError):
        return False
    return bool(np.isin(row[bits], (0.0, 1.0)).all() and np.array_equal(again[bits], row[bits]))


def _plain(kwargs: dict) -> dict:
    """An environment's make() options as JSON reads them back (what a lesson file records and is checked by)."""
    return json.loads(json.dumps(kwargs, default=repr))
