"""Independent tasks on the local process pool (the default) or as Ray tasks (`--ray [ADDRESS]`).

A task is a picklable value; `fn(state, task)` runs it with a per-process state (a simulator, say) that
`setup(*setup_args)` builds once in each worker process, and returns a picklable result. Results come back
to the driver as tasks finish, in any order, and the driver alone writes files. Ray is imported only when a
Ray backend runs (`pip install -e ".[cluster]"`); the default install does not need it.

A Ray task whose worker process dies (killed, out of memory, a lost node) is retried up to RAY_MAX_RETRIES
times; an exception raised by the task itself is not retried and is re-raised on the driver as raised, the
same error as with the local pool.
"""

from __future__ import annotations

import itertools
import logging
import multiprocessing
import os
import socket
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from functools import partial
from typing import Any

from homer_sim.errors import HomerError

log = logging.getLogger(__name__)

RAY_LOCAL = "local"
"""The `--ray` value that starts a Ray instance on this machine (what `--ray` without an address means)."""
RAY_MAX_RETRIES = 3  # reruns of a task whose worker process died; a task's own exception is never retried
IN_FLIGHT_PER_CPU = 2  # Ray tasks submitted but not yet collected, per cluster CPU (bounds work lost to Ctrl-C)
WAIT_S = 0.5  # s the driver blocks in one ray.wait, so that Ctrl-C is handled promptly


class ExecutionError(HomerError):
    """The execution backend is misconfigured or lost a task for good (not an error of the task itself)."""


@dataclass(frozen=True)
class Backend:
    """Where tasks run: `workers` local processes (1: in this process), or Ray at `ray`.

    ray: None for the local pool; "local" starts Ray on this machine; "auto" joins the cluster this machine
    belongs to; "ray://HOST:PORT" (Ray Client) or "HOST:PORT" (the head's GCS) joins a remote one.
    """

    workers: int = 1
    ray: str | None = None

    def __post_init__(self) -> None:
        if self.workers < 1:
            raise ExecutionError(f"workers must be at least 1, not {self.workers}")
        if self.ray is not None:
            check_ray_address(self.ray)
            if self.workers != 1:
                raise ExecutionError(f"--workers {self.workers} sizes the local pool; with --ray the cluster's "
                                     "CPUs set how many tasks run at once (drop --workers)")

    def run(self, fn: Callable[[Any, Any], Any], tasks: Iterable, setup: Callable[..., Any],
            setup_args: tuple = (), local_state: Any = None, cpus_per_task: int = 1) -> TaskRun:
        """A `TaskRun` of `fn` over `tasks` on this backend (see `TaskRun`)."""
        return TaskRun(self, fn, tasks, setup, setup_args, local_state, cpus_per_task)


IN_PROCESS = Backend()
"""The default backend: every task in the calling process, one after the other."""


def check_ray_address(address: str) -> str:
    """`address` if it is a valid `--ray` value, else an ExecutionError naming the valid forms."""
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if address in (RAY_LOCAL, "auto") or (host and port.isdigit()):
        return address
    raise ExecutionError(f"--ray {address!r}: expected nothing (start Ray here), 'auto' (join this machine's "
                         "cluster), 'ray://HOST:PORT' or 'HOST:PORT'")


# --- running ----------------------------------------------------------------------------------------------
_NO_TASK = object()
_STATE: tuple[tuple, Any] | None = None  # (setup, setup_args) and the state it built, in this worker process


def _call(fn: Callable, setup: Callable, setup_args: tuple, task: Any) -> tuple[str, Any]:
    """Run one task in a worker process, building the process's state on its first task; returns (worker,
    result), the worker named host:pid."""
    global _STATE
    if _STATE is None or _STATE[0] != (setup, setup_args):
        _STATE = ((setup, setup_args), setup(*setup_args))
    return f"{socket.gethostname()}:{os.getpid()}", fn(_STATE[1], task)


