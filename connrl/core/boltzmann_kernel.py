"""Eq. 3.4's stochastic choice inside a compiled loop, with the numbers of ``boltzmann_select`` (issue 45).

A training step's choice is ``boltzmann_select(merits, T, rng)``: ``p = exp((m - max m) / T)``, ``p /= p.sum()``,
then the first action whose cumulative probability exceeds one uniform draw. To compile a whole training trial the
choice must be compiled too, and give the same action from the same draw, bit for bit:

* NumPy computes ``exp`` with its own vector loop, which differs from libm's (what ``math.exp`` calls inside Numba)
  in the last bit for some inputs (one in twenty here). ``_numpy_exp`` therefore calls NumPy's own loop: the
  ``d->d`` inner loop of the ``np.exp`` ufunc, read from the ufunc's C struct and checked at import against
  ``np.exp`` on test inputs (``numpy_exp_checked``). Where it cannot be found or does not agree, callers keep the
  Python path.
* ``p.sum()`` of fewer than 8 numbers is NumPy's plain loop from 0 (8 or more are summed pairwise): the kernel
  takes fewer than 8 merits (``compiled_choice_fits``).
* The uniform draw is the Generator's ``random()``: Numba shares the Generator's state, so the stream is the same.

The kernel is not cached: it holds the address of NumPy's loop, which is only known in the running process.
"""

from __future__ import annotations

import ctypes
from functools import cache

import numba
import numpy as np

from connrl.core.exploration import boltzmann_select, weighted_boltzmann_probabilities

# PyUFuncObject (numpy/ufuncobject.h): after PyObject_HEAD (16 bytes) and four ints come ``functions`` (the inner
# loops), ``data``, ``ntypes``, two more fields, then ``types`` (each loop's nargs type numbers).
_FUNCTIONS, _NTYPES, _TYPES = 32, 48, 64
_LOOP = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)


def _ufunc_loop(ufunc: np.ufunc, signature: str):
    """(the inner loop of ``ufunc`` for ``signature``, e.g. ``"dd"``, and its data pointer), or None where the struct
    is not as read."""
    address = id(ufunc)
    ntypes = ctypes.c_int.from_address(address + _NTYPES).value
    if ntypes != len(ufunc.types) or ufunc.nargs != len(signature):
        return None
    types = ctypes.cast(ctypes.c_void_p.from_address(address + _TYPES).value, ctypes.POINTER(ctypes.c_ubyte))
    want = [np.dtype(c).num for c in signature]
    for i, written in enumerate(ufunc.types):
        found = [types[i * ufunc.nargs + j] for j in range(ufunc.nargs)]
        if found != [np.dtype(c).num for c in written.replace("->", "")]:
            return None  # the struct's types do not read as the ufunc's own list: another layout
        if found == want:
            size = ctypes.sizeof(ctypes.c_void_p)
            functions = ctypes.c_void_p.from_address(address + _FUNCTIONS).value
            data = ctypes.c_void_p.from_address(address + _FUNCTIONS + size).value
            loop_data = ctypes.c_void_p.from_address(data + size * i).value if data else None
            return _LOOP(ctypes.c_void_p.from_address(functions + size * i).value), loop_data or 0
    return None


_exp_loop = _ufunc_loop(np.exp, "dd")
# never called unless numpy_exp_checked()
_EXP, _EXP_DATA = _exp_loop if _exp_loop is not None else (_LOOP(0), 0)


@numba.njit(cache=False)
def _numpy_exp(z, out, scratch):
    """out[:] = np.exp(z) by NumPy's own loop; ``scratch`` is int64 (5,): the loop's arguments, size and strides."""
    scratch[0], scratch[1] = z.ctypes.data, out.ctypes.data
    scratch[2], scratch[3], scratch[4] = z.size, 8, 8
    base = scratch.ctypes.data
    _EXP(base, base + 16, base + 24, _EXP_DATA)


@numba.njit(cache=False)
def _nanmax(q, n):
    """``q[:n].max()`` as NumPy gives it: a NaN propagates."""
    top = q[0]
    for k in range(1, n):
        if top != top:
            break
        if q[k] > top or q[k] != q[k]:
            top = q[k]
    return top


@numba.njit(cache=False)
def _probabilities(q, w, temperature, p, scratch):
    """p[:] = ``boltzmann_probabilities(q, temperature)`` (``w`` empty) or ``weighted_boltzmann_probabilities(q, w,
    temperature)`` (Eq. 6.6: a weight of 0 rules a choice out), as NumPy computes them, for ``temperature > 0`` and
    ``q.size < 8``. A NaN merit (among the allowed) makes every entry NaN. The compiled choice's one probability."""
    n = q.size
    weighted = w.size > 0
    top, seen = 0.0, False
    for k in range(n):  # q.max(), or q[w > 0].max(): a NaN propagates
        if (not weighted or w[k] > 0) and (not seen or q[k] > top or q[k] != q[k]) and top == top:
            top, seen = q[k], True
    for k in range(n):
        p[k] = (q[k] - top) / temperature
    _numpy_exp(p, p, scratch)
    total = 0.0
    for k in range(n):  # weighted: np.where(w > 0, w * exp, 0.0); summed by NumPy's plain loop
        if weighted:
            p[k] = w[k] * p[k] if w[k] > 0 else 0.0
        total += p[k]
    for k in range(n):
        p[k] /= total


