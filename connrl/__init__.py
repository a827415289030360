"""connrl: Long-Ji Lin's thesis (CMU-CS-93-103, 1993) as reusable reinforcement-learning software."""

from connrl import envs as _envs  # noqa: F401  (registers the thesis's worlds: gymnasium.make("connrl/..."))

__version__ = "0.1.0"