class TaskRun:
    """One run of `fn` over `tasks`: iterate for the results as they finish; use as a context manager so that
    Ctrl-C or an error cancels what is still running (and stops a Ray instance the run started).

    With one local worker the tasks run in this process on `local_state` (or a state built by `setup`);
    `cpus_per_task` is what a Ray task reserves (a training run's threads, say). After the run, `usage()` tells
    where the tasks ran.
    """

    def __init__(self, backend: Backend, fn: Callable[[Any, Any], Any], tasks: Iterable, setup: Callable[..., Any],
                 setup_args: tuple, local_state: Any, cpus_per_task: int) -> None:
        self.backend, self.fn, self.tasks, self.cpus_per_task = backend, fn, tasks, cpus_per_task
        self.setup, self.setup_args, self.local_state = setup, setup_args, local_state
        self.workers: set[str] = set()
        self._ray_started = False
        self._cluster_cpus: float | None = None
        self._results: Iterator[Any] | None = None

    def __enter__(self) -> TaskRun:
        return self

    def __exit__(self, *exc_info: object) -> None:
        if self._results is not None:  # cancels what is still running (see _pool and _ray)
            self._results.close()
        if self._ray_started:
            import ray

            ray.shutdown()
            self._ray_started = False

    def __iter__(self) -> Iterator[Any]:
        queue = iter(self.tasks)
        first = next(queue, _NO_TASK)
        if first is _NO_TASK:  # nothing to do: no pool, no Ray
            self._results = _nothing()
        else:
            queue = itertools.chain([first], queue)
            if self.backend.ray is not None:
                self._results = self._ray(queue)
            else:
                self._results = self._in_process(queue) if self.backend.workers == 1 else self._pool(queue)
        return self._results

    def usage(self) -> dict:
        """{"mode": "local" | "ray", "address", "workers": processes that ran tasks, "nodes": their hosts,
        "cluster_cpus" (Ray only)}."""
        usage = {"mode": "ray" if self.backend.ray is not None else "local", "address": self.backend.ray,
                 "workers": len(self.workers), "nodes": len({w.rpartition(":")[0] for w in self.workers})}
        if self._cluster_cpus is not None:
            usage["cluster_cpus"] = self._cluster_cpus
        return usage

    def _in_process(self, queue: Iterator) -> Iterator[Any]:
        state = self.local_state if self.local_state is not None else self.setup(*self.setup_args)
        for task in queue:
            result = self.fn(state, task)
            self.workers.add(f"{socket.gethostname()}:{os.getpid()}")
            yield result

    def _pool(self, queue: Iterator) -> Iterator[Any]:
        call = partial(_call, self.fn, self.setup, self.setup_args)
        with multiprocessing.get_context("fork").Pool(self.backend.workers) as pool:
            for worker, result in pool.imap_unordered(call, queue, chunksize=1):
                self.workers.add(worker)
                yield result

    def _ray(self, queue: Iterator) -> Iterator[Any]:
        ray = _import_ray()
        self._connect(ray)
        remote = ray.remote(_call).options(max_retries=RAY_MAX_RETRIES, retry_exceptions=False,
                                           num_cpus=self.cpus_per_task)
        limit = max(2, int(IN_FLIGHT_PER_CPU * self._cluster_cpus // self.cpus_per_task))
        pending = {}
        try:
            while True:
                for task in queue:
                    pending[remote.remote(self.fn, self.setup, self.setup_args, task)] = task
                    if len(pending) >= limit:
                        break
                if not pending:
                    return
                done, _ = ray.wait(list(pending), num_returns=1, timeout=WAIT_S)
                for ref in done:
                    worker, result = _ray_result(ray, ref, pending.pop(ref))
                    self.workers.add(worker)
                    yield result
        finally:  # Ctrl-C, a failed task or an abandoned run: nothing keeps running for nobody
            if pending and not self._ray_started:
                _cancel(ray, pending)
            # else __exit__'s ray.shutdown ends this driver's job, and Ray stops the job's tasks with it. No cancel
            # then: ray.cancel (forced or not) of a task finishing at that moment makes Ray 2.60 abort the driver
            # ("Tried to complete task that was not pending", exit 1), and at Ctrl-C tasks of equal length often do

    def _connect(self, ray: Any) -> None:
        if not ray.is_initialized():
            start_here = {"include_dashboard": False} if self.backend.ray == RAY_LOCAL else {}
            try:  # address "local" starts a new instance even where a cluster runs (None would join it)
                ray.init(address=self.backend.ray, logging_level=logging.WARNING, **start_here)
            except Exception as error:  # Ray raises ConnectionError, RuntimeError, its own: all mean "no cluster"
                raise ExecutionError(f"cannot start or reach Ray at --ray {self.backend.ray!r}: "
                                     f"{type(error).__name__}: {error}") from error
            self._ray_started = True
        self._cluster_cpus = float(ray.cluster_resources().get("CPU", 0.0))
        log.info("ray: %s CPUs in the cluster (%s)", self._cluster_cpus, self.backend.ray)
        if self._cluster_cpus < self.cpus_per_task:
            raise ExecutionError(f"the Ray cluster at {self.backend.ray!r} has {self._cluster_cpus:g} CPUs; a task "
                                 f"needs {self.cpus_per_task}")


def _cancel(ray: Any, pending: dict) -> None:
    """Cancels the tasks of a connection the caller owns (which outlives the run): those not yet finished, to
    narrow the window in which a cancel races a task's end (see TaskRun._ray)."""
    _, running = ray.wait(list(pending), num_returns=len(pending), timeout=0)
    for ref in running:
        ray.cancel(ref)  # not forced: KeyboardInterrupt in the task, the worker kept


def _nothing() -> Iterator[Any]:
    yield from ()


def _import_ray() -> Any:
    try:
        import ray
    except ImportError:
        raise ExecutionError("--ray needs Ray: install the cluster extra (pip install -e '.[cluster]')") from None
    return ray


def _ray_result(ray: Any, ref: Any, task: Any) -> tuple[str, Any]:
    """The (worker, result) of a finished Ray task; a task's own exception is re-raised as raised."""
    from ray.exceptions import RayError, RayTaskError, WorkerCrashedError

    try:
        return ray.get(ref)
    except RayTaskError as error:
        cause = error.cause
        if isinstance(cause, BaseException):
            raise cause from None
        raise
    except WorkerCrashedError as error:
        raise ExecutionError(f"task {task!r} lost its worker process {RAY_MAX_RETRIES + 1} times; last: "
                             f"{error}") from None
    except RayError as error:  # out of memory, a lost node or object: Ray gave up on the task
        raise ExecutionError(f"Ray lost task {task!r}: {type(error).__name__}: {error}") from None
