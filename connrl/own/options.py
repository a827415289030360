"""The own-task learner's settings (``AgentOptions``), each checked on construction (connrl.own.api uses them)."""

from __future__ import annotations

from dataclasses import dataclass, fields

from connrl.nets.mlp import MAX_UNITS
from connrl.own.spaces import INPUT_SCALES
from connrl.storage import shown

# the size-like options' ranges: far beyond any task of the thesis or of Gymnasium's classic control, small enough
# that no typo asks for gigabytes or centuries before it is noticed
_SIZES = {"hidden": (0, MAX_UNITS), "anneal_steps": (1, 10**10), "lessons_per_trial": (0, 10_000),
          "capacity": (1, 100_000), "warmup_steps": (1, 10**7), "window": (1, 64), "context": (0, MAX_UNITS),
          "average_steps": (1, 10**10)}
# the positive real options' upper ends: far beyond any sensible value (the thesis's rates are 0.01-0.4), small enough
# that a typo (lr: 1e20) is refused here, not met as an overflow inside a compiled kernel mid-run
_POSITIVE = {"lr": 100.0, "lr_end": 100.0, "init_range": 100.0, "t_start": 1e6, "t_end": 1e6}
_MAY_BE_NONE = ("t_start", "t_end", "lr_end", "average_steps", "p_threshold")  # None: the framework's, or off
MAX_NET_WEIGHTS = 50_000_000  # inputs x hidden units x actions: 400 MB of float64 per array


# the default temperatures (t_start, t_end) on values / value_range. AHC's merits gather whatever TD error the action
# taken meets, so at Q-learning's temperatures the action a random start favours soon has a merit several T above
# the other's, the other is almost never tried and the critic's TD errors, now measuring that one policy, average 0:
# nothing moves the merits again (CartPole: one push for ever, 9-step trials). The thesis gave its AHC agents a
# temperature ten times its Q agents' (Table 4.1: 1/T 2 -> 10 against 20 -> 60); on CartPole 2.0 -> 0.1 learns
# (scripts/own_task/ahcon_cartpole.py; docs/PERFORMANCE.md, "AHCON on your own task").
TEMPERATURES = {"Q": (0.05, 0.005), "AHC": (2.0, 0.1)}


def temperatures(options: AgentOptions, kind: str) -> tuple[float, float]:
    """``(t_start, t_end)`` for the framework ``kind``: the options' where given, else ``TEMPERATURES``'s."""
    start, end = TEMPERATURES["AHC" if kind.startswith("AHCON") else "Q"]
    return (start if options.t_start is None else options.t_start, end if options.t_end is None else options.t_end)


@dataclass(frozen=True)
class AgentOptions:
    """The learner's settings; every one has a default (docs: README, "Your own task")."""

    hidden: int = 16  # hidden units of each action's net (of the one shared net with shared_hidden)
    shared_hidden: bool = False  # one hidden layer read by every action's output (the multi-output net 3.4 weighs
    # against OAON) instead of one net per action; not for recurrent-Q
    lr: float = 0.05  # back-propagation learning rate, ...
    lr_end: float | None = None  # ... going linearly to this over the first anneal_steps steps; None: lr throughout
    momentum: float = 0.9
    init_range: float = 0.5  # initial weights uniform in +-init_range
    gamma: float = 0.99  # discount factor
    lam: float = 0.7  # TD(lambda) recency factor of replay (QCON-R)
    t_start: float | None = None  # Boltzmann temperature on Q (or merits) / value_range, from ...
    t_end: float | None = None  # ... to this over the first anneal_steps steps; None: the framework's (TEMPERATURES:
    # Q-learning 0.05 -> 0.005; AHC 2.0 -> 0.1, hotter as the thesis's AHC agents were, 4.3.2; issue 30)
    anneal_steps: int = 50_000
    lessons_per_trial: int = 20  # lessons replayed after each trial (QCON-R)
    capacity: int = 100  # latest lessons kept for replay
    p_threshold: float | None = None  # actions less likely than this are not replayed (3.5.1); None: the thesis's
    # value for the framework (4.2.7): 0.01 for Q-learning, 0.2 for AHC
    value_range: float | None = None  # Q spans +-value_range; None: the largest return the rewards seen allow
    # (max |r| / (1 - gamma), but |r| for a reward that ends the episode; set by the first non-zero reward, grown by
    # larger ones)
    warmup_steps: int = 1000  # random-policy steps that set the input and value scales
    input_scale: str = "bounds"  # a bounded Box unit onto [-1, 1] by its bounds, or "spread": by the warm-up's mean
    # and spread, as an unbounded one is (for bounds far wider than the task visits)
    window: int = 2  # window-Q: the N latest observations and actions beside the current one (7.3)
    context: int = 8  # recurrent-Q: context units, at most hidden (7.3-7.4)
    average_steps: int | None = None  # the greedy policy acts with the weights averaged over about this many latest
    # steps (connrl.own.averaging); None: with the live weights

    def __post_init__(self):
        for name, (low, high) in _SIZES.items():
            v = getattr(self, name)
            if v is None and name in _MAY_BE_NONE:
                continue
            if isinstance(v, bool) or not isinstance(v, int) or not low <= v <= high:
                off = " or None (null in a settings file: off)" if name == "average_steps" else ""
                raise ValueError(f"option {name} must be a whole number from {low} to {high:,}{off}, got {shown(v)}")
        for name, hi in _POSITIVE.items():
            v = getattr(self, name)
            if v is None and name in _MAY_BE_NONE:
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v <= hi:
                raise ValueError(f"option {name} must be a number > 0 and <= {hi:g}, got {shown(v)}")
        for name in ("momentum", "p_threshold"):
            v = getattr(self, name)
            if v is None and name in _MAY_BE_NONE:
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 <= v < 1:
                raise ValueError(f"option {name} must be in [0, 1), got {v!r}")
        if self.input_scale not in INPUT_SCALES:
            raise ValueError(f"option input_scale must be one of {', '.join(INPUT_SCALES)}, "
                             f"got {shown(self.input_scale)}")
        if not isinstance(self.shared_hidden, bool):
            raise ValueError(f"option shared_hidden must be true or false, got {shown(self.shared_hidden)}")
        for name in ("gamma", "lam"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 <= v <= 1:
                raise ValueError(f"option {name} must be in [0, 1], got {v!r}")
        if self.value_range is not None and (isinstance(self.value_range, bool) or not (
                isinstance(self.value_range, (int, float)) and 0 < self.value_range <= MAX_VALUE_RANGE)):
            raise ValueError(f"option value_range must be None or a number > 0 and <= {MAX_VALUE_RANGE:g}, got "
                             f"{shown(self.value_range)}")


MAX_VALUE_RANGE = 1e12  # value_range an option may set and an agent file may hold (Agent.save refuses more)


def options_from(kwargs: dict) -> AgentOptions:
    """``AgentOptions(**kwargs)``, refusing an unknown option with the allowed ones in one line."""
    allowed = [f.name for f in fields(AgentOptions)]
    unknown = sorted(set(kwargs) - set(allowed))
    if unknown:
        named = ", ".join(repr(u[:40]) for u in unknown[:5]) + (f" and {len(unknown) - 5} more" if len(unknown) > 5
                                                                 else "")
        raise ValueError(f"unknown option(s) {named}; allowed: {', '.join(allowed)}")
    return AgentOptions(**kwargs)
