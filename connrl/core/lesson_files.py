"""Taught lessons as versioned JSON files: plain data, so loading never executes code.

A file is ``{"format": "connrl-lesson", "version": 1, "env_id", "env_kwargs", "source", "lessons": [...]}``;
each lesson is ``{"inputs": n+1 rows of d finite numbers, "actions": n integers, "rewards": n finite numbers,
"terminated": bool, "truncated": bool (optional), "taught": bool (optional), "meta": object (optional)}``.
``load_lessons`` checks all of it and refuses anything else with a one-line ``LessonFileError`` naming the
file, the lesson, what is wrong and what is allowed; ``save_lessons`` never writes a file it would refuse.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from connrl.core.lessons import Lesson
from connrl.storage import (
    MAX_JSON_BYTES,
    MAX_NESTING,
    FileError,
    atomic_write_text,
    json_problem,
    max_depth,
    read_limited,
)

LESSON_FORMAT = "connrl-lesson"
LESSON_VERSION = 1
_REQUIRED = ("inputs", "actions", "rewards", "terminated")
_NEEDS = "a lesson needs 'inputs', 'actions', 'rewards' and 'terminated'"


class LessonFileError(ValueError):
    """A lesson file that cannot be used: malformed, wrong version, or made for another task."""


# ------------------------------------------------------------------------------------------------ writing

def lesson_json(lesson: Lesson) -> dict:
    """One lesson as the JSON object a lesson file holds."""
    return {
        "inputs": lesson.inputs.tolist(),
        "actions": lesson.actions.tolist(),
        "rewards": lesson.rewards.tolist(),
        "terminated": bool(lesson.terminated),
        "truncated": bool(lesson.truncated),
        "taught": bool(lesson.taught),
        "meta": lesson.meta,
    }


def _lessons_json(path, lessons: list[Lesson], first: int = 0, input_dim: int | None = None,
                  n_actions: int | None = None) -> list[dict]:
    """The JSON form of ``lessons``, checked as ``load_lessons`` would check it (so nothing unreadable is written)."""
    out = []
    for i, lesson in enumerate(lessons, start=first):
        raw = lesson_json(lesson)
        _check_lesson(raw, f"{path}: lesson {i} (not written)", input_dim, n_actions)
        out.append(raw)
    return out


def save_lessons(path, lessons: list[Lesson], *, env_id: str, env_kwargs: dict | None = None,
                 source: str = "") -> None:
    """Write taught lessons as versioned JSON (plain data: loading never executes code), atomically."""
    doc = {
        "format": LESSON_FORMAT,
        "version": LESSON_VERSION,
        "env_id": env_id,
        "env_kwargs": env_kwargs or {},
        "source": source,
        "lessons": _lessons_json(path, lessons),
    }
    atomic_write_text(path, json.dumps(doc, allow_nan=False))


def append_lessons(path, lessons: list[Lesson], *, env_id: str, env_kwargs: dict | None = None,
                   option_defaults: dict | None = None, input_dim: int | None = None,
                   n_actions: int | None = None) -> int:
    """Append ``lessons`` to an existing lesson file made for the same world; returns the file's lesson count.

    The file is checked like ``check_lesson_file`` first and the new lessons must have its input width; its
    metadata (env_id, env_kwargs, source, any other key) and its lessons are kept exactly as they are.
    """
    doc = check_lesson_file(path, env_id=env_id, env_kwargs=env_kwargs, option_defaults=option_defaults,
                            input_dim=input_dim, n_actions=n_actions)
    width = input_dim if input_dim is not None else len(doc["lessons"][0]["inputs"][0])
    doc["lessons"] = doc["lessons"] + _lessons_json(path, lessons, len(doc["lessons"]), width, n_actions)
    atomic_write_text(path, json.dumps(doc, allow_nan=False))
    return len(doc["lessons"])


# ------------------------------------------------------------------------------------------------ reading

def _kind(value) -> str:
    """A short one-line description of a JSON value for error messages."""
    names = {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "a list",
             dict: "an object", type(None): "null"}
    if value is None:
        return "null"
    if isinstance(value, list | dict):
        unit = "item" if isinstance(value, list) else "key"
        return f"{names[type(value)]} of {len(value)} {unit}{'' if len(value) == 1 else 's'}"
    text = json.dumps(value) if isinstance(value, str | bool | type(None)) else repr(value)
    text = text if len(text) <= 40 else text[:37] + "..."
    return f"{names.get(type(value), type(value).__name__)} ({text})"


def _finite(v) -> bool:
    try:
        return type(v) in (int, float) and math.isfinite(v)
    except OverflowError:  # an integer too large for a float
        return False


def _check_numbers(values, where: str, what: str) -> np.ndarray:
    if not isinstance(values, list):
        raise LessonFileError(f"{where}: '{what}s' is {_kind(values)}; it must be a list of finite numbers")
    for j, v in enumerate(values):
        if not _finite(v):
            raise LessonFileError(f"{where}: {what} {j} is {_kind(v)}; {what}s must be finite numbers")
    return np.array(values, dtype=np.float64)


def _check_inputs(rows, where: str, input_dim: int | None) -> np.ndarray:
    shape = "a list of rows, one per state, each a list of the same number of finite numbers"
    if not isinstance(rows, list) or not rows:
        raise LessonFileError(f"{where}: 'inputs' is {_kind(rows)}; it must be {shape}")
    width = len(rows[0]) if isinstance(rows[0], list) else 0
    for j, row in enumerate(rows):
        if not isinstance(row, list) or not row:
            raise LessonFileError(f"{where}: input row {j} is {_kind(row)}; 'inputs' must be {shape}")
        if len(row) != width:
            raise LessonFileError(f"{where}: input row {j} has {len(row)} numbers, row 0 has {width}; "
                                  f"'inputs' must be {shape}")
        for k, v in enumerate(row):
            if not _finite(v):
                raise LessonFileError(f"{where}: input row {j}, column {k} is {_kind(v)}; "
                                      f"inputs must be finite numbers")
    if input_dim is not None and width != input_dim:
        raise LessonFileError(f"{where} has {width} inputs, the agent expects {input_dim} "
                              f"(every input row must hold {input_dim} numbers)")
    return np.array(rows, dtype=np.float64)


def _check_actions(actions, where: str, n_actions: int | None) -> np.ndarray:
    allowed = f"integers 0..{n_actions - 1}" if n_actions is not None else "non-negative integers"
    if not isinstance(actions, list) or not actions:
        raise LessonFileError(f"{where}: 'actions' is {_kind(actions)}; it must be a non-empty list of {allowed}")
    for j, a in enumerate(actions):
        if type(a) is not int:
            raise LessonFileError(f"{where}: action {j} is {_kind(a)}; actions must be {allowed}")
        if a < 0 or (n_actions is not None and a >= n_actions) or a >= 2 ** 63:
            raise LessonFileError(f"{where}: action {j} is {a}, outside the allowed actions; actions must be {allowed}")
    return np.array(actions, dtype=np.int64)


def _check_flag(raw: dict, key: str, where: str, default: bool | None) -> bool:
    value = raw.get(key, default)
    if not isinstance(value, bool):
        raise LessonFileError(f"{where}: '{key}' is {_kind(value)}; it must be true or false")
    return value


def _check_lesson(raw, where: str, input_dim: int | None, n_actions: int | None) -> Lesson:
    """One lesson of a file, every field checked; ``where`` is ``"<path>: lesson <i>"``."""
    if not isinstance(raw, dict):
        raise LessonFileError(f"{where} is {_kind(raw)}; each lesson must be a JSON object ({_NEEDS})")
    missing = [k for k in _REQUIRED if k not in raw]
    if missing:
        raise LessonFileError(f"{where} is malformed: it has no {', '.join(map(repr, missing))}; {_NEEDS}")
    actions = _check_actions(raw["actions"], where, n_actions)
    rewards = _check_numbers(raw["rewards"], where, "reward")
    inputs = _check_inputs(raw["inputs"], where, input_dim)
    n = len(actions)
    if len(inputs) != n + 1:
        raise LessonFileError(f"{where}: 'inputs' has {len(inputs)} rows for {n} actions; "
                              f"it must have one row per state, {n + 1} (actions + 1)")
    if len(rewards) != n:
        raise LessonFileError(f"{where}: 'rewards' has {len(rewards)} values for {n} actions; "
                              f"it must have one reward per action")
    flags = {key: _check_flag(raw, key, where, default)
             for key, default in (("terminated", None), ("truncated", False), ("taught", True))}
    meta = raw.get("meta", {})
    if not isinstance(meta, dict):
        raise LessonFileError(f"{where}: 'meta' is {_kind(meta)}; it must be a JSON object")
    return Lesson(inputs, actions, rewards, meta=dict(meta), **flags)


def _read_doc(path: Path) -> dict:
    """The file's JSON with its format, version and top-level fields checked."""
    try:
        raw = read_limited(path, MAX_JSON_BYTES, "lesson file")
    except FileError as exc:
        raise LessonFileError(str(exc)) from None
    depth = max_depth(raw)
    if depth > MAX_NESTING:  # the parser recurses: bound the nesting before parsing
        raise LessonFileError(f"{path}: nests {depth} levels deep; a lesson file nests at most {MAX_NESTING}")
    try:
        doc = json.loads(raw.decode("utf-8"))
    except json.JSONDecodeError as exc:
        raise LessonFileError(f"{path}: not a JSON lesson file ({json_problem(exc)})") from None
    except UnicodeDecodeError:
        raise LessonFileError(f"{path}: not a JSON lesson file (not UTF-8 text)") from None
    except (ValueError, RecursionError) as exc:  # e.g. an integer of more digits than Python converts
        raise LessonFileError(f"{path}: not a usable lesson file ({str(exc).splitlines()[0][:200]})") from None
    if not isinstance(doc, dict) or doc.get("format") != LESSON_FORMAT:
        raise LessonFileError(f"{path}: 'format' must be {LESSON_FORMAT!r}")
    if doc.get("version") != LESSON_VERSION or isinstance(doc.get("version"), bool):  # true == 1 in Python
        raise LessonFileError(f"{path}: lesson format version {doc.get('version')!r} is not supported "
                              f"(this connrl reads version {LESSON_VERSION})")
    if not isinstance(doc.get("env_id", ""), str):
        raise LessonFileError(f"{path}: 'env_id' is {_kind(doc['env_id'])}; it must be a registered environment id")
    if not isinstance(doc.get("env_kwargs", {}), dict):
        raise LessonFileError(f"{path}: 'env_kwargs' is {_kind(doc['env_kwargs'])}; it must be a JSON object "
                              f"of world options")
    if "lessons" not in doc:
        raise LessonFileError(f"{path}: the file has no 'lessons'; it must hold a list of lesson objects")
    if not isinstance(doc["lessons"], list):
        raise LessonFileError(f"{path}: 'lessons' is {_kind(doc['lessons'])}; it must be a list of lesson objects")
    if not doc["lessons"]:
        raise LessonFileError(f"{path}: the file holds no lessons")
    return doc


