"""``connrl teach``: play a task from the keyboard and save the trial as a taught lesson (3.7).

The terminal UI shows the environment's ANSI (or a text summary of its) rendering and reads one key per
line (type the key and Enter): it works in any terminal, over ssh and under tmux. ``x`` ends the trial
early (kept as a lesson cut by a time limit), ``u`` quits without saving. The lesson is saved with
``connrl.core.lesson_files.save_lessons`` (versioned JSON), appending to the file if it already exists.

Each target names a registered environment, its constructor arguments and the key map of its actions.
Chapters add targets to ``TEACH_TARGETS``.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from connrl.core.lesson_files import LessonFileError, load_lessons, save_lessons
from connrl.core.lessons import Lesson


@dataclass(frozen=True)
class TeachTarget:
    env_id: str  # registered Gymnasium id
    keymap: dict[str, int]  # key -> action index
    env_kwargs: dict = field(default_factory=dict)
    describe: str = ""  # one line shown before play


def _targets() -> dict[str, TeachTarget]:
    from connrl.envs.robot import KEYMAP as ROBOT_KEYS
    from connrl.envs.survival import KEYMAP as SURVIVAL_KEYS

    out = {
        "survival": TeachTarget("connrl/Survival-v0", dict(SURVIVAL_KEYS), {"action_representation": "global"},
                                "w/d/s/a move north/east/south/west"),
        "survival-local": TeachTarget("connrl/Survival-v0", dict(SURVIVAL_KEYS), {"action_representation": "local"},
                                      "w/d/s/a move front/right/back/left"),
    }
    for task in ("dk", "dp", "wfl", "wfr"):
        out[f"robot-{task}"] = TeachTarget(f"connrl/Robot-{task.upper()}-v0", dict(ROBOT_KEYS), {},
                                           "a/d turn +-15 deg, q/e turn +-60 deg, w forward, s backward")
    return out


class _LazyTargets(dict):
    def _load(self):
        if not super().__len__():
            self.update(_targets())

    def __contains__(self, k):
        self._load()
        return super().__contains__(k)

    def __iter__(self):
        self._load()
        return super().__iter__()

    def __getitem__(self, k):
        self._load()
        return super().__getitem__(k)


TEACH_TARGETS: dict[str, TeachTarget] = _LazyTargets()


def play(env, keymap: dict[str, int], read_key, show, *, seed: int = 0) -> tuple[list, bool]:
    """Play one trial with keys from ``read_key()``; returns (steps, saved). Pure of I/O for tests."""
    obs, info = env.reset(seed=seed)
    steps = []
    show(env, info)
    while True:
        key = read_key()
        if key == "u":
            return steps, False
        if key == "x":
            if steps:
                s = steps[-1]
                steps[-1] = (s[0], s[1], s[2], s[3], s[4], True)
            return steps, True
        if key not in keymap:
            show(None, {"message": f"unknown key {key!r}; keys: {', '.join(keymap)}, x = end, u = quit"})
            continue
        a = keymap[key]
        nxt, r, term, trunc, info = env.step(a)
        steps.append((obs, a, float(r), nxt, bool(term), bool(trunc)))
        obs = nxt
        show(env, info)
        if term or trunc:
            return steps, True


def teach(target: str, *, out: Path | None = None, seed: int = 0) -> int:
    import gymnasium as gym

    import connrl.envs  # noqa: F401  (registers the environments)

    t = TEACH_TARGETS[target]
    env = gym.make(t.env_id, render_mode="ansi", **t.env_kwargs) if _has_ansi(t) else gym.make(t.env_id,
                                                                                               **t.env_kwargs)
    out = out or Path("lessons") / f"{target}-{time.strftime('%Y%m%d-%H%M%S')}.json"
    print(f"Teaching {target} ({t.env_id}). {t.describe}. x = end the trial, u = quit without saving.")

    def read_key():
        line = sys.stdin.readline()
        if not line:
            return "u"
        return line.strip()[:1]

    def show(e, info):
        if e is not None and getattr(e, "render_mode", None) == "ansi":
            print(e.render())
        msg = info.get("message") if info else None
        if msg:
            print(msg)
        elif info:
            print({k: v for k, v in info.items() if np.isscalar(v) or isinstance(v, tuple | str)})

    steps, saved = play(env, t.keymap, read_key, show, seed=seed)
    if not saved or not steps:
        print("nothing saved")
        return 1
    lessons = []
    if out.exists():
        try:
            lessons = load_lessons(out, env_id=t.env_id)
        except LessonFileError as exc:
            raise SystemExit(f"connrl: will not append to {out}: {exc}") from None
    lessons.append(Lesson.from_steps(steps, taught=True, meta={"seed": seed, "made_by": "person (connrl teach)"}))
    save_lessons(out, lessons, env_id=t.env_id, env_kwargs=t.env_kwargs, source="played by a person with connrl teach")
    print(f"saved lesson {len(lessons)} ({len(steps)} steps) to {out}")
    return 0


def _has_ansi(t: TeachTarget) -> bool:
    import gymnasium as gym
    from gymnasium.envs.registration import load_env_creator

    cls = load_env_creator(gym.spec(t.env_id).entry_point)
    return "ansi" in getattr(cls, "metadata", {}).get("render_modes", [])
