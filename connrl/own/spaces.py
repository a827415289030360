"""Which Gymnasium environments and spaces the own-task API (connrl.own.api) takes, the input code of composite
observations, and spaces as strict JSON in ``agent.json`` (written by ``space_json``, checked by ``check_space``,
rebuilt by ``space_from``; no pickle).

A ``Dict``, ``Tuple``, ``MultiDiscrete`` or ``MultiBinary`` observation is flattened in ``gymnasium.spaces.flatten``
order: each discrete part (a ``Discrete``, each ``MultiDiscrete`` entry) becomes its one-hot and each binary entry its
bit, both at +-0.5 (the thesis's binary code, 5.3.2); each ``Box`` entry is scaled as a plain ``Box`` is.
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from connrl.storage import FileError, check_number

SUPPORTED = ("a Box (any shape), Discrete, MultiDiscrete or MultiBinary observation space, or a Dict / Tuple of "
             "them")
COMPOSITE = (spaces.Dict, spaces.Tuple, spaces.MultiDiscrete, spaces.MultiBinary)
MAX_DEPTH = 8  # nested Dict / Tuple levels an agent file may declare


def check_single(env) -> None:
    """Refuse a vectorised environment in one line, before its batched spaces are mistaken for the task's."""
    n = getattr(env, "num_envs", None)
    if n is not None or getattr(env, "is_vector_env", False) or _is_vector(env):
        raise ValueError(f"connrl agents learn from one environment at a time (per-sample nets, the thesis's trials); "
                         f"got a vector env ({type(env).__name__}, {n} copies): pass a single env, e.g. gym.make(id) "
                         "instead of gym.make_vec(id, n)")


def _is_vector(env) -> bool:
    from gymnasium.vector import VectorEnv
    return isinstance(env, VectorEnv)


def check_observation_space(space, depth: int = 0) -> None:
    """A ValueError in one line unless connrl can encode ``space`` (``SUPPORTED``)."""
    if isinstance(space, spaces.Dict | spaces.Tuple) and depth < MAX_DEPTH:
        parts = space.spaces.items() if isinstance(space, spaces.Dict) else enumerate(space.spaces)
        for key, part in parts:
            if isinstance(space, spaces.Dict) and not isinstance(key, str):
                raise ValueError(f"connrl agents need a Dict observation space with string keys, got key {key!r}")
            check_observation_space(part, depth + 1)
    elif not isinstance(space, spaces.Box | spaces.Discrete | spaces.MultiDiscrete | spaces.MultiBinary):
        raise ValueError(f"connrl agents need {SUPPORTED} (at most {MAX_DEPTH} levels deep), got {space}")
    if depth == 0 and spaces.flatdim(space) < 1:
        raise ValueError(f"the observation space {space} has no dimensions; connrl agents need {SUPPORTED}")


def binary_units(space) -> np.ndarray:
    """Which entries of ``gymnasium.spaces.flatten(space, obs)`` are one-hot or binary bits (True) and which a Box's."""
    if isinstance(space, spaces.Box):
        return np.zeros(int(np.prod(space.shape)), bool)
    if isinstance(space, spaces.Dict | spaces.Tuple):
        parts = space.spaces.values() if isinstance(space, spaces.Dict) else space.spaces
        return np.concatenate([binary_units(p) for p in parts] or [np.zeros(0, bool)])
    return np.ones(spaces.flatdim(space), bool)


INPUT_SCALES = ("bounds", "spread")  # AgentOptions.input_scale


def affine_scales(low, high, samples, by: str = "bounds") -> tuple[np.ndarray, np.ndarray]:
    """(offset, scale) per unit: a bounded one onto [-1, 1]; an unbounded one so that 2 standard deviations of the
    samples (a random policy's observations) reach +-1; a unit the samples never moved is left as it is. ``by="spread"``
    scales the bounded units by the samples too: bounds far wider than what the task visits (LunarLander-v3's
    velocities: +-10 for a spread under 1) would squeeze the inputs into a small part of the code."""
    if by not in INPUT_SCALES:
        raise ValueError(f"input scale must be one of {', '.join(INPUT_SCALES)}, got {by!r}")
    low, high = np.asarray(low, float).ravel(), np.asarray(high, float).ravel()
    x = np.asarray(samples, float).reshape(len(samples), -1)
    bounded = np.isfinite(low) & np.isfinite(high) & (high - low < 1e6) & (by == "bounds")
    lo, hi = np.where(bounded, low, 0.0), np.where(bounded, high, 0.0)
    offset = np.where(bounded, (lo + hi) / 2, x.mean(axis=0))
    scale = np.where(bounded, (hi - lo) / 2, 2 * x.std(axis=0))
    return offset, np.where(scale > 1e-6, scale, 1.0)


