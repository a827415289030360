"""State grouping (6.6.4): replay a long lesson as a shorter one whose steps stand for runs of similar states.

Consecutive states whose inputs lie within Euclidean distance mu of the run's first state, and at which the same
action (behaviour) was taken, form one group; mu is drawn uniformly from ``mu_range`` for each group (6.6.4: "a
random number between 0.5 and 2.5"). Each group is replayed as one state, its *centre*, a member drawn at random on
every replay so that every pattern is trained on in time (footnote 5). Between consecutive centres k steps apart,
the reward is the discounted sum of the k rewards and the discount is gamma^k (6.6.4: "the discount factor should be
changed to gamma^n"). Pure given the Generator.

Choices the thesis leaves open (docs/RECONSTRUCTION.md, "State grouping"): distances are measured to the group's
first state, not to every member; a group never spans a change of action (the thesis's example is the states "a
behavior takes the robot through"), so the centre's action is every member's and replay's test of bad choices,
made at the centre, speaks for the group; the final state (the lesson's last next state) is never grouped; steps of
the first group before its centre are not replayed (they lead to a state of the same group).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

from connrl.core.lessons import Lesson


def check_mu_range(mu_range) -> tuple[float, float]:
    """``mu_range`` as (low, high) with 0 <= low <= high, both finite, else one clear ValueError."""
    try:
        lo, hi = (float(v) for v in mu_range)
    except (TypeError, ValueError):
        raise ValueError(f"mu_range must be two numbers (low, high), got {mu_range!r}") from None
    if not 0 <= lo <= hi < math.inf:
        raise ValueError(f"mu_range must be (low, high) with 0 <= low <= high, both finite, got {mu_range!r}")
    return lo, hi


def group_states(inputs: np.ndarray, mu_range: tuple[float, float], rng: np.random.Generator,
                 actions: np.ndarray | None = None) -> np.ndarray:
    """Start index of each group of consecutive similar rows of ``inputs`` (see the module docstring); with
    ``actions``, a group also ends where the action changes. Compiled (``_group_starts``); the plain loop is
    ``group_states_reference``."""
    x = np.ascontiguousarray(inputs, dtype=np.float64)
    lo, hi = check_mu_range(mu_range)
    acts = np.zeros(0, dtype=np.int64) if actions is None else np.asarray(actions)
    # the compiled loop takes a Generator's draws, integer actions, one per row (else the plain loop's own errors)
    if (x.ndim != 2 or not isinstance(rng, np.random.Generator) or acts.dtype.kind not in "iu"
            or (actions is not None and acts.shape != (len(x),))):
        return group_states_reference(x, (lo, hi), rng, actions)
    return _group_starts(x, lo, hi, rng, np.ascontiguousarray(acts, dtype=np.int64), actions is not None)


def group_states_reference(inputs: np.ndarray, mu_range: tuple[float, float], rng: np.random.Generator,
                           actions: np.ndarray | None = None) -> np.ndarray:
    """``group_states`` as a plain loop over NumPy's distances: its oracle."""
    x = np.asarray(inputs, dtype=np.float64)
    lo, hi = check_mu_range(mu_range)
    starts, i = [], 0
    while i < len(x):
        starts.append(i)
        mu = rng.uniform(lo, hi)
        j = i + 1
        while j < len(x) and np.linalg.norm(x[j] - x[i]) < mu and (actions is None or actions[j] == actions[i]):
            j += 1
        i = j
    return np.array(starts, dtype=np.int64)


@numba.njit(cache=True)
def _group_starts(x, lo, hi, rng, actions, has_actions):
    """``group_states_reference``'s loop, compiled: the same draws from ``rng`` (Numba's ``uniform`` is NumPy's) and
    the same distances (``_sq_distance``)."""
    n = x.shape[0]
    starts = np.empty(n, dtype=np.int64)
    d, acc = np.empty(x.shape[1]), np.empty(16)
    g, i = 0, 0
    while i < n:
        starts[g] = i
        g += 1
        mu = rng.uniform(lo, hi)
        j = i + 1
        while j < n and (not has_actions or actions[j] == actions[i]) and math.sqrt(_sq_distance(x, i, j, d, acc)) < mu:
            j += 1
        i = j
    return starts[:g]


@numba.njit(cache=True)
def _sq_distance(x, i, j, d, acc):
    """|x[j] - x[i]|^2 summed in the order of ``np.linalg.norm``'s dot where the stored results were made (NumPy's
    OpenBLAS with ``OPENBLAS_CORETYPE=Haswell``: sixteen fused multiply-add lanes over blocks of 16, a fixed tree,
    then a plain tail), fixed here on every machine. ``d`` (I,) and ``acc`` (16,) are scratch."""
    n = x.shape[1]
    for k in range(n):
        d[k] = x[j, k] - x[i, k]
    n1 = n & -16
    s = 0.0
    if n1:
        for lane in range(16):
            acc[lane] = 0.0
        for b in range(0, n1, 16):
            for lane in range(16):
                acc[lane] = _fma(d[b + lane], d[b + lane], acc[lane])
        even = ((acc[0] + acc[2]) + (acc[4] + acc[6])) + ((acc[8] + acc[10]) + (acc[12] + acc[14]))
        odd = ((acc[1] + acc[3]) + (acc[5] + acc[7])) + ((acc[9] + acc[11]) + (acc[13] + acc[15]))
        s = even + odd
    for k in range(n1, n):
        s += d[k] * d[k]
    return s


