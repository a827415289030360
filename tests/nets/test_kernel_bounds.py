"""Compiled kernels index without bounds checks; a buffer one row short corrupts memory silently (or crashes a
run much later). This runs the compiled-against-reference tests of the recurrent replay kernel again with Numba's
bounds checking on and a fresh cache, so such a write fails here instead."""

import os
import subprocess
import sys
from pathlib import Path


def test_recurrent_replay_kernel_stays_in_bounds(tmp_path):
    env = dict(os.environ, NUMBA_BOUNDSCHECK="1", NUMBA_CACHE_DIR=str(tmp_path))
    root = Path(__file__).resolve().parents[2]
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                           "tests/agents/test_memory.py", "-k", "compiled_recurrent_replay"],
                          cwd=root, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
