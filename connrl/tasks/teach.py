"""``connrl teach``: play a task from the keyboard and save the trial as a taught lesson (3.7).

The terminal UI shows the environment's ANSI (or a text summary of its) rendering and reads one key per
line (type the key and Enter): it works in any terminal, over ssh and under tmux. ``x`` ends the trial
early (kept as a lesson cut by a time limit), ``u`` quits without saving. The lesson is saved with
``connrl.core.lesson_files`` (versioned JSON), appending to the file if it already exists. An existing file
is checked before any play (same world, world options, input size and number of actions, not damaged) and
keeps its metadata; if saving fails after play, the trial goes to a new ``<name>.rescued-<time>.json``
beside it (path printed, non-zero exit).

Each target names a registered environment, its constructor arguments and the key map of its actions.
Chapters add targets to ``TEACH_TARGETS``.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from connrl.core.lesson_files import LessonFileError, append_lessons, check_lesson_file, lesson_json, save_lessons
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
TEACH_SOURCE = "played by a person with connrl teach"


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


def _read_stdin_key() -> str:
    line = sys.stdin.readline()
    return line.strip()[:1] if line else "u"


def _print_show(e, info) -> None:
    if e is not None and getattr(e, "render_mode", None) == "ansi":
        print(e.render())
    msg = info.get("message") if info else None
    if msg:
        print(msg)
    elif info:
        print({k: v for k, v in info.items() if np.isscalar(v) or isinstance(v, tuple | str)})


def _make_env(t: TeachTarget):
    import gymnasium as gym

    import connrl.envs  # noqa: F401  (registers the environments)

    return gym.make(t.env_id, render_mode="ansi", **t.env_kwargs) if _has_ansi(t) else gym.make(t.env_id,
                                                                                               **t.env_kwargs)


def _file_checks(t: TeachTarget, env) -> dict:
    """What a lesson file must match to take a lesson played on ``env``: world, options, input size, actions."""
    return {"env_id": t.env_id, "env_kwargs": t.env_kwargs, "option_defaults": _option_defaults(t.env_id),
            "input_dim": int(np.prod(env.observation_space.shape)), "n_actions": int(env.action_space.n)}


def check_out_file(out: Path, target: str, checks: dict) -> None:
    """Before any play: refuse (LessonFileError) an ``--out`` file the played lesson could not be added to."""
    if out.parent.exists() and not out.parent.is_dir():
        raise LessonFileError(f"{out}: {out.parent} is not a directory; --out must be a file in a directory")
    if not out.exists():
        return
    try:
        check_lesson_file(out, **checks)
    except LessonFileError as exc:
        raise LessonFileError(f"{exc}; `connrl teach {target}` will not add its lesson to this file "
                              f"(choose another --out file)") from None


def save_played(out: Path, lesson: Lesson, t: TeachTarget, checks: dict) -> int:
    """Add the played lesson to ``out`` (kept metadata) or create it; if that fails, rescue the trial beside it."""
    try:
        if out.exists():
            count = append_lessons(out, [lesson], **checks)
        else:
            save_lessons(out, [lesson], env_id=t.env_id, env_kwargs=t.env_kwargs, source=TEACH_SOURCE)
            count = 1
    except Exception as exc:  # whatever went wrong, the played trial must not be lost
        print(f"connrl: the played lesson was not saved: {_why(exc, out)}", file=sys.stderr)
        rescued = rescue_lesson(out, lesson, t)
        if rescued is not None:
            print(f"connrl: the played trial ({len(lesson)} steps) is saved in {rescued} instead", file=sys.stderr)
        return 1
    print(f"saved lesson {count} ({len(lesson)} steps) to {out}")
    return 0


def _why(exc: Exception, out: Path) -> str:
    """One line saying why ``out`` could not be written."""
    if isinstance(exc, LessonFileError):
        return str(exc)
    if isinstance(exc, OSError):
        where = f": {exc.filename}" if exc.filename and str(exc.filename) != str(out) else ""
        return f"{out}: cannot write the file ({exc.strerror or exc}{where})"
    return f"{out}: {type(exc).__name__}: {exc}"


def _reserve(folder: Path, stem: str) -> Path | None:
    """A new empty file ``<stem>.rescued-<time>[-k].json`` in ``folder`` (exclusive create: never an existing one)."""
    stamp = time.strftime("%Y%m%d-%H%M%S")
    for k in range(100):
        p = folder / f"{stem}.rescued-{stamp}{f'-{k}' if k else ''}.json"
        try:
            with open(p, "x"):
                return p
        except FileExistsError:
            continue
        except OSError:
            return None
    return None


def rescue_lesson(out: Path, lesson: Lesson, t: TeachTarget) -> Path | None:
    """Save the played lesson alone to a new file beside ``out`` (else in the working or temporary directory).

    Never overwrites a file. If nothing can be written, the lesson file is printed to stderr so that the
    trial is still not lost; returns None then.
    """
    import tempfile

    for folder in dict.fromkeys([out.parent, Path.cwd(), Path(tempfile.gettempdir())]):
        p = _reserve(folder, out.stem)
        if p is None:
            continue
        try:
            save_lessons(p, [lesson], env_id=t.env_id, env_kwargs=t.env_kwargs, source=TEACH_SOURCE)
            return p
        except Exception:  # try the next folder, then print the lesson
            p.unlink(missing_ok=True)
    doc = {"format": "connrl-lesson", "version": 1, "env_id": t.env_id, "env_kwargs": t.env_kwargs,
           "source": TEACH_SOURCE, "lessons": [lesson_json(lesson)]}
    print(f"connrl: could not write the played trial anywhere; here is its lesson file:\n{json.dumps(doc)}",
          file=sys.stderr)
    return None


def teach(target: str, *, out: Path | None = None, seed: int = 0, read_key=None, show=None) -> int:
    """Play ``target`` from the keyboard (or ``read_key``) and save the trial as a taught lesson to ``out``.

    An existing ``out`` is checked before any play (LessonFileError if it cannot take the lesson); the lesson
    is appended keeping the file's metadata; if saving fails after play, the trial is saved beside it.
    """
    t = TEACH_TARGETS[target]
    env = _make_env(t)
    out = Path(out) if out else Path("lessons") / f"{target}-{time.strftime('%Y%m%d-%H%M%S')}.json"
    checks = _file_checks(t, env)
    check_out_file(out, target, checks)
    print(f"Teaching {target} ({t.env_id}). {t.describe}. x = end the trial, u = quit without saving.")
    steps, saved = play(env, t.keymap, read_key or _read_stdin_key, show or _print_show, seed=seed)
    if not saved or not steps:
        print("nothing saved")
        return 1
    lesson = Lesson.from_steps(steps, taught=True, meta={"seed": seed, "made_by": "person (connrl teach)"})
    return save_played(out, lesson, t, checks)


def _option_defaults(env_id: str) -> dict:
    """The world options an environment takes when not given: its registration kwargs over its signature."""
    import inspect

    import gymnasium as gym
    from gymnasium.envs.registration import load_env_creator

    spec = gym.spec(env_id)
    params = inspect.signature(load_env_creator(spec.entry_point)).parameters
    defaults = {k: p.default for k, p in params.items() if p.default is not inspect.Parameter.empty}
    return {**defaults, **(spec.kwargs or {})}


def _has_ansi(t: TeachTarget) -> bool:
    import gymnasium as gym
    from gymnasium.envs.registration import load_env_creator

    cls = load_env_creator(gym.spec(t.env_id).entry_point)
    return "ansi" in getattr(cls, "metadata", {}).get("render_modes", [])
