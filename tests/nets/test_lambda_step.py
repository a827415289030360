"""Fig. 5.1's step 4 is written once in Python (``connrl.core.returns.td_lambda_target``, the oracle) and, in the
compiled kernels, once for each of its two roundings: ``_lambda_target`` (the oracle's, for the kernels compiled
without fastmath) and ``_lambda_target_fused`` (the same expression compiled with fastmath: the OAON replay's, whose
stored results hold it). No kernel writes the recursion itself, and neither step's bits depend on which kernel a
process compiles first."""

import ast
import os
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np

from connrl.core.returns import td_lambda_target
from connrl.nets import kernels

from .lanes import stored_results_cpu

SOURCE = ast.parse(Path(kernels.__file__).read_text())
FUNCTIONS = {n.name: n for n in SOURCE.body if isinstance(n, ast.FunctionDef)}
# plain kernels whose arithmetic does not change when a fastmath kernel inlines them: explicit FMAs, a fixed order
FLAG_PROOF = {"_fma", "_dot_in_fours", "_forward_at"}


def _fma(a, b, c) -> float:
    """a b + c rounded once, from exact rationals (an oracle independent of the CPU's FMA)."""
    return float(Fraction(a) * Fraction(b) + Fraction(c))


def _draws(n, seed=5):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield (float(rng.choice([0.0, -1.0, 100.0, 0.37])), rng.uniform(0, 1), float(rng.choice([0.0, 0.7, 1.0])),
               rng.normal(0, 50), rng.normal(0, 50), rng.normal(0, 50))


def test_the_plain_step_is_the_pure_function_to_the_bit():
    for r, gamma, lam, u, e_next, clip in _draws(2000):
        want = td_lambda_target(r, u, e_next, gamma, lam)
        assert kernels._lambda_target(r, gamma, lam, u, e_next, 0.0, False) == want
        assert kernels._lambda_target(r, gamma, lam, u, e_next, clip, True) == min(want, clip)


def test_the_fastmath_step_is_two_fused_multiply_adds_of_the_same_return():
    """What fastmath makes of the expression on this machine's CPU (the stored results' form): u + lam (e' - u) and
    the discounted sum, each one fused multiply-add."""
    exact = stored_results_cpu()  # elsewhere LLVM may fuse otherwise, or not at all: close, not equal
    for r, gamma, lam, u, e_next, clip in _draws(2000, seed=6):
        want = _fma(gamma, _fma(lam, e_next - u, u), r)
        got = kernels._lambda_target_fused(r, gamma, lam, u, e_next, 0.0, False)
        plain = td_lambda_target(r, u, e_next, gamma, lam)
        assert got == want if exact else abs(got - plain) <= 8 * np.spacing(max(abs(plain), abs(u), abs(e_next), 1.0))
        assert kernels._lambda_target_fused(r, gamma, lam, u, e_next, clip, True) == min(got, clip)
        assert abs(want - plain) <= 4 * np.spacing(max(abs(plain), abs(u), abs(e_next), abs(r)))


def _fastmath(fn: ast.FunctionDef) -> bool:
    return any("fastmath=True" in ast.unparse(d) for d in fn.decorator_list)


def _inlined(fn: ast.FunctionDef) -> bool:
    """Inlined at Numba's IR: compiled inside each caller with that caller's flags, never on its own for it."""
    return any("inline='always'" in ast.unparse(d) for d in fn.decorator_list)


def _calls(fn: ast.FunctionDef) -> set[str]:
    return {c.func.id for c in ast.walk(fn) if isinstance(c, ast.Call) and isinstance(c.func, ast.Name)
            and c.func.id in FUNCTIONS}


def test_every_replay_calls_a_step_and_none_writes_the_recursion():
    copies = [f"{name}: {ast.unparse(node)}" for name, fn in FUNCTIONS.items() if not name.startswith("_lambda_target")
              for node in ast.walk(fn) if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Sub)
              and isinstance(node.left, ast.Constant) and node.left.value == 1.0]
    assert not copies, copies
    fused = {name for name, fn in FUNCTIONS.items() if "_lambda_target_fused" in _calls(fn)}
    plain = {name for name, fn in FUNCTIONS.items() if "_lambda_target" in _calls(fn)}
    assert fused == {"_replay_q_steps", "_replay_mlp"}
    assert plain == {"_replay_rotated_kernel", "_replay_ahc_rotated_kernel", "_replay_recurrent_lesson"}


def test_a_fastmath_kernel_calls_only_fastmath_or_flag_proof_kernels():
    """Numba compiles a plain kernel that a fastmath one calls first with the caller's flags (and caches it so):
    such a callee's bits would depend on which kernel a process compiled first. An inlined kernel is no such callee:
    each caller compiles its own copy, with its own flags."""
    bad = [f"{name} -> {callee}" for name, fn in FUNCTIONS.items() if _fastmath(fn) for callee in _calls(fn)
           if not (_fastmath(FUNCTIONS[callee]) or _inlined(FUNCTIONS[callee])) and callee not in FLAG_PROOF]
    assert not bad, bad


def args_of(r, gamma, lam, u, e_next):
    return r, gamma, lam, u, e_next, 0.0, False


def test_the_steps_bits_do_not_depend_on_which_kernel_compiled_first(tmp_path):
    """A fresh process with an empty kernel cache compiles the fastmath OAON replay first, then the plain step."""
    code = ("import numpy as np\n"
            "from connrl.core.lessons import Lesson\nfrom connrl.core.replay import ReplayParams\n"
            "from connrl.core.replay_kernel import replay_oaon\nfrom connrl.nets import OAON, NetConfig\n"
            "from connrl.nets import kernels\n"
            "rng = np.random.default_rng(0)\n"
            "lesson = Lesson(rng.uniform(-1, 1, (6, 3)), rng.integers(0, 2, 5), rng.normal(0, 1, 5),\n"
            "                terminated=True)\n"
            "net = OAON(NetConfig(3, 2, value_range=1.0, init_range=0.5, lr=0.1), 2, rng)\n"
            "replay_oaon(net, lesson, ReplayParams(gamma=0.9, lam=0.7))\n"
            "args = (0.37, 0.19402547600704456, 0.7, -1.0611730208644898, 30.460824641637036)\n"
            "print(repr(kernels._lambda_target(*args, 0.0, False)),\n"
            "      repr(kernels._lambda_target_fused(*args, 0.0, False)))")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True).stdout
    r, gamma, lam, u, e_next = 0.37, 0.19402547600704456, 0.7, -1.0611730208644898, 30.460824641637036
    plain, fused = out.split()
    assert plain == repr(td_lambda_target(r, u, e_next, gamma, lam))
    assert fused == repr(kernels._lambda_target_fused(*args_of(r, gamma, lam, u, e_next)))  # this process's compile
    if stored_results_cpu():
        assert fused == repr(_fma(gamma, _fma(lam, e_next - u, u), r))
