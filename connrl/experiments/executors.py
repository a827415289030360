"""Where runs execute: in this process, in worker processes, or as Ray tasks; and the live display of a pool of runs,
with its ETA from the runs' expected times.

Each executor takes the whole list of jobs and yields ``(job, result)`` as each finishes, in any order; jobs start in
the order given (``connrl reproduce`` gives them longest first, so no long run starts last while a core sits idle).
"""

from __future__ import annotations

import multiprocessing as mp
import os
import queue
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any, Protocol

from connrl.experiments.guards import ExecutorError, check_ray_cluster


class Executor(Protocol):
    """Runs ``fn(job)`` for every job, yields ``(job, result)`` as each finishes, calls ``tick()`` often."""

    def map_unordered(self, fn: Callable, jobs: list[Any],
                      tick: Callable[[], None]) -> Iterator[tuple[Any, Any]]: ...


_progress_queue = None
_progress_tick: Callable[[], None] | None = None


def _init_worker(q, tick=None, parent: int | None = None):
    global _progress_queue, _progress_tick
    _progress_queue, _progress_tick = q, tick
    if parent is not None:
        threading.Thread(target=_exit_with_parent, args=(parent,), daemon=True).start()


def _exit_with_parent(parent: int) -> None:
    """A worker whose parent died (e.g. SIGKILL, which runs no cleanup) exits instead of running on: the
    parent is gone when this process has been handed to another (init or a subreaper)."""
    while True:
        time.sleep(0.5)
        if os.getppid() != parent:
            os._exit(1)


class SerialExecutor:
    """Runs jobs one after another in this process (used with --workers 1 and in tests)."""

    def __init__(self, progress_queue=None):
        self.q = progress_queue

    def map_unordered(self, fn, jobs, tick):
        _init_worker(self.q, tick)
        try:
            for job in jobs:
                yield job, fn(job)
        finally:
            _init_worker(None)


class ProcessExecutor:
    """Independent runs in worker processes (default: one per core)."""

    def __init__(self, workers: int, progress_queue=None):
        self.workers = workers
        self.q = progress_queue

    def map_unordered(self, fn, jobs, tick):
        ctx = mp.get_context("spawn")  # fresh interpreters: no inherited state, same on every OS
        pool = ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=_init_worker,
                                   initargs=(self.q, None, os.getpid()))
        pending: dict[Future, Any] = {}
        it = iter(jobs)
        try:
            for job in it:
                pending[pool.submit(fn, job)] = job
                if len(pending) >= 2 * self.workers:
                    break
            while pending:
                done, _ = wait(pending, timeout=0.25, return_when=FIRST_COMPLETED)
                tick()
                for fut in done:
                    job = pending.pop(fut)
                    yield job, fut.result()
                    nxt = next(it, None)
                    if nxt is not None:
                        pending[pool.submit(fn, nxt)] = nxt
        except BaseException:
            # Ctrl-C (or any error): stop the runs in flight instead of finishing them; what finished is saved
            procs = list(getattr(pool, "_processes", {}).values())  # no public handle on the workers
            for proc in procs:
                proc.terminate()
            for proc in procs:  # a worker that does not go within 5 s is killed: shutdown below waits for them all
                proc.join(timeout=5)
                if proc.is_alive():
                    proc.kill()
            raise
        finally:
            for fut in pending:
                fut.cancel()
            pool.shutdown(wait=True, cancel_futures=True)


