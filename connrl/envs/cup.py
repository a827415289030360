"""Two-cup collection in a 1-D corridor: the hidden-state task of thesis Ch. 7 (7.5.1-7.5.3).

## Description
The agent lives in a corridor of 11 cells (0-10) with walls beyond both ends and must pick up two cups, at
cells 3 and 7. It cannot sense the cup in its own cell, only cups in the two neighbouring cells, so after
the first cup is collected every cell on the way to the second one looks the same (all bits off): the
direction to walk is a *hidden state* that only history (which instance the trial started in) reveals.
There are two task instances (our reconstruction of the lost Fig. 7.4; docs/RECONSTRUCTION.md, "Cup collection")::

    cell:   0 1 2 3 4 5 6 7 8 9 10
    Inst A: . . I C . . . C . . .     start senses "cup right"
    Inst B: . . . C . . . C I . .     start senses "cup left"

The optimal policy takes 7 steps in each instance (A: right, pick-up, right x4, pick-up; B mirrored), 14
for both (7.5.1).

**Trial and performance measure.** One episode is one trial = one task instance: ``reset`` draws A or B
uniformly at random ("In each trial the agent started with one of the two possible initial states",
7.5.1), or takes ``options={"instance": "A" | "B"}``. The thesis's test score ("the number of steps to
pick up the four cups in both task instances", optimal 14) is the *sum over two test episodes*, one
started in each of ``INSTANCES``, each counting 30 steps when it times out (worst case 60), with control
errors off and greedy actions. That protocol lives in the experiment code; this environment provides the
per-instance episodes.

## Action Space
``Discrete(3)``: 0 = walk left one cell, 1 = walk right one cell, 2 = pick up (succeeds iff a cup is in
the agent's own cell). Walking into a wall leaves the agent where it is and is sensed as a collision.

## Observation Space
``Box(-0.5, 0.5, (4 + random_bits,), float32)``; every entry is a binary bit encoded as +0.5 (on) or -0.5
(off), the encoding of binary inputs used for the thesis's networks (5.3.2):

| index | bit |
|---|---|
| 0 | cup in the cell immediately left |
| 1 | cup in the cell immediately right |
| 2 | the previous action collided with the left wall |
| 3 | the previous action collided with the right wall |
| 4.. | ``random_bits`` fair coin flips, redrawn every step (Task 2, 7.5.2) |

## Rewards
1 on the step that picks up the last cup, 0 otherwise (7.5.1).

## Starting State
Agent at cell 2 (instance A) or cell 8 (instance B), cups at cells 3 and 7, collision bits off.

## Episode End
- Termination: both cups picked up.
- Truncation: ``max_steps`` (30, 7.5.1) steps without termination: a timeout, not a failure.

## Arguments
- ``random_bits`` (int, default 0): irrelevant random sensation bits appended (Task 2 uses 2).
- ``control_error`` (float in [0, 1), default 0): probability that an action has no effect at all (Task 3
  uses 0.15; the thesis turns control errors off for tests, so an experiment builds its test env with 0).
- ``max_steps`` (int, default 30): trial timeout.
- ``render_mode``: ``None`` or ``"ansi"`` (a one-line picture: ``I`` agent, ``C`` cup, ``@`` agent on a cup).

``info`` carries the true state for analysis: ``instance``, ``position``, ``cups`` (sorted cells still
holding a cup) and ``control_error_occurred`` (on steps).

## Differences from the thesis
- Fig. 7.4 is lost; the corridor length, cup cells and start cells are our reconstruction
  (docs/RECONSTRUCTION.md), chosen to
  match every number the text states (two instances, one cup visible at the start, 7 optimal steps each).
- The thesis does not say how a failed action (control error) interacts with the collision bits; here an
  action that fails has no effect at all, so it moves nothing, picks up nothing and senses no collision.
- 7.5.1 does not give the bit values; we use +-0.5, the thesis's usual convention ("As usual, binary inputs
  are represented by 0.5 and -0.5", 5.3.2).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

N_CELLS = 11  # cells 0..10; walls beyond both ends (R)
CUP_CELLS = (3, 7)  # both instances (R)
START_CELLS = {"A": 2, "B": 8}  # instance -> agent start cell (R)
INSTANCES = ("A", "B")  # a test of the thesis's measure runs one episode from each (7.5.1)
OPTIMAL_STEPS = 7  # per instance; 14 for both (7.5.1; verified by search in tests/envs/test_cup.py)
LEFT, RIGHT, PICK_UP = 0, 1, 2
ACTION_NAMES = ("left", "right", "pick-up")
ON, OFF = 0.5, -0.5


def transition(position: int, cups: frozenset[int], action: int) -> tuple[int, frozenset[int], int, float]:
    """Deterministic dynamics of one executed action (no control error).

    Returns ``(position, cups, collision, reward)`` with ``collision`` -1 (left wall), +1 (right wall) or 0.
    Pure, so tests can search the true state space.
    """
    if action == LEFT:
        return (position - 1, cups, 0, 0.0) if position > 0 else (position, cups, -1, 0.0)
    if action == RIGHT:
        return (position + 1, cups, 0, 0.0) if position < N_CELLS - 1 else (position, cups, +1, 0.0)
    if action == PICK_UP:
        if position in cups:
            left = cups - {position}
            return position, left, 0, (1.0 if not left else 0.0)
        return position, cups, 0, 0.0
    raise ValueError(f"action must be 0 (left), 1 (right) or 2 (pick-up), got {action!r}")


def sense(position: int, cups: frozenset[int], collision: int) -> np.ndarray:
    """The 4 thesis bits (+-0.5): cup left, cup right, collision left, collision right."""
    return np.array(
        [
            ON if position - 1 in cups else OFF,
            ON if position + 1 in cups else OFF,
            ON if collision < 0 else OFF,
            ON if collision > 0 else OFF,
        ],
        dtype=np.float32,
    )


class CupCollectionEnv(gym.Env):
    metadata = {"render_modes": ["ansi"], "render_fps": 4}

    def __init__(
        self,
        random_bits: int = 0,
        control_error: float = 0.0,
        max_steps: int = 30,
        render_mode: str | None = None,
    ):
        if not isinstance(random_bits, int | np.integer) or random_bits < 0:
            raise ValueError(f"random_bits must be an int >= 0 (Task 2 uses 2), got {random_bits!r}")
        if not 0.0 <= control_error < 1.0:
            raise ValueError(f"control_error must be in [0, 1) (Task 3 uses 0.15), got {control_error!r}")
        if not isinstance(max_steps, int | np.integer) or max_steps < 1:
            raise ValueError(f"max_steps must be an int >= 1 (thesis: 30), got {max_steps!r}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode must be None or 'ansi', got {render_mode!r}")
        self.random_bits = int(random_bits)
        self.control_error = float(control_error)
        self.max_steps = int(max_steps)
        self.render_mode = render_mode
        self.action_space = spaces.Discrete(3)
        self.observation_space = spaces.Box(OFF, ON, shape=(4 + self.random_bits,), dtype=np.float32)
        self.instance: str | None = None
        self.position = 0
        self.cups: frozenset[int] = frozenset()
        self._collision = 0
        self._steps = 0
        self._done = True

    def _obs(self) -> np.ndarray:
        bits = sense(self.position, self.cups, self._collision)
        if self.random_bits:
            noise = np.where(self.np_random.random(self.random_bits) < 0.5, OFF, ON).astype(np.float32)
            bits = np.concatenate([bits, noise])
        return bits

    def _info(self) -> dict[str, Any]:
        return {"instance": self.instance, "position": self.position, "cups": tuple(sorted(self.cups))}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        instance = (options or {}).get("instance")
        if instance is None:
            instance = "A" if self.np_random.random() < 0.5 else "B"
        if instance not in START_CELLS:
            raise ValueError(f"options['instance'] must be 'A' or 'B', got {instance!r}")
        self.instance = instance
        self.position = START_CELLS[instance]
        self.cups = frozenset(CUP_CELLS)
        self._collision = 0
        self._steps = 0
        self._done = False
        return self._obs(), self._info()

    def step(self, action):
        if self._done:
            raise RuntimeError("episode is over (terminated or truncated); call reset() before step()")
        # a plain int in range needs no Gymnasium check (it costs more than the step itself)
        if not (action.__class__ is int and 0 <= action < 3) and not self.action_space.contains(action):
            raise ValueError(f"action must be 0 (left), 1 (right) or 2 (pick-up), got {action!r}")
        failed = self.control_error > 0.0 and self.np_random.random() < self.control_error
        if failed:  # the action has no effect at all (7.5.3)
            self._collision, reward = 0, 0.0
        else:
            moved = transition(self.position, self.cups, int(action))
            self.position, self.cups, self._collision, reward = moved
        self._steps += 1
        terminated = not self.cups
        truncated = not terminated and self._steps >= self.max_steps
        self._done = terminated or truncated
        info = self._info()
        info["control_error_occurred"] = failed
        return self._obs(), reward, terminated, truncated, info

    def render(self):
        if self.render_mode != "ansi":
            return None
        cells = ["C" if c in self.cups else "." for c in range(N_CELLS)]
        cells[self.position] = "@" if self.position in self.cups else "I"
        return "|" + " ".join(cells) + "|"
