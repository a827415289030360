"""Guards of ``connrl run``: a lock against a second run into the same folder, and a Ray cluster that answers and
accepts this driver."""

from __future__ import annotations

import os
import socket
import subprocess
import sys

from connrl.storage import run_lock  # noqa: F401  (the runner's lock, re-exported)


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


_JOINED: set[str] = set()  # addresses whose cluster accepted this driver


def check_ray_cluster(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """The Ray cluster at ``address`` must accept this driver within ``timeout`` seconds; ``ExecutorError`` in one
    line otherwise (Ray itself retries a refused driver for 20 s, logging every attempt, then names no cause).

    ``ray start --head`` turns token authentication on when it finds a token (``~/.ray/auth_token``, which any local
    Ray start writes, or ``RAY_AUTH_TOKEN`` / ``RAY_AUTH_TOKEN_PATH``), but Ray sends none from a driver given an
    explicit address unless ``RAY_AUTH_MODE=token``. So, when ``RAY_AUTH_MODE`` is unset and a token is at hand, this
    sets it (as Ray does for ``address="auto"``); a cluster without authentication accepts the token too."""
    if address in _JOINED:
        return  # checked already in this process (the CLI checks before any run, the executor again)
    check_reachable(address)
    if address == "auto" or address.startswith("ray://"):
        return  # Ray finds the local cluster, and its auth, itself; Ray Client is not the GCS this probes
    # in a child: it can be killed at the timeout, Ray's own logs stay there, and this process need not load Ray
    with subprocess.Popen([sys.executable, "-c", _PROBE, address], stdout=subprocess.PIPE,
                          stderr=subprocess.DEVNULL, text=True) as probe:
        first = probe.stdout.readline().strip()  # once Ray is loaded: the timeout is the head's, not the import's
        try:
            said = probe.communicate(timeout=timeout)[0].strip()
        except subprocess.TimeoutExpired:
            probe.kill()
            raise ExecutorError(f"{address} accepts connections but does not answer as a Ray cluster's head within "
                                f"{timeout:g} s; give the address `ray start --head` printed (HOST:6379 by default)"
                                ) from None
    if not first:  # the probe could not even load Ray: ray.init's own errors are all there is
        return
    has_token = first == "token"
    if "RAY_AUTH_MODE" not in os.environ and has_token:
        os.environ["RAY_AUTH_MODE"] = "token"  # for ray.init here and the processes it starts, as in the probe
        if "ray._raylet" in sys.modules:  # Ray caches its settings: reread them, as Ray does when it turns tokens on
            sys.modules["ray._raylet"].Config.initialize("")
    if said == "ok":
        _JOINED.add(address)
        return
    if said == "auth":
        hint = "set RAY_AUTH_TOKEN to the head's token (`ray get-auth-token` there prints it)"
        mode = os.environ.get("RAY_AUTH_MODE", "")
        if mode.lower() not in ("", "token"):
            raise ExecutorError(f"the Ray cluster at {address} requires token authentication, but RAY_AUTH_MODE="
                                f"{mode} here; unset it" + ("" if has_token else f" and {hint}"))
        if not has_token:
            raise ExecutorError(f"the Ray cluster at {address} requires token authentication and this machine has "
                                f"no token; {hint}")
        raise ExecutorError(f"the Ray cluster at {address} refused this machine's token (RAY_AUTH_TOKEN, "
                            f"RAY_AUTH_TOKEN_PATH or ~/.ray/auth_token); {hint}")
    raise ExecutorError(f"cannot join the Ray cluster at {address}: {said or 'the connection check failed'}")


# Says whether a token is at hand ("token" / "none"; the same rule check_ray_cluster applies), then asks the head
# for its cluster ID, which is what a driver does first: "ok", "auth" or the error's first line. A Ray without
# token authentication has no AuthenticationTokenLoader: then it prints nothing.
_PROBE = """
import os, sys
from ray._raylet import AuthenticationTokenLoader, Config, GcsClient
from ray.exceptions import AuthenticationError
has_token = AuthenticationTokenLoader.instance().has_token(ignore_auth_mode=True)
if "RAY_AUTH_MODE" not in os.environ and has_token:
    os.environ["RAY_AUTH_MODE"] = "token"
    Config.initialize("")
print("token" if has_token else "none", flush=True)
try:
    GcsClient(address=sys.argv[1])
except AuthenticationError:
    print("auth")
except Exception as exc:
    print(type(exc).__name__ + ": " + (str(exc).strip().splitlines() or [""])[0])
else:
    print("ok")
"""

