"""The own-task API's files (connrl.api): an agent as ``agent.json`` + ``agent.npz`` (no pickle), and lesson files
of a teacher's episodes on any Gymnasium task (``record_lessons``, read back by ``make_agent(env, "QCON-T",
lessons=...)``).

An agent folder holds the JSON record (format, kind, connrl version, env id, spaces, options, scales, counters,
random state) and one NPZ of arrays: the nets' weights and momentum (``v.``, ``policy.`` prefixes for AHCON's two
nets), the replay memory (``lesson<k>_*``) and the taught lessons (``taught<k>_*``), so a loaded agent learns on
exactly as the saved one would have.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from gymnasium import spaces

from connrl.core.lesson_files import LessonFileError, load_lessons, save_lessons
from connrl.core.lessons import Lesson
from connrl.storage import atomic_save_npz, atomic_write_text

FORMAT = 1
_FIELDS = ("inputs", "actions", "rewards")


def space_json(space) -> dict:
    if isinstance(space, spaces.Discrete):
        return {"type": "Discrete", "n": int(space.n), "start": int(space.start)}
    if isinstance(space, spaces.Box):
        return {"type": "Box", "shape": list(space.shape), "low": _bounds(space.low), "high": _bounds(space.high)}
    return {"type": type(space).__name__}


def _bounds(values) -> list:
    """A Box bound as strict JSON: an infinite bound as the string "inf" / "-inf" (JSON has no Infinity)."""
    return [v if np.isfinite(v) else ("inf" if v > 0 else "-inf") for v in np.asarray(values, float).ravel().tolist()]


def space_from(d: dict):
    if d["type"] == "Discrete":
        return spaces.Discrete(d["n"], start=d.get("start", 0))
    shape = tuple(d["shape"])
    return spaces.Box(np.asarray(d["low"], float).reshape(shape), np.asarray(d["high"], float).reshape(shape),
                      dtype=np.float64)


def version() -> str:
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as dist_version
    try:
        return dist_version("connrl")
    except PackageNotFoundError:
        return "unknown"


def _lesson_arrays(prefix: str, lessons) -> dict:
    return {f"{prefix}{k}_{name}": getattr(lesson, name) for k, lesson in enumerate(lessons) for name in _FIELDS}


def _lessons(prefix: str, arrays: dict, ends: list, taught: bool) -> list[Lesson]:
    return [Lesson(*(arrays[f"{prefix}{k}_{name}"] for name in _FIELDS), terminated=bool(terminated),
                   truncated=bool(truncated), taught=taught) for k, (terminated, truncated) in enumerate(ends)]


def write_agent(path: Path, record: dict, state: dict, memory: list[Lesson], taught: list[Lesson]) -> None:
    """``path/agent.npz`` (``state`` plus the lessons) then ``path/agent.json`` (``record`` plus the format and the
    lessons' ends), each written atomically."""
    atomic_save_npz(path / "agent.npz", **state, **_lesson_arrays("lesson", memory), **_lesson_arrays("taught", taught))
    ends = {key: [[bool(x.terminated), bool(x.truncated)] for x in lessons]
            for key, lessons in (("lesson_ends", memory), ("taught_ends", taught))}
    atomic_write_text(path / "agent.json", json.dumps(
        {"format": FORMAT, "kind": "connrl agent", "connrl": version(), **record, **ends}, indent=1,
        allow_nan=False) + "\n")  # strict JSON: any reader can parse it


def read_agent(path: Path) -> tuple[dict, dict, list[Lesson], list[Lesson]]:
    """(record, net state, replay memory, taught lessons) of an agent folder; ValueError in one line when it is not
    a connrl agent of this format or is damaged."""
    meta = path / "agent.json"
    try:
        m = json.loads(meta.read_text())
    except (OSError, ValueError) as exc:
        raise ValueError(f"{meta}: not a readable connrl agent file ({type(exc).__name__})") from None
    if not isinstance(m, dict) or m.get("kind") != "connrl agent":
        raise ValueError(f"{meta}: not a connrl agent file")
    if m.get("format") != FORMAT:
        raise ValueError(f"{meta}: agent file format {m.get('format')!r}; this connrl reads format {FORMAT}")
    try:
        with np.load(path / "agent.npz", allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        state = {k: v for k, v in arrays.items() if not k.startswith(("lesson", "taught"))}
        return (m, state, _lessons("lesson", arrays, m.get("lesson_ends", []), False),
                _lessons("taught", arrays, m.get("taught_ends", []), True))
    except Exception as exc:  # a truncated or foreign archive, a missing lesson: one clear line
        raise ValueError(f"{path}: not a readable connrl agent ({type(exc).__name__}: {exc})") from None


def observation_row(space, obs) -> list[float]:
    """An observation as a lesson file's input row: a Box flattened, a Discrete as its one integer."""
    if isinstance(space, spaces.Discrete):
        return [float(int(obs))]
    return np.asarray(obs, float).ravel().tolist()


def record_lessons(env, teacher, episodes: int, path, seed: int = 0) -> list[Lesson]:
    """Play ``episodes`` episodes with ``teacher(observation) -> action`` and write them as a lesson file (plain
    JSON, connrl.core.lesson_files) whose input rows are the raw observations; returns the lessons.

    ``make_agent(env, "QCON-T", lessons=path)`` replays them after every trial beside its own (3.7), scaled by the
    agent's own input code, so one file serves any agent on that task."""
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
    width = 1 if discrete else int(np.prod(space.shape))
    lessons = load_lessons(path, input_dim=width, n_actions=int(env.action_space.n),
                           **({"env_id": spec.id, "env_kwargs": _plain(spec.kwargs)} if spec is not None else {}))
    for k, lesson in enumerate(lessons):
        rows = lesson.inputs[:, 0] if discrete else None
        if discrete and not np.all((rows == np.round(rows)) & (rows >= space.start) & (rows < space.start + space.n)):
            raise LessonFileError(f"{path}: lesson {k} holds observations outside {space} (whole numbers "
                                  f"{space.start}..{space.start + space.n - 1} are allowed)")
    return [Lesson(x.inputs[:, 0] if discrete else x.inputs, x.actions, x.rewards, terminated=x.terminated,
                   truncated=x.truncated, taught=True) for x in lessons]


def _plain(kwargs: dict) -> dict:
    """An environment's make() options as JSON reads them back (what a lesson file records and is checked by)."""
    return json.loads(json.dumps(kwargs, default=repr))
