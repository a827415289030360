"""connrl: Long-Ji Lin's thesis (CMU-CS-93-103, 1993) as reusable reinforcement-learning software."""

from connrl import envs as _envs  # noqa: F401  (registers the thesis's worlds: gymnasium.make("connrl/..."))

__version__ = "0.1.0"

_API = ("make_agent", "load", "evaluate", "record_lessons", "Agent", "AgentOptions")


def __getattr__(name):  # the own-task API (connrl.own.api) is imported on first use: ``import connrl`` stays light
    if name in _API:
        from connrl.own import api
        return getattr(api, name)
    raise AttributeError(f"module 'connrl' has no attribute {name!r}")
