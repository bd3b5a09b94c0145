"""Where independent tasks run: local processes or Ray tasks, behind one function (:func:`run_tasks`).

Used by the dataset generator (one task per shard) and by the benchmarks (one task per trial or scene). A task is
a plain module-level function of one picklable argument; :func:`run_tasks` yields ``(job, result)`` as tasks
finish, in completion order, so the caller writes each result as it comes (a stopped run keeps what is done).

- ``backend="local"``: ``workers`` = 1 runs the tasks in this process, one after the other; more starts a pool
  of spawned processes, never more than there are tasks (:func:`pool_size`).
- ``backend="ray"``: one Ray task per job (1 CPU each). Without ``ray_address`` a Ray instance with ``workers``
  CPUs is started on this machine for the run and shut down after it; with ``ray_address`` (e.g.
  ``ray://head:10001`` or ``auto``) the tasks run on that existing cluster, whose nodes need this package
  installed. Ray is the optional extra ``cluster`` (``pip install 'slax-drake[cluster]'``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator

from slax_drake.errors import BackendError

BACKENDS = ("local", "ray")


def add_backend_arguments(parser, what: str) -> None:
    """``--workers``, ``--backend`` and ``--ray-address`` of a command that runs ``what`` as tasks."""
    parser.add_argument("--workers", type=int, default=1,
                        help="parallel local processes, or the CPUs of the Ray instance started here; never more "
                        "than there are tasks (default: 1)")
    parser.add_argument("--backend", choices=BACKENDS, default="local",
                        help=f"run the {what} as local processes or as Ray tasks (extra 'cluster') (default: local)")
    parser.add_argument("--ray-address", default=None, metavar="ADDRESS",
                        help="with --backend ray: an existing Ray cluster (e.g. ray://head:10001 or auto) instead of "
                        "a Ray instance started on this machine")


def check_backend(backend: str, workers: int, ray_address: str | None = None) -> None:
    """UserError for a request no backend can serve, before anything runs."""
    if backend not in BACKENDS:
        raise BackendError(f"unknown backend {backend!r}: use 'local' or 'ray'")
    if workers < 1:
        raise BackendError("--workers must be at least 1")
    if ray_address is not None and backend != "ray":
        raise BackendError("--ray-address needs --backend ray")
    if backend == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            raise BackendError("--backend ray needs Ray: pip install 'slax-drake[cluster]'") from None


def run_tasks(task: Callable, jobs: Iterable, workers: int = 1, backend: str = "local",
              ray_address: str | None = None) -> Iterator[tuple]:
    """Runs ``task(job)`` for every job on ``backend``; yields ``(job, result)`` as each finishes."""
    jobs = list(jobs)
    check_backend(backend, workers, ray_address)
    if not jobs:
        return
    workers = pool_size(workers, len(jobs))
    if backend == "ray":
        yield from _run_ray(task, jobs, workers, ray_address)
    elif workers <= 1:
        for job in jobs:
            yield job, task(job)
    else:
        import multiprocessing

        with multiprocessing.get_context("spawn").Pool(workers) as pool:
            yield from pool.imap_unordered(_Tagged(task), jobs, chunksize=1)


def pool_size(workers: int, tasks: int) -> int:
    """The processes (or local Ray CPUs) worth starting for ``tasks`` tasks when ``workers`` were asked for: never
    more than there are tasks, since an extra one would only idle (and cost its start and memory)."""
    return max(1, min(int(workers), int(tasks)))


class _Tagged:
    """``job -> (job, task(job))``, picklable for a process pool."""

    def __init__(self, task: Callable):
        self.task = task

    def __call__(self, job):
        return job, self.task(job)


def _run_ray(task: Callable, jobs: list, workers: int, ray_address: str | None) -> Iterator[tuple]:
    import ray

    started_here = not ray.is_initialized()
    if started_here:
        try:
            if ray_address is None:
                ray.init(num_cpus=max(1, workers), include_dashboard=False, log_to_driver=False)
            else:
                ray.init(address=ray_address, log_to_driver=False)
        except (ConnectionError, RuntimeError, ValueError) as e:
            raise BackendError(f"cannot start or reach Ray at {ray_address or 'this machine'}: "
                               f"{str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
    try:
        remote = ray.remote(num_cpus=1)(task)
        pending = {remote.remote(job): job for job in jobs}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            for ref in ready:
                yield pending.pop(ref), ray.get(ref)
    finally:
        if started_here:
            ray.shutdown()