def _load(path: Path, env_id: str | None, input_dim: int | None, n_actions: int | None) -> tuple[dict, list]:
    doc = _read_doc(path)
    if env_id is not None and doc.get("env_id") != env_id:
        raise LessonFileError(f"{path}: lessons were recorded on {doc.get('env_id')!r}, expected {env_id!r}")
    return doc, [_check_lesson(raw, f"{path}: lesson {i}", input_dim, n_actions)
                 for i, raw in enumerate(doc["lessons"])]


def load_lessons(path, *, env_id: str | None = None, input_dim: int | None = None, n_actions: int | None = None,
                 env_kwargs: dict | None = None, option_defaults: dict | None = None) -> list[Lesson]:
    """Read a lesson file written by ``save_lessons``; any mismatch raises LessonFileError saying what. With
    ``env_kwargs`` the file's world options are checked too, as ``check_lesson_file`` checks them."""
    path = Path(path)
    doc, lessons = _load(path, env_id, input_dim, n_actions)
    if env_kwargs is not None:
        _check_options(path, doc, env_kwargs, option_defaults or {})
    return lessons


def _option(options: dict, key: str, defaults: dict) -> tuple[bool, object]:
    """(set?, value as it reads back from JSON) of one world option, falling back on the default."""
    if key in options or key in defaults:
        return True, json.loads(json.dumps(options[key] if key in options else defaults[key], default=repr))
    return False, None


