"""Threads per worker: the cores shared among the trials running at once, not claimed by each.

A trial renders with Mesa's llvmpipe (without a GPU), filters images with OpenCV and does
its linear algebra with OpenBLAS; each of them starts a thread per core of the machine, and
OpenBLAS's threads spin while they wait for work. Measured on 16 realistic accuracy trials
with 2 workers on 2 cores: 41-42 s with the libraries' defaults, 35 s with one thread each,
and 41 s with OpenBLAS alone left at two (llvmpipe at two: 34 s). So each worker process
gets ``cores // workers`` threads (at least one), through the environment variables the
libraries read when they start; one process alone keeps them all (one thread would cost it
10-15 %).

The results do not depend on it: llvmpipe and OpenCV split an image by pixels or rows, and
OpenBLAS splits a product by rows, not its sums (benchmarks/compare_runs.py: the same rows).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

THREAD_VARIABLES = (
    "LP_NUM_THREADS",  # Mesa's llvmpipe rasteriser
    "OPENCV_FOR_THREADS_NUM",  # OpenCV's parallel loops
    "OPENBLAS_NUM_THREADS",  # NumPy's BLAS
    "OMP_NUM_THREADS",  # OpenMP (IPOPT's linear solver, BLAS builds on OpenMP)
)


def thread_env(workers: int, cores: int | None = None) -> dict[str, str]:
    """The thread variables for one of ``workers`` processes sharing ``cores`` (default:
    this machine's). A variable the user has set is left as it is."""
    cores = cores or os.cpu_count() or 1
    threads = str(max(1, cores // max(1, workers)))
    return {name: os.environ.get(name, threads) for name in THREAD_VARIABLES}


@contextmanager
def worker_threads(workers: int) -> Iterator[None]:
    """Within the block, processes started from this one (a spawned pool's workers) get
    ``thread_env(workers)``; this process' own libraries, already started, are unchanged."""
    before = {name: os.environ.get(name) for name in THREAD_VARIABLES}
    os.environ.update(thread_env(workers))
    try:
        yield
    finally:
        for name, value in before.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
