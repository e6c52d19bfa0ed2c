"""Type stubs of regatta's native module (written by hand; docstrings are in the module)."""

from __future__ import annotations

import os
from typing import Any, Iterable, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, os.PathLike[str]]

class WorldError(ValueError):
    """A world that does not parse or check; the message holds the diagnostics at file:line:col."""

    file: str | None
    """The file of the first error (``None`` when the world failed for another reason)."""
    line: int | None
    """Its line, from 1."""
    column: int | None
    """Its column, from 1, in characters."""
    message: str | None
    """Its message, without location."""
    errors: list[tuple[str, int, int, str]]
    """Every error as ``(file, line, column, message)``."""

class Robot:
    """One robot of a :class:`World`, as it is after the last step."""

    @property
    def name(self) -> str: ...
    @property
    def pose(self) -> tuple[float, float, float]:
        """(x, z, heading): metres, and radians counter-clockwise from +x seen from above."""
    @property
    def proximity(self) -> npt.NDArray[np.uint16]:
        """The 8 IR readings, 0..1023, larger when closer."""
    @property
    def ambient(self) -> npt.NDArray[np.uint16]:
        """The 8 ambient light readings, 0..1023, larger when darker."""
    def retina(self, filter: str = "odd") -> npt.NDArray[np.uint16]:
        """One enabled filter's converted retina output over the region of interest."""
    @property
    def wheels(self) -> tuple[int, int]:
        """The last step's wheel commands, pulses per 10 ms."""
    @property
    def contacts(self) -> int: ...
    @property
    def touching(self) -> bool: ...
    @property
    def visits(self) -> list[int]:
        """Buoys entered, in order, numbered from 1."""
    @property
    def reward(self) -> float: ...
    @property
    def fitness(self) -> dict[str, Any]:
        """The chosen fitness so far: ``value`` and its terms (``cyclic_visits``…)."""
    def state(self) -> dict[str, Any]: ...

