"""The sum order of ``connrl.nets.kernels._dot_kernel`` written out one lane at a time in scalars: the independent
reference its vector IR is held to (tests/nets/test_rotated_kernel.py, tests/nets/test_mlp_kernel.py)."""

from __future__ import annotations

import numba
import numpy as np

from connrl.nets.kernels import _fma


def stored_results_cpu() -> bool:
    """Whether this is the CPU the stored results were made on (znver5), where the old fastmath loops summed in the
    written-out order, so the kernels must match them bit for bit."""
    import os

    from llvmlite import binding

    return (os.environ.get("NUMBA_CPU_NAME") or binding.get_host_cpu_name()) == "znver5"


@numba.njit(cache=False)
def lanes_one_at_a_time(w, x, n, start, width):
    """``start + sum w[i] x[i]`` over i < n: 32 lanes over blocks of 32 (``start`` in lane 0), lane k of the four
    8-lane accumulators added (0 + 1) + (2 + 3), then the 8 lanes' halves; ``width`` lanes over the blocks left
    (the sum so far in lane 0), their halves added the same way; then one at a time."""
    acc = np.zeros(32)
    s, i = start, 0
    if n >= 32:
        acc[0] = start
        while i < (n & ~31):
            for lane in range(32):
                acc[lane] = _fma(x[i + lane], w[i + lane], acc[lane])
            i += 32
        v = np.array([(acc[k] + acc[8 + k]) + (acc[16 + k] + acc[24 + k]) for k in range(8)])
        s = ((v[0] + v[4]) + (v[2] + v[6])) + ((v[1] + v[5]) + (v[3] + v[7]))
    if n - i >= width:
        acc[:width] = 0.0
        acc[0] = s
        while i < (n & ~(width - 1)):
            for lane in range(width):
                acc[lane] = _fma(x[i + lane], w[i + lane], acc[lane])
            i += width
        if width == 8:
            s = ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]))
        else:
            s = (acc[0] + acc[2]) + (acc[1] + acc[3])
    while i < n:
        s = _fma(x[i], w[i], s)
        i += 1
    return s
