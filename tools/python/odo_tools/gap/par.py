"""Independent fits of one diagnosis on the machine's cores.

A diagnosis is mostly fits that do not depend on each other: the singles, the pairs, the clock
a truth may run behind, the lever arms under each skid subset. `each` runs such a batch in
forked worker processes, which inherit the runs, the problem and every cache as they are at the
fork, so nothing is pickled on the way in; each task's result (a Fit, numbers) is pickled back.
A task computes exactly what it would in the parent, so the diagnosis is the same bit for bit
with one core or many (tests/python/test_gap_par.py); only its wall time changes.

Tasks must not rely on changing the parent's objects: what a child changes (a run's placed
bumps, a cache it fills) stays in the child.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
from collections.abc import Callable, Iterator, Sequence
from typing import TypeVar

T = TypeVar("T")

_jobs = 1  # worker processes a batch may use (set per diagnosis by `cores`)
_tasks: Sequence[Callable[[], object]] = ()


def available() -> int:
    """The cores this process may use; one inside a pool's worker (the blind check runs its
    diagnoses side by side, and a daemonic worker cannot have children)."""
    if multiprocessing.current_process().daemon:
        return 1
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


@contextlib.contextmanager
def cores(jobs: int | None) -> Iterator[int]:
    """Run the batches inside on `jobs` processes (None: every available core)."""
    global _jobs
    n = available() if jobs is None else max(1, min(int(jobs), available()))
    old, _jobs = _jobs, n
    try:
        yield n
    finally:
        _jobs = old


def jobs() -> int:
    """The worker processes a batch may use now (1 inside a task, and outside `cores`)."""
    return _jobs


def _call(i: int) -> object:
    global _jobs
    _jobs = 1  # a task that asks for a batch runs it in its own process
    return _tasks[i]()


def each(
    tasks: Sequence[Callable[[], T]],
    labels: Sequence[str] | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[T]:
    """Every task's result, in order; `progress(label)` as each is taken up (serially) or has
    finished (in workers)."""
    global _tasks
    n = min(_jobs, len(tasks))
    if n <= 1 or "fork" not in multiprocessing.get_all_start_methods():
        out = []
        for i, t in enumerate(tasks):
            if progress and labels:
                progress(labels[i])
            out.append(t())
        return out
    _tasks = tasks
    try:
        with multiprocessing.get_context("fork").Pool(n) as pool:
            out = []
            try:
                for i, r in enumerate(pool.imap(_call, range(len(tasks)), chunksize=1)):
                    if progress and labels:
                        progress(labels[i])
                    out.append(r)
            except Exception:
                # a task's error: the other tasks end before the pool does. Leaving the `with`
                # at once terminates the pool while its task handler still feeds the workers,
                # which can wait for ever (CPython issues 96995 and 78178; ctest's
                # py.test_gap_par once waited 10 min here, two workers reaped by nobody)
                pool.close()
                pool.join()
                raise
            return out
    finally:
        _tasks = ()