class World:
    """One world stepped from Python. See ``help(regatta.World)``."""

    def __init__(
        self,
        path: _Path,
        *,
        seed: Optional[int] = None,
        lenient: bool = False,
        control: Optional[Sequence[str]] = None,
        fitness: str = "regatta",
        text: Optional[str] = None,
        vary: Sequence[str] = (),
        view: bool = False,
        view_port: int = 0,
    ) -> None: ...
    @property
    def variations(self) -> list[tuple[str, str]]:
        """The values this episode's variations drew: (``Node[i].field``, value) pairs."""
        ...
    def reset(self, seed: Optional[int] = None) -> npt.NDArray[np.float32]:
        """Restarts the world; returns the first observation (driven robots, length)."""
    def step(self, actions: Optional[npt.ArrayLike] = None) -> npt.NDArray[np.float32]:
        """Applies 2 wheel speeds per driven robot, advances one step, returns the observation."""
    def run(self, steps: int) -> npt.NDArray[np.float32]:
        """Runs `steps` steps with the current actions without returning to Python."""
    @property
    def observation(self) -> npt.NDArray[np.float32]: ...
    @property
    def rewards(self) -> npt.NDArray[np.float64]: ...
    @property
    def observation_names(self) -> list[str]: ...
    @property
    def observation_bounds(self) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
    @property
    def speed_scale(self) -> list[float]: ...
    @property
    def controlled(self) -> list[str]: ...
    @property
    def robots(self) -> list[Robot]: ...
    def robot(self, name: str) -> Robot: ...
    def __getitem__(self, name: str) -> Robot: ...
    @property
    def time(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def view_url(self) -> Optional[str]:
        """The live viewer's page when made with ``view=True`` (127.0.0.1), with the run's token (``?token=…``), else None."""
    @property
    def time_step(self) -> float: ...
    @property
    def seed(self) -> int: ...
    @property
    def name(self) -> str: ...
    def log(self, path: _Path, steps: int = 0) -> None:
        """Records the run to MCAP from step 0, as `regatta run --log` does."""
    def close(self) -> None: ...
    def summary(self) -> dict[str, Any]:
        """The object `regatta run --json` prints, without wall time."""
    def summary_json(self) -> str: ...
    def render(self, size: int = 256) -> npt.NDArray[np.uint8]:
        """The arena from above, RGB, (size, size, 3)."""

class VectorWorld:
    """Copies of a world stepped together in Rust. See ``help(regatta.VectorWorld)``."""

    def __init__(
        self,
        path: _Path,
        num_envs: int,
        *,
        seed: Optional[int] = None,
        lenient: bool = False,
        robot: Optional[str] = None,
        fitness: str = "regatta",
        duration: float = 60.0,
        threads: int = 0,
        autoreset: str = "next_step",
        text: Optional[str] = None,
        vary: Sequence[str] = (),
    ) -> None: ...
    def reset(
        self,
        seed: Union[None, int, Sequence[Optional[int]]] = None,
        mask: Optional[Sequence[bool]] = None,
    ) -> npt.NDArray[np.float32]: ...
    def step(
        self, actions: npt.ArrayLike
    ) -> tuple[
        npt.NDArray[np.float32],
        npt.NDArray[np.float64],
        npt.NDArray[np.bool_],
        npt.NDArray[np.bool_],
        npt.NDArray[np.bool_],
        Optional[npt.NDArray[np.float32]],
    ]:
        """(observations, rewards, terminated, truncated, restarted, final observations)."""
    @property
    def observation(self) -> npt.NDArray[np.float32]: ...
    @property
    def num_envs(self) -> int: ...
    @property
    def observation_len(self) -> int: ...
    @property
    def observation_names(self) -> list[str]: ...
    @property
    def observation_bounds(self) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...
    @property
    def episode_steps(self) -> int: ...
    @property
    def time_step(self) -> float: ...
    @property
    def autoreset(self) -> str: ...
    @property
    def threads(self) -> int: ...
    def episodes(self) -> list[tuple[int, int, int]]:
        """Per copy: (seed, steps into the episode, episodes started)."""
    def info(self) -> dict[str, npt.NDArray[Any]]:
        """Each copy's driven robot: ``time``, ``visits``, ``contacts``, ``touching``, ``fitness``."""
    def summary_json(self, index: int) -> str: ...
    def render(self, index: int = 0, size: int = 256) -> npt.NDArray[np.uint8]: ...

def evaluate(
    world: _Path,
    weights: Optional[npt.ArrayLike] = None,
    seeds: Iterable[int] = ...,
    *,
    fitness: str = "regatta",
    duration: float = 60.0,
    threads: int = 0,
    lenient: bool = False,
    overrides: Sequence[str] = (),
    text: Optional[str] = None,
    vary: Sequence[str] = (),
) -> npt.NDArray[np.float64]:
    """Fitness of each candidate (row of `weights`) under each seed: (candidates, seeds)."""

def batch(
    world: _Path,
    seeds: Iterable[int],
    *,
    weights: Optional[npt.ArrayLike] = None,
    fitness: str = "regatta",
    duration: float = 60.0,
    threads: int = 0,
    lenient: bool = False,
    overrides: Sequence[str] = (),
    text: Optional[str] = None,
    vary: Sequence[str] = (),
) -> list[str]:
    """The JSON lines `regatta batch --json` writes for the same runs."""

def parameter_count(
    world: _Path, *, lenient: bool = False, overrides: Sequence[str] = ()
) -> int:
    """The number of weights of the world's NeuralNetwork."""

def network_weights(
    world: _Path, *, lenient: bool = False, overrides: Sequence[str] = ()
) -> npt.NDArray[np.float64]:
    """The weights the world's NeuralNetwork holds."""

def with_weights(world: _Path, weights: Sequence[float]) -> str:
    """The world file's text with `weights` written into its NeuralNetwork (canonical form)."""

def embedded_world(name: str) -> str:
    """The text of a world the package carries (`regatta.wbt`, `avoidance.wbt`)."""