class RayExecutor:
    """Runs as Ray tasks (``--executor ray``): on a local Ray instance started here, or on the cluster at ``address``
    (``ray start --head`` on one machine, ``ray start --address=HEAD:6379`` on the others; ``--address HEAD:6379``
    here). ``fn(job)`` runs as a task and its result comes back here (``runner.execute`` gives it ``run_job``, which
    writes nothing, and writes the records itself, so the cluster needs no shared disk)."""

    def __init__(self, workers: int, address: str | None = None):
        self.workers, self.address = workers, address

    def map_unordered(self, fn, jobs, tick):
        import ray

        started = not ray.is_initialized()
        if started and self.address:
            check_ray_cluster(self.address)  # answers, and takes this driver's token if it wants one
        if started:  # "local": a fresh instance here, whatever RAY_ADDRESS says; else the cluster at address
            try:
                ray.init(address=self.address or "local", num_cpus=None if self.address else self.workers,
                         include_dashboard=False, log_to_driver=False, configure_logging=False)
            except Exception as exc:  # unreachable address, a cluster refusing num_cpus, ...: one line
                raise ExecutorError(f"cannot start or reach Ray at {self.address or 'a local instance'}: "
                                    f"{type(exc).__name__}: {exc}") from None
        task = ray.remote(num_cpus=1)(fn)
        pending = {task.remote(job): job for job in jobs}
        try:
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1, timeout=0.25)
                tick()
                for ref in done:
                    job = pending.pop(ref)
                    yield job, ray.get(ref)
        except BaseException:
            for ref in pending:  # Ctrl-C or an error: stop the runs in flight; what finished is saved
                ray.cancel(ref, force=True)
            raise
        finally:
            if started:
                ray.shutdown()


EXECUTORS = ("process", "ray")


def check_executor(executor: str) -> None:
    """Refuse an unknown executor, or Ray when it is not installed, in one line before any run."""
    if executor not in EXECUTORS:
        raise ValueError(f"unknown executor {executor!r}; available: {', '.join(EXECUTORS)}")
    if executor == "ray":
        import importlib.util
        if importlib.util.find_spec("ray") is None:
            raise ValueError("--executor ray needs Ray: pip install -e \".[ray]\" (or pip install ray)")


class Progress:
    """A rich live display: one bar for the pool, with an ETA, and one bar per run in flight.

    ``expected`` gives each job's expected seconds (by its path); the ETA is the expected time of what is left over
    the workers (never less than the longest run left), scaled by how the finished runs compared with their
    expectation (the machine's speed). With ``calibrated`` False the expected times are only relative (another
    profile's), so no ETA is shown until a run has finished."""

    def __init__(self, jobs: Iterable[Any], title: str, expected: dict[str, float] | None = None, workers: int = 1,
                 calibrated: bool = True):
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        self.jobs = {j.path: j for j in jobs}
        self.expected = expected or {p: 1.0 for p in self.jobs}
        self.workers, self.calibrated = max(workers, 1), calibrated
        self.fraction: dict[str, float] = {}  # of each run in flight
        self.took, self.planned = 0.0, 0.0  # actual and expected seconds of the finished runs
        self.progress = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                                 TimeElapsedColumn(), TextColumn("{task.fields[eta]}"), transient=False)
        self.total = self.progress.add_task(f"{title}: runs", total=len(self.jobs), eta=self.eta_text())
        self.tasks: dict[str, int] = {}

    def eta_seconds(self) -> float | None:
        if not self.calibrated and self.planned == 0:
            return None
        speed = self.took / self.planned if self.planned > 0 else 1.0
        left = [self.expected.get(p, 0.0) * (1.0 - self.fraction.get(p, 0.0)) for p in self.jobs]
        return speed * max(sum(left) / self.workers, max(left, default=0.0))  # no sooner than the longest run left

    def eta_text(self) -> str:
        eta = self.eta_seconds()
        return "" if eta is None else f"ETA {int(eta // 3600)}:{int(eta % 3600 // 60):02d}:{int(eta % 60):02d}"

    def start(self):
        self.progress.start()

    def stop(self):
        self.progress.stop()

    def drain(self, q):
        while q is not None:
            try:
                path, done, total = q.get_nowait()
            except (queue.Empty, EOFError, OSError):
                break
            if path not in self.jobs:
                continue
            if path not in self.tasks:
                j = self.jobs[path]
                self.tasks[path] = self.progress.add_task(f"  {j.experiment}: {j.variant} seed {j.seed}", total=total,
                                                          eta="")
            self.progress.update(self.tasks[path], completed=done, total=total)
            self.fraction[path] = done / total if total else 0.0
        self.progress.update(self.total, eta=self.eta_text())

    def finish(self, job, wall: float | None = None):
        if wall is not None and job.path in self.expected:
            self.took += wall
            self.planned += self.expected[job.path]
        self.jobs.pop(job.path, None)
        self.fraction.pop(job.path, None)
        self.progress.advance(self.total)
        self.progress.update(self.total, eta=self.eta_text())
        if job.path in self.tasks:
            self.progress.remove_task(self.tasks.pop(job.path))
