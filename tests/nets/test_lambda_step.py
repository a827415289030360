"""Fig. 5.1's step 4 is written once in Python (``connrl.core.returns.td_lambda_target``, the oracle) and once
compiled (``connrl.nets.kernels._lambda_target``), and every compiled replay calls the compiled one."""

import ast
import inspect
from pathlib import Path

import numpy as np

from connrl.core.returns import td_lambda_target
from connrl.nets import kernels


def test_the_compiled_step_is_the_pure_function_to_the_bit():
    rng = np.random.default_rng(5)
    for _ in range(2000):
        r, u, e_next = rng.choice([0.0, -1.0, 100.0, 0.37]), rng.normal(0, 50), rng.normal(0, 50)
        gamma, lam, clip = rng.uniform(0, 1), rng.choice([0.0, 0.7, rng.uniform(0, 1)]), rng.normal(0, 50)
        want = td_lambda_target(r, u, e_next, gamma, lam)
        assert kernels._lambda_target(r, gamma, lam, u, e_next, 0.0, False) == want
        assert kernels._lambda_target(r, gamma, lam, u, e_next, clip, True) == min(want, clip)


def test_every_compiled_replay_calls_the_one_step():
    """No kernel writes the recursion r + gamma ((1 - lam) u + lam e') itself: a second copy could drift."""
    tree = ast.parse(Path(kernels.__file__).read_text())
    callers, copies = set(), []
    for fn in (n for n in tree.body if isinstance(n, ast.FunctionDef)):
        for node in ast.walk(fn):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "_lambda_target":
                callers.add(fn.name)
            if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Sub) and \
                    isinstance(node.left, ast.Constant) and node.left.value == 1.0 and fn.name != "_lambda_target":
                copies.append(f"{fn.name}: {ast.unparse(node)}")
    assert not copies, copies
    assert {"_replay_q_steps", "_replay_mlp", "_replay_rotated_kernel", "_replay_ahc_rotated_kernel",
            "_replay_recurrent_lesson"} <= callers
    assert "(1.0 - lam" not in inspect.getsource(kernels._replay_mlp)
