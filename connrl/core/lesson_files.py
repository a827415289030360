"""Taught lessons as versioned JSON files: plain data, so loading never executes code."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from connrl.core.lessons import Lesson
from connrl.storage import atomic_write_text

LESSON_FORMAT = "connrl-lesson"
LESSON_VERSION = 1


class LessonFileError(ValueError):
    """A lesson file that cannot be used: malformed, wrong version, or made for another task."""


def save_lessons(path, lessons: list[Lesson], *, env_id: str, env_kwargs: dict | None = None,
                 source: str = "") -> None:
    """Write taught lessons as versioned JSON (plain data: loading never executes code), atomically."""
    doc = {
        "format": LESSON_FORMAT,
        "version": LESSON_VERSION,
        "env_id": env_id,
        "env_kwargs": env_kwargs or {},
        "source": source,
        "lessons": [
            {
                "inputs": lesson.inputs.tolist(),
                "actions": lesson.actions.tolist(),
                "rewards": lesson.rewards.tolist(),
                "terminated": lesson.terminated,
                "truncated": lesson.truncated,
                "taught": lesson.taught,
                "meta": lesson.meta,
            }
            for lesson in lessons
        ],
    }
    atomic_write_text(path, json.dumps(doc))


def load_lessons(path, *, env_id: str | None = None, input_dim: int | None = None,
                 n_actions: int | None = None) -> list[Lesson]:
    """Read a lesson file written by ``save_lessons``; any mismatch raises LessonFileError saying what."""
    path = Path(path)
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise LessonFileError(f"{path}: no such lesson file") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise LessonFileError(f"{path}: not a JSON lesson file ({exc})") from None
    if not isinstance(doc, dict) or doc.get("format") != LESSON_FORMAT:
        raise LessonFileError(f"{path}: 'format' must be {LESSON_FORMAT!r}")
    if doc.get("version") != LESSON_VERSION:
        raise LessonFileError(f"{path}: lesson format version {doc.get('version')!r} is not supported "
                              f"(this connrl reads version {LESSON_VERSION})")
    if env_id is not None and doc.get("env_id") != env_id:
        raise LessonFileError(f"{path}: lessons were recorded on {doc.get('env_id')!r}, expected {env_id!r}")
    out = []
    for i, raw in enumerate(doc.get("lessons") or []):
        try:
            lesson = Lesson(np.array(raw["inputs"], dtype=np.float64), np.array(raw["actions"]),
                            np.array(raw["rewards"], dtype=np.float64), terminated=bool(raw["terminated"]),
                            truncated=bool(raw.get("truncated", False)), taught=bool(raw.get("taught", True)),
                            meta=dict(raw.get("meta", {})))
        except (KeyError, TypeError, ValueError) as exc:
            raise LessonFileError(f"{path}: lesson {i} is malformed: {exc}") from None
        if input_dim is not None and lesson.inputs.shape[1] != input_dim:
            raise LessonFileError(f"{path}: lesson {i} has {lesson.inputs.shape[1]} inputs, "
                                  f"the agent expects {input_dim}")
        if n_actions is not None and len(lesson) and not (0 <= lesson.actions.min()
                                                          and lesson.actions.max() < n_actions):
            raise LessonFileError(f"{path}: lesson {i} has actions outside 0..{n_actions - 1}")
        out.append(lesson)
    if not out:
        raise LessonFileError(f"{path}: the file holds no lessons")
    return out