def flat_scales(space, samples: list, by: str = "bounds") -> tuple[np.ndarray, np.ndarray]:
    """(offset, scale) of a composite space's flattened units: bits to +-0.5, Box entries as ``affine_scales``."""
    flat = spaces.flatten_space(space)
    offset, scale = affine_scales(flat.low, flat.high, [spaces.flatten(space, o) for o in samples], by)
    bits = binary_units(space)
    return np.where(bits, 0.5, offset), np.where(bits, 1.0, scale)


def flatten(space, obs) -> np.ndarray:
    return np.asarray(spaces.flatten(space, obs), float)


def split_batch(space, obs) -> list | None:
    """The observations of a batch (a vector env's: one first axis over the environments, in every part of a
    ``Dict`` / ``Tuple``), or None where ``obs`` is one observation of ``space``."""
    n = _batch_size(space, obs)
    if n is None:
        return None
    return [_item(space, obs, i) for i in range(n)]


def _batch_size(space, obs) -> int | None:
    if isinstance(space, (spaces.Dict, spaces.Tuple)):
        parts = space.spaces.items() if isinstance(space, spaces.Dict) else enumerate(space.spaces)
        sizes = {_batch_size(s, obs[k]) for k, s in parts}
        if len(sizes) != 1:
            raise ValueError(f"the parts of an observation of {space} must all be one observation or all a batch "
                             "of the same size")
        return sizes.pop()
    extra = np.ndim(obs) - len(space.shape)
    if extra not in (0, 1):
        raise ValueError(f"an observation of {space} has shape {space.shape}, a batch of them one axis more; got "
                         f"shape {np.shape(obs)}")
    return np.shape(obs)[0] if extra else None


def _item(space, obs, i):
    if isinstance(space, spaces.Dict):
        return {k: _item(s, obs[k], i) for k, s in space.spaces.items()}
    if isinstance(space, spaces.Tuple):
        return tuple(_item(s, o, i) for s, o in zip(space.spaces, obs, strict=True))
    return np.asarray(obs)[i]


# ------------------------------------------------------------------------------------------------- as JSON

def space_json(space) -> dict:
    if isinstance(space, spaces.Discrete):
        return {"type": "Discrete", "n": int(space.n), "start": int(space.start)}
    if isinstance(space, spaces.Box):
        return {"type": "Box", "shape": list(space.shape), "low": _bounds(space.low), "high": _bounds(space.high)}
    if isinstance(space, spaces.MultiDiscrete):
        return {"type": "MultiDiscrete", "shape": list(space.shape), "nvec": space.nvec.ravel().tolist(),
                "start": space.start.ravel().tolist()}
    if isinstance(space, spaces.MultiBinary):
        return {"type": "MultiBinary", "shape": list(space.shape)}
    if isinstance(space, spaces.Tuple):
        return {"type": "Tuple", "spaces": [space_json(s) for s in space.spaces]}
    if isinstance(space, spaces.Dict):  # a list of pairs: the order is the flatten order
        return {"type": "Dict", "spaces": [[str(k), space_json(s)] for k, s in space.spaces.items()]}
    return {"type": type(space).__name__}


def _bounds(values) -> list:
    """A Box bound as strict JSON: an infinite bound as the string "inf" / "-inf" (JSON has no Infinity)."""
    return [v if np.isfinite(v) else ("inf" if v > 0 else "-inf") for v in np.asarray(values, float).ravel().tolist()]


def space_from(d: dict):
    """The space ``space_json`` wrote (checked by ``check_space`` first)."""
    t = d["type"]
    if t == "Discrete":
        return spaces.Discrete(d["n"], start=d.get("start", 0))
    shape = tuple(d.get("shape", ()))
    if t == "Box":
        return spaces.Box(np.asarray(d["low"], float).reshape(shape), np.asarray(d["high"], float).reshape(shape),
                          dtype=np.float64)
    if t == "MultiDiscrete":
        return spaces.MultiDiscrete(np.reshape(d["nvec"], shape), start=np.reshape(d["start"], shape))
    if t == "MultiBinary":
        return spaces.MultiBinary(list(shape))
    if t == "Tuple":
        return spaces.Tuple([space_from(s) for s in d["spaces"]])
    return spaces.Dict([(k, space_from(s)) for k, s in d["spaces"]])


