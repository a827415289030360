"""Guards of ``connrl run``: a lock against a second run into the same folder, and a Ray address that answers."""

from __future__ import annotations

import contextlib
import errno
import os
import socket
from pathlib import Path


class ExecutorError(RuntimeError):
    """The executor could not start (said in one line by the CLI)."""


CONNECT_TIMEOUT_S = 10.0


def check_reachable(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """A Ray address of the form [ray://]HOST:PORT must accept a TCP connection within ``timeout`` seconds (Ray
    itself retries a dead address for minutes, silently); ``ExecutorError`` in one line otherwise."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit() or not host:
        if address == "auto":
            return  # Ray finds the local cluster itself
        raise ExecutorError(f"--address must be HOST:PORT (e.g. 10.0.0.5:6379) or auto, got {address!r}")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except OSError as exc:
        raise ExecutorError(f"no Ray cluster answers at {address} within {timeout:g} s "
                            f"({exc.strerror or type(exc).__name__}); start one with `ray start --head` there, "
                            "or leave out --address to run on a local instance") from None


@contextlib.contextmanager
def run_lock(folder: Path):
    """Hold ``FOLDER/.connrl-run.lock`` while a run writes there: a second ``connrl run`` of the same experiment into
    the same folder is refused at once (``BlockingIOError`` in one line) instead of computing everything twice. The
    lock is the OS's (released even when the holder is killed); where ``fcntl`` is missing (Windows) there is none."""
    try:
        import fcntl
    except ImportError:
        yield
        return
    fd = os.open(folder / ".connrl-run.lock", os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise BlockingIOError(errno.EWOULDBLOCK, f"another connrl run is writing to {folder}; wait for it to "
                                  "finish (its finished runs are then reused) or give another --out") from None
        yield
    finally:
        os.close(fd)
