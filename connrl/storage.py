"""Atomic writes of plain formats (JSON, CSV, NPZ without pickle): a reader never sees half a file."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np


def _tmp_for(path: Path) -> Path:
    return path.with_name(f".{path.name}.{os.getpid()}.tmp")


def atomic_write_bytes(path, data: bytes) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _tmp_for(path)
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def atomic_write_text(path, text: str) -> None:
    atomic_write_bytes(path, text.encode())


def atomic_save_npz(path, **arrays: np.ndarray) -> None:
    """NPZ holding numeric arrays only; read it back with ``np.load(path, allow_pickle=False)``."""
    buf = io.BytesIO()
    np.savez(buf, **{k: np.asarray(v) for k, v in arrays.items()})
    atomic_write_bytes(path, buf.getvalue())


def check_writable_dir(path) -> None:
    """Make sure ``path`` is (or can become) a folder we can write in, before any work is done; ``OSError``
    with a plain reason otherwise."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise NotADirectoryError(f"{path} is a file, not a folder")
    path.mkdir(parents=True, exist_ok=True)
    probe = path / f".connrl-write-test-{os.getpid()}"
    try:
        probe.write_bytes(b"")
    finally:
        probe.unlink(missing_ok=True)