@intrinsic
def _fma(typingctx, a, b, c):
    """``a * b + c`` rounded once, on every CPU (hardware FMA or libm's fma). The same intrinsic as
    ``connrl.nets.kernels._fma``, defined again here: a cached kernel may only use its own file's
    (tests/nets/test_kernel_cache.py)."""

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        return builder.call(builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d])), args)

    return types.float64(types.float64, types.float64, types.float64), codegen


@dataclass(frozen=True)
class GroupedLesson:
    """A lesson rewritten over group centres, with what ``connrl.core.replay.replay_q`` needs to replay it."""

    lesson: Lesson  # inputs: the centres, then the original final state; actions: those taken at the centres
    discounts: np.ndarray  # gamma^k per step, k = the steps from one centre to the next
    centres: np.ndarray  # index of each centre in the original lesson
    weights: np.ndarray | None = None  # the original per-step rows at the centres
    allowed: np.ndarray | None = None  # rows at the centres and the final state


def group_lesson(lesson: Lesson, gamma: float, mu_range: tuple[float, float], rng: np.random.Generator,
                 weights: np.ndarray | None = None, allowed: np.ndarray | None = None) -> GroupedLesson:
    """6.6.4: ``lesson`` replayed over its groups of similar states (module docstring). ``weights`` (n, A) and
    ``allowed`` (n+1, A) per-step rows are carried over to the centres."""
    n = len(lesson)
    if n == 0:
        raise ValueError("a lesson to group needs at least one step")
    starts = group_states(lesson.inputs[:n], mu_range, rng, lesson.actions)
    centres, rewards = (_centres_and_rewards if isinstance(rng, np.random.Generator) else
                        centres_and_rewards_reference)(starts, rng, lesson.rewards, gamma ** np.arange(n))
    steps = np.append(centres[1:], n) - centres
    out = Lesson(lesson.inputs[np.append(centres, n)], lesson.actions[centres], rewards, lesson.terminated,
                 lesson.truncated, lesson.taught, dict(lesson.meta))
    return GroupedLesson(out, gamma ** steps.astype(np.float64), centres,
                         None if weights is None else np.asarray(weights)[centres],
                         None if allowed is None else np.asarray(allowed)[np.append(centres, n)])


def centres_and_rewards_reference(starts, rng, rewards, powers) -> tuple[np.ndarray, np.ndarray]:
    """Each group's centre, drawn in its span, and the reward from a centre to the next, discounted by ``powers``
    (gamma^k, k = 0, 1, ...): ``_centres_and_rewards``'s oracle."""
    ends = np.append(starts[1:], len(rewards))
    centres = np.array([int(rng.integers(s, e)) for s, e in zip(starts, ends, strict=True)], dtype=np.int64)
    nxt = np.append(centres[1:], len(rewards))
    return centres, np.array([np.sum(rewards[c:m] * powers[:m - c]) for c, m in zip(centres, nxt, strict=True)])


@numba.njit(cache=True)
def _centres_and_rewards(starts, rng, rewards, powers):
    """Each group's centre (``rng.integers(start, end)``: Numba's draw is NumPy's) and the discounted reward sum from
    it to the next centre, ``np.sum(rewards[c:m] * powers[:m - c])`` in NumPy's (pairwise) order."""
    n, g = rewards.shape[0], starts.shape[0]
    centres = np.empty(g, dtype=np.int64)
    for k in range(g):
        centres[k] = rng.integers(starts[k], starts[k + 1] if k + 1 < g else n)
    out = np.empty(g)
    terms = np.empty(n)
    for k in range(g):
        c, m = centres[k], centres[k + 1] if k + 1 < g else n
        for i in range(m - c):
            terms[i] = rewards[c + i] * powers[i]
        out[k] = 0.0 + _pairwise_sum(terms, 0, m - c)
    return centres, out


@numba.njit(cache=True)
def _pairwise_sum(a, lo, n):
    """NumPy's pairwise sum of a[lo:lo + n] (numpy/_core/src/umath/loops_utils.h.src): blocks of up to 128 terms
    (``_block_sum``), a longer run the sum of its two halves (the first a multiple of 8 long). The halving is walked
    with a stack of its own: a recursive kernel cannot be loaded from Numba's cache."""
    if n <= 128:
        return _block_sum(a, lo, n)
    # frames of the halving, depth-first: start, length, stage (0: go left, 1: go right, 2: add), left half's sum
    starts, lengths, stage, left = np.empty(64, np.int64), np.empty(64, np.int64), np.zeros(64, np.int64), np.empty(64)
    top, ret = 0, 0.0
    starts[0], lengths[0] = lo, n
    while top >= 0:
        m = lengths[top]
        half = m // 2 - (m // 2) % 8
        if m <= 128 or stage[top] == 2:
            ret = _block_sum(a, starts[top], m) if m <= 128 else left[top] + ret
            top -= 1
            continue
        if stage[top] == 1:
            left[top] = ret
        stage[top] += 1
        starts[top + 1] = starts[top] + (half if stage[top] == 2 else 0)
        lengths[top + 1] = m - half if stage[top] == 2 else half
        stage[top + 1] = 0
        top += 1
    return ret


@numba.njit(cache=True)
def _block_sum(a, lo, n):
    """NumPy's sum of at most 128 terms: below 8 left to right, else eight interleaved sums, a fixed tree, the rest."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r = a[lo:lo + 8].copy()
    i = 8
    while i < n - n % 8:
        for k in range(8):
            r[k] += a[lo + i + k]
        i += 8
    res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    for k in range(i, n):
        res += a[lo + k]
    return res
