"""regatta: Khepera robots with the EDI panoramic retina, simulated in Rust.

The native core steps worlds written in regatta's VRML-style language; this package gives it to
Python:

- :class:`World`: one world stepped from Python (``reset``/``step``, robots by name, an MCAP log
  as ``regatta run --log`` writes it, the ``regatta run --json`` summary).
- :class:`VectorWorld`: many copies of a world stepped together on a thread pool in one call,
  with the GIL released (the core of the Gymnasium vector environment).
- :func:`evaluate`: the fitness of many ``NeuralNetwork`` weight vectors under many seeds, in
  parallel in Rust, the same numbers as ``regatta batch``; :func:`parameter_count` gives the
  length of a weight vector; :func:`batch` the ``regatta batch --json`` rows themselves.
- ``regatta.gym``: ``regatta/Regatta-v0`` and ``regatta/Avoidance-v0`` (registered with
  Gymnasium when this package is imported and Gymnasium is installed), and their vector
  environment for ``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``.
- ``regatta.webots``: ``regatta/Webots-v0``, one robot of a Webots project as a Gymnasium
  environment (actions: its motors' velocities; observations: its sensors), the project's
  other controllers running beside it.
- ``regatta.pettingzoo``: :func:`regatta.pettingzoo.parallel_env`, one agent per robot.
- ``regatta.ray``: :func:`regatta.ray.evaluate`, :func:`evaluate` spread over a Ray cluster.
"""

from __future__ import annotations

import importlib.util as _importlib_util

from ._regatta import (
    Robot,
    VectorWorld,
    World,
    WorldError,
    __version__,
    batch,
    embedded_world,
    evaluate,
    network_weights,
    parameter_count,
    with_weights,
)

__all__ = [
    "Robot",
    "VectorWorld",
    "World",
    "WorldError",
    "__version__",
    "batch",
    "embedded_world",
    "evaluate",
    "network_weights",
    "parameter_count",
    "with_weights",
]

if _importlib_util.find_spec("gymnasium") is not None:
    from .gym import register_environments as _register_environments
    from .webots import register as _register_webots

    _register_environments()
    _register_webots()
