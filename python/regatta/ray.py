"""Ray: :func:`regatta.evaluate` spread over a cluster.

``regatta.ray.evaluate`` takes :func:`regatta.evaluate`'s arguments, cuts the candidates into
chunks, evaluates each chunk in a Ray task (in Rust, on the worker's cores) and gathers the
rows in order: the same numbers as on one machine, for any chunking. The world's text is read
once here and shipped to the workers, so they need no copy of the file (a world that uses
EXTERNPROTO or Inline files still needs them beside the path it names). Going from one machine
to a cluster is one line::

    ray.init(address="auto")   # or ray.init(num_cpus=8) for a local one
    fitness = regatta.ray.evaluate("worlds/avoidance.wbt", weights, seeds=range(8))
"""

from __future__ import annotations

import os
from typing import Iterable, Optional, Sequence, Union

import numpy as np

from . import _regatta


def _evaluate_chunk(world, text, weights, seeds, fitness, duration, threads, lenient, overrides):
    return _regatta.evaluate(
        world,
        weights,
        seeds,
        fitness=fitness,
        duration=duration,
        threads=threads,
        lenient=lenient,
        overrides=overrides,
        text=text,
    )


def evaluate(
    world: Union[str, os.PathLike],
    weights=None,
    seeds: Iterable[int] = (1,),
    *,
    fitness: str = "regatta",
    duration: float = 60.0,
    threads: int = 0,
    lenient: bool = False,
    overrides: Sequence[str] = (),
    chunk_size: Optional[int] = None,
    num_cpus: Optional[float] = None,
) -> np.ndarray:
    """:func:`regatta.evaluate` on a Ray cluster: a float64 array (candidates, seeds).

    ``chunk_size`` candidates go to each task (default: enough for about four tasks per CPU
    of the cluster); ``threads`` is each task's thread count (0: the worker's cores) and
    ``num_cpus`` the CPUs a task reserves (default: ``threads`` or 1). Ray must be
    initialised (``ray.init(...)``); if it is not, a local one is started.
    """
    import ray

    if not ray.is_initialized():
        ray.init()
    path = os.fspath(world)
    with open(path, "rb") as f:
        raw = f.read()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        # Let the worker report the file's own error (or read a gzip-compressed one itself).
        text = None
    seeds = [int(s) for s in seeds]
    overrides = list(overrides)
    if weights is None:
        rows = None
        chunks = [None]
    else:
        rows = np.ascontiguousarray(np.asarray(weights, dtype=np.float64))
        if rows.ndim != 2:
            raise ValueError("weights must be a 2-D array: one row per candidate")
        if chunk_size is None:
            cpus = max(1, int(ray.cluster_resources().get("CPU", 1)))
            chunk_size = max(1, -(-len(rows) // (4 * cpus)))
        if chunk_size < 1:
            raise ValueError(f"chunk_size must be at least 1, found {chunk_size}")
        chunks = [rows[i : i + chunk_size] for i in range(0, len(rows), chunk_size)]
        if not chunks:
            return np.zeros((0, len(seeds)))
    task = ray.remote(num_cpus=num_cpus if num_cpus is not None else max(1, threads))(
        _evaluate_chunk
    )
    pending = [
        task.remote(path, text, chunk, seeds, fitness, duration, threads, lenient, overrides)
        for chunk in chunks
    ]
    parts = ray.get(pending)
    return np.concatenate(parts, axis=0)