_KEYS = {"Discrete": {"type", "n", "start"}, "Box": {"type", "shape", "low", "high"}, "MultiBinary": {"type", "shape"},
         "MultiDiscrete": {"type", "shape", "nvec", "start"}, "Tuple": {"type", "spaces"}, "Dict": {"type", "spaces"}}


def check_space(meta, d, key: str, max_width: int, depth: int = 0) -> int:
    """A space as ``space_json`` writes it, every field checked; returns its width as the nets see it (its
    ``flatdim``). FileError naming the field when it is not one connrl writes."""
    if not isinstance(d, dict) or d.get("type") not in _KEYS or set(d) - _KEYS[d["type"]]:
        raise FileError(meta, f"must be an object with 'type' one of {', '.join(_KEYS)} and that type's fields", key)
    t = d["type"]
    if t == "Discrete":
        n = check_number(meta, f"{key}.n", d.get("n"), 1, max_width, integer=True)
        check_number(meta, f"{key}.start", d.get("start", 0), -2**62, 2**62, integer=True)
        return n
    if t in ("Tuple", "Dict"):
        parts = d.get("spaces")
        if depth >= MAX_DEPTH or not isinstance(parts, list) or not parts:
            raise FileError(meta, f"must be a non-empty list of spaces, at most {MAX_DEPTH} levels deep",
                            f"{key}.spaces")
        if t == "Dict":
            names = [p[0] if isinstance(p, list) and len(p) == 2 and isinstance(p[0], str) else None for p in parts]
            if None in names or len(set(names)) != len(names) or max(map(len, names)) > 200:
                raise FileError(meta, "must be a list of [key, space] pairs with distinct string keys",
                                f"{key}.spaces")
            parts = [p[1] for p in parts]
        width = 0
        for k, part in enumerate(parts):
            width += check_space(meta, part, f"{key}.spaces[{k}]", max_width - width, depth + 1)
        return width
    shape = d.get("shape")
    if not isinstance(shape, list) or len(shape) > 8:
        raise FileError(meta, f"is {shape!r}; it must be a list of at most 8 sizes", f"{key}.shape")
    size = 1
    for s in shape:
        size *= check_number(meta, f"{key}.shape", s, 1, max_width, integer=True)
        if size > max_width:
            raise FileError(meta, f"is {shape!r}: more than {max_width:,} inputs", f"{key}.shape")
    if t == "MultiBinary":
        return size
    if t == "MultiDiscrete":
        nvec, start = d.get("nvec"), d.get("start")
        for name, values, low in (("nvec", nvec, 1), ("start", start, -2**62)):
            if not isinstance(values, list) or len(values) != size:
                raise FileError(meta, f"must be a list of {size} whole numbers", f"{key}.{name}")
            for v in values:
                check_number(meta, f"{key}.{name}", v, low, 2**62, integer=True)
        if sum(nvec) > max_width:
            raise FileError(meta, f"sums to {sum(nvec)}: more than {max_width:,} inputs", f"{key}.nvec")
        return sum(nvec)
    for bound in ("low", "high"):
        values = d.get(bound)
        if not isinstance(values, list) or len(values) != size or not all(
                v in ("inf", "-inf") or isinstance(v, int | float) and not isinstance(v, bool) and not v != v
                for v in values):
            raise FileError(meta, f"must be a list of {size} numbers (\"inf\" / \"-inf\" for no bound)",
                            f"{key}.{bound}")
    if any(float(lo) > float(hi) for lo, hi in zip(d["low"], d["high"], strict=True)):
        raise FileError(meta, "holds a low bound above its high bound", f"{key}.low")
    return size


def check_render_dependency(env, env_id: str, env_kwargs: dict) -> None:
    """Gymnasium's own worlds draw a human window with pygame, imported only at the first frame: without it training
    would end in a long traceback mid-run, so say which package is missing before any step."""
    import importlib.util

    entry = str(getattr(getattr(env, "spec", None), "entry_point", "") or "")
    if env_kwargs.get("render_mode") == "human" and entry.startswith("gymnasium.") and \
            importlib.util.find_spec("pygame") is None:
        raise ValueError(f"{env_id} with render_mode='human' needs pygame, which is not installed: "
                         "pip install \"gymnasium[classic-control]\" (or \"gymnasium[box2d]\"), or leave render_mode "
                         "out")
