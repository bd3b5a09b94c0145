"""``--workers`` never starts more processes than there are tasks."""

from __future__ import annotations

import multiprocessing

from slax_drake import backends


def _square(x):
    return x * x


def test_pool_size_is_clamped_to_the_work():
    assert backends.pool_size(5000, 3) == 3
    assert backends.pool_size(2, 10) == 2
    assert backends.pool_size(5000, 1) == 1


def test_run_tasks_starts_no_more_processes_than_tasks(monkeypatch):
    started = []
    real_get_context = multiprocessing.get_context

    def recording_context(method):
        context = real_get_context(method)

        class Recording:
            def Pool(self, processes):  # noqa: N802 - mirrors multiprocessing's name
                started.append(processes)
                return context.Pool(processes)

        return Recording()

    monkeypatch.setattr(multiprocessing, "get_context", recording_context)
    results = dict(backends.run_tasks(_square, [2, 3], workers=5000))
    assert results == {2: 4, 3: 9}
    assert started == [2]


def test_one_task_with_many_workers_runs_here_without_a_pool(monkeypatch):
    def no_pool(method):
        raise AssertionError("a pool was started for one task")

    monkeypatch.setattr(multiprocessing, "get_context", no_pool)
    assert dict(backends.run_tasks(_square, [4], workers=5000)) == {4: 16}
