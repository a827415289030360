"""Per-task settings files in RL Zoo's shape: one YAML file per agent kind, one entry per environment id.

    # connrl/data/hyperparams/qcon-r.yml
    CartPole-v1:
      n_timesteps: 50000     # connrl train's --steps
      env_kwargs: {}         # gymnasium.make(id, **env_kwargs)
      hidden: 16             # any connrl.own.api.AgentOptions field
      lr: 0.05

``connrl train ENV`` uses the shipped entry for ENV and its agent when there is one (and says so); ``--hyperparams
FILE`` reads your own file of the same shape; ``--steps``, ``--option`` and ``--env-kwargs`` override single values.
Files are read with ``yaml.safe_load`` (no tags, so reading never runs code) and every value is checked before
anything is built: a wrong key is one line naming the file, the entry and what is allowed.
"""

from __future__ import annotations

import json
from pathlib import Path

from connrl.storage import MAX_NESTING, FileError, read_limited_text, shown

SETTINGS_DIR = Path(__file__).parents[1] / "data" / "hyperparams"
RESERVED = ("n_timesteps", "env_kwargs")
MAX_SETTINGS_BYTES = 2**20
MAX_STEPS = 10**10  # environment steps of one `connrl train` (and a settings file's n_timesteps): months of compute


SHARED = {"QCON-T": "QCON-R"}  # QCON-T is QCON-R that also replays a teacher's lessons: its settings, as the
# benchmark gives them (benchmarks/bench_gymnasium.py), unless it has a file of its own


def shipped_file(kind: str) -> Path:
    """The shipped settings file of an agent kind (it may not exist): its own, else the one it shares."""
    own = SETTINGS_DIR / f"{kind.lower()}.yml"
    return own if own.exists() or kind not in SHARED else SETTINGS_DIR / f"{SHARED[kind].lower()}.yml"


def load_plain_yaml(text: str, path):
    """YAML as plain data: aliases (``*name``, the "billion laughs" expansion) are refused and nesting is bounded,
    both checked on the parser's event stream before anything is built (the parser is not recursive; the builder
    is). ValueError in one line naming the file; yaml.YAMLError for what is not YAML."""
    import yaml

    depth = 0
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, yaml.AliasEvent):
            mark = event.start_mark
            raise ValueError(f"{path}: uses a YAML alias (*{event.anchor}, line {mark.line + 1}); a settings file "
                             "holds plain values: write the value out where it is used")
        if isinstance(event, yaml.MappingStartEvent | yaml.SequenceStartEvent):
            depth += 1
            if depth > MAX_NESTING:
                raise ValueError(f"{path}: nests more than {MAX_NESTING} levels deep (line "
                                 f"{event.start_mark.line + 1}); a settings file nests a few")
        elif isinstance(event, yaml.MappingEndEvent | yaml.SequenceEndEvent):
            depth -= 1
    try:
        return yaml.safe_load(text)
    except ValueError as exc:  # a value Python will not build, e.g. an integer of more than 4300 digits
        raise ValueError(f"{path}: holds a value that cannot be read ({str(exc).splitlines()[0][:120]})") from None


def read_settings(path) -> dict[str, dict]:
    """All entries of a settings file, each checked (``check_entry``); ValueError in one line otherwise."""
    import yaml

    path = Path(path)
    try:
        data = load_plain_yaml(read_limited_text(path, MAX_SETTINGS_BYTES, "settings file"), path)
    except FileError as exc:
        raise ValueError(str(exc)) from None
    except yaml.YAMLError as exc:
        where = getattr(exc, "problem_mark", None)
        at = f" (line {where.line + 1})" if where is not None else ""
        problem = (str(getattr(exc, "problem", None) or exc).strip().splitlines() or ["?"])[0][:200]
        raise ValueError(f"{path}: is not valid YAML{at}: {problem}") from None
    if data is None:
        return {}
    if not isinstance(data, dict) or not all(isinstance(k, str) for k in data):
        raise ValueError(f"{path}: must map environment ids to settings (RL Zoo's shape: 'CartPole-v1: {{lr: "
                         "0.05}}')")
    return {env_id: check_entry(path, env_id, entry) for env_id, entry in data.items()}


def check_entry(path, env_id: str, entry) -> dict:
    """An entry with its options checked as ``AgentOptions`` fields, ``n_timesteps`` a whole number >= 1 and
    ``env_kwargs`` a mapping with string keys."""
    from connrl.own.api import options_from

    where = f"{path}: entry {env_id!r}"
    if entry is None:
        entry = {}
    if not isinstance(entry, dict) or not all(isinstance(k, str) for k in entry):
        raise ValueError(f"{where} must be a mapping of settings, got {type(entry).__name__}")
    n = entry.get("n_timesteps")
    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_STEPS):
        raise ValueError(f"{where}: n_timesteps must be a whole number from 1 to {MAX_STEPS:.0e} (the --steps "
                         f"cap), got {shown(n)}")
    kwargs = entry.get("env_kwargs") or {}
    if not isinstance(kwargs, dict) or not all(isinstance(k, str) for k in kwargs):
        raise ValueError(f"{where}: env_kwargs must be a mapping of argument names to values, got {shown(kwargs)}")
    try:
        plain = json.loads(json.dumps(kwargs, default=str)) == kwargs  # a YAML date, set or bytes: not kept
    except ValueError:  # an integer too long to write as text
        plain = False
    if not plain:
        raise ValueError(f"{where}: env_kwargs must be plain values (numbers, strings, true/false, null, lists, "
                         f"mappings), got {shown(kwargs)}")
    options = {k: v for k, v in entry.items() if k not in RESERVED}
    try:
        options_from(options)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"{where}: {exc}") from None
    return {"n_timesteps": n, "env_kwargs": dict(kwargs), "options": options}


def task_settings(env_id: str, kind: str, path=None) -> tuple[dict | None, str | None]:
    """(entry, where it came from) for ``env_id``: from ``path`` when given (an id it lacks is an error), else
    from the shipped file of ``kind`` when it has the id, else (None, None)."""
    if path is not None:
        entries = read_settings(path)
        if env_id not in entries:
            have = ", ".join(sorted(entries)) or "none"
            raise ValueError(f"{path}: has no entry for {env_id!r} (it has: {have})")
        return entries[env_id], f"{path} [{env_id}]"
    file = shipped_file(kind)
    if not file.exists():
        return None, None
    entries = read_settings(file)
    if env_id not in entries:
        return None, None
    return entries[env_id], f"{file.relative_to(Path(__file__).parents[2])} [{env_id}]"


def settings_yaml(env_id: str, n_timesteps: int | None, env_kwargs: dict, options: dict, comment: str = "") -> str:
    """One entry as the text of a settings file (``connrl tune`` writes its best settings so)."""
    import yaml

    entry = {**({"n_timesteps": n_timesteps} if n_timesteps else {}), **({"env_kwargs": env_kwargs}
                                                                          if env_kwargs else {}), **options}
    head = "".join(f"# {line}\n" for line in comment.splitlines())
    return head + yaml.safe_dump({env_id: entry}, sort_keys=False)