def check_lesson_file(path, *, env_id: str, env_kwargs: dict | None = None, option_defaults: dict | None = None,
                      input_dim: int | None = None, n_actions: int | None = None) -> dict:
    """Check that an existing lesson file holds lessons of this world; returns its JSON document.

    Beyond ``load_lessons``, the file's world options (``env_kwargs``) must equal ``env_kwargs``; an option
    one side leaves out takes its value from ``option_defaults`` (the environment's defaults).
    """
    path = Path(path)
    doc, _ = _load(path, env_id, input_dim, n_actions)
    _check_options(path, doc, env_kwargs or {}, option_defaults or {})
    return doc


def _check_options(path: Path, doc: dict, env_kwargs: dict, defaults: dict) -> None:
    """The file's world options must equal ``env_kwargs``; an option one side leaves out takes its value from
    ``defaults`` (the environment's)."""
    recorded, wanted = doc.get("env_kwargs", {}), env_kwargs
    differ = []
    for key in sorted(set(recorded) | set(wanted)):
        (has, have), (wants, want) = _option(recorded, key, defaults), _option(wanted, key, defaults)
        if (has, have) != (wants, want):
            differ.append(f"{key}={have if has else '(unset)'!r} (expected {want if wants else '(unset)'!r})")
    if differ:
        raise LessonFileError(f"{path}: lessons were recorded with world options {', '.join(differ)}; "
                              f"a lesson file holds lessons of one world, all with the same options")


def load_lessons_and_options(path, *, env_id: str | None = None, input_dim: int | None = None,
                             n_actions: int | None = None) -> tuple[list[Lesson], dict]:
    """``load_lessons`` and the world options (``env_kwargs``) the file records, from one read of it."""
    doc, lessons = _load(Path(path), env_id, input_dim, n_actions)
    return lessons, dict(doc.get("env_kwargs") or {})