@numba.njit(cache=False)
def _boltzmann_choice(q, temperature, rng, p, scratch):
    """``boltzmann_select(q, temperature, rng)`` for ``temperature > 0`` and ``q.size < 8``: returns the action, p
    its probabilities. NaN merits give action 0, as ``searchsorted`` of the NaN distribution does."""
    _probabilities(q, q[:0], temperature, p, scratch)
    u = rng.random() * 1.0
    acc = 0.0
    for k in range(q.size):  # searchsorted(cumsum, u, "right"): the first sum above u (a NaN sorts above everything)
        acc = p[k] if k == 0 else acc + p[k]
        if not acc <= u:
            return k
    return q.size - 1


@numba.njit(cache=False)
def _weighted_choice(q, w, temperature, rng, p, scratch):
    """Eq. 6.6's draw as ``BehaviourChoice.choose`` makes it for ``temperature > 0`` and ``q.size < 8``:
    ``p = weighted_boltzmann_probabilities(q, w, temperature)``, then ``rng.choice(q.size, p=p)``, i.e. the cumulative
    sum divided by its last element and the first entry above one uniform draw. Returns the choice, or -1 without a
    draw where ``p`` holds a NaN (``rng.choice`` refuses it: "Probabilities contain NaN")."""
    n = q.size
    _probabilities(q, w, temperature, p, scratch)
    for k in range(n):
        if p[k] != p[k]:
            return -1
    last = 0.0
    for k in range(n):
        last += p[k]
    u = rng.random()
    acc = 0.0
    for k in range(n):
        acc += p[k]
        if acc / last > u:
            return k
    return n - 1


def compiled_choice_fits(n_actions: int) -> bool:
    """Whether ``_boltzmann_choice`` gives ``boltzmann_select``'s numbers for this many actions: NumPy's loop found,
    and the choice checked against ``boltzmann_select`` once per process (which compiles the kernels)."""
    return 1 <= n_actions < 8 and numpy_exp_checked() and choice_checked()


@cache
def numpy_exp_checked() -> bool:
    """NumPy's loop, called as the kernel calls it (in place too), against ``np.exp`` on inputs of every size the
    kernel takes."""
    if _exp_loop is None:
        return False
    z = np.linspace(-745.0, 0.0, 7919)
    z[1::3] = -np.geomspace(1e-300, 700.0, z[1::3].size)
    out, scratch = np.empty_like(z), np.zeros(5, np.int64)
    for n in (1, 4, 7, z.size):
        _numpy_exp(z[:n], out[:n], scratch)
        if not np.array_equal(out[:n], np.exp(z[:n])):
            return False
    inplace = z.copy()
    _numpy_exp(inplace, inplace, scratch)
    return np.array_equal(inplace, np.exp(z))


def weighted_choice_fits(n_choices: int) -> bool:
    """Whether ``_weighted_choice`` gives ``BehaviourChoice.choose``'s numbers for this many choices (as
    ``compiled_choice_fits``)."""
    return 1 <= n_choices < 8 and numpy_exp_checked() and weighted_checked()


@cache
def weighted_checked() -> bool:
    """``_weighted_choice`` against ``weighted_boltzmann_probabilities`` and ``Generator.choice`` on 2000 draws of 1 to
    7 choices with weights 0, 1 and 100 (Eq. 6.6's), at least one above 0."""
    data, rng, ref = np.random.default_rng(66), np.random.default_rng(67), np.random.default_rng(67)
    scratch = np.zeros(5, np.int64)
    for i in range(2000):
        n = 1 + i % 7
        q, t, p = data.normal(0.0, 50.0, n), 10.0 ** data.uniform(-1.0, 2.0), np.empty(n)
        w = data.choice(np.array([0.0, 1.0, 100.0]), n)
        w[data.integers(n)] = data.choice(np.array([1.0, 100.0]))
        b = _weighted_choice(q, w, t, rng, p, scratch)
        with np.errstate(over="ignore", invalid="ignore"):  # an excluded choice's exp may overflow; it is not used
            want_p = weighted_boltzmann_probabilities(q, w, t)
        if b != int(ref.choice(n, p=want_p)) or not np.array_equal(p, want_p):
            return False
    return True


@cache
def choice_checked() -> bool:
    """``_boltzmann_choice`` against ``boltzmann_select`` (the sum's and the cumulative sum's order are NumPy's
    build's) on 2000 draws of 1 to 7 merits."""
    data, rng, ref = np.random.default_rng(45), np.random.default_rng(46), np.random.default_rng(46)
    scratch = np.zeros(5, np.int64)
    for i in range(2000):
        n = 1 + i % 7
        q, t, p = data.normal(0.0, 1.0, n), 10.0 ** data.uniform(-3.0, 1.0), np.empty(n)
        a = _boltzmann_choice(q, t, rng, p, scratch)
        want, want_p = boltzmann_select(q, t, ref)
        if a != want or not np.array_equal(p, want_p):
            return False
    return True
