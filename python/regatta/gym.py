"""Gymnasium environments over regatta worlds.

- ``regatta/Regatta-v0``: the paper's regatta (``worlds/regatta.wbt``): a Khepera with a
  Panoramic turret among three light buoys; reward: the ``regatta`` fitness (a buoy visit that
  continues the cyclic order earns 1, another buoy 0.25, contact costs 0.5 per second).
- ``regatta/Avoidance-v0``: Floreano and Mondada's obstacle avoidance
  (``worlds/avoidance.wbt``); reward: the step's Φ = V (1 - √Δv) (1 - i).

Both take ``world=`` (a path to any world file), ``robot=``, ``fitness=``, ``duration=`` (the
episode's simulated seconds: it is then truncated; nothing terminates an episode) and
``render_mode="rgb_array"`` (the arena from above). Observations and actions are those of
:class:`regatta.World`: a float32 ``Box`` of the robot's IR and ambient readings / 1024 and its
pooled retina (-1..1), and a ``Box(-1, 1, (2,))`` of wheel speeds in units of the robot's speed
scale.

``gymnasium.make_vec("regatta/Regatta-v0", num_envs=64,
vectorization_mode="vector_entry_point")`` gives :class:`RegattaVectorEnv`: the copies step in
Rust on a thread pool in one call, with Gymnasium 1.x autoreset (``autoreset_mode``
``NextStep`` by default, ``SameStep`` or ``Disabled``).
"""

from __future__ import annotations

import os
from typing import Any, Optional, Sequence, Union

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ._regatta import VectorWorld, World, embedded_world

#: The worlds the registered environments use when given none (carried by the package).
DEFAULT_WORLDS = {"Regatta-v0": "regatta.wbt", "Avoidance-v0": "avoidance.wbt"}

#: Simulated seconds of an episode when none is given.
DEFAULT_DURATION = {"Regatta-v0": 60.0, "Avoidance-v0": 20.0}


def _world_source(world: Optional[Union[str, os.PathLike]], default: str):
    """(path, text): a file's path (text None), or an embedded world's name and text."""
    if world is not None:
        return os.fspath(world), None
    return default, embedded_world(default)


def _check_arguments(render_mode: Optional[str], duration: float) -> None:
    if render_mode is not None and render_mode != "rgb_array":
        raise ValueError(f"render_mode must be None or 'rgb_array', found {render_mode!r}")
    if not (duration > 0):
        raise ValueError(f"duration must be a positive number of seconds, found {duration}")


def _spaces(bounds):
    low, high = bounds
    observation = spaces.Box(low=low, high=high, dtype=np.float32)
    action = spaces.Box(low=-1.0, high=1.0, shape=(2,), dtype=np.float32)
    return observation, action


class RegattaEnv(gymnasium.Env):
    """One robot of a regatta world as a Gymnasium environment.

    Args:
        world: the world file (None: the environment's own world).
        robot: the robot the actions drive (None: the first); other robots run their own
            controllers.
        fitness: the reward's fitness (``regatta``, ``avoidance``, ``phototaxis``, with
            optional parameters such as ``regatta:penalty=1``).
        duration: simulated seconds after which an episode is truncated.
        render_mode: None or ``"rgb_array"`` (the arena from above, ``render_size`` pixels).
        render_size: the side of a rendered image, in pixels.
        lenient: read a foreign world file leniently.
        default_world: the world of the project's ``worlds/`` used when ``world`` is None
            (each registered environment names its own).
        vary: variations drawn anew from each ``reset(seed)``, as ``regatta run --vary``
            takes them (``"DirectionalLight.intensity=0.02..0.8"``).

    ``step``'s info holds the driven robot's step: ``time`` (s), ``visits`` (buoy visits so
    far) and ``new_visits`` (the buoys entered this step, numbered from 1), ``contacts``
    (contacts begun so far), ``touching``, ``reward`` (the step's fitness term) and
    ``fitness`` (the chosen fitness so far, its ``value`` and terms, as
    :attr:`regatta.Robot.fitness` gives them: ``cyclic_visits``, ``other_visits`` and
    ``contact_s`` for ``regatta``).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(
        self,
        world: Optional[Union[str, os.PathLike]] = None,
        *,
        robot: Optional[str] = None,
        fitness: str = "regatta",
        duration: float = 60.0,
        render_mode: Optional[str] = None,
        render_size: int = 256,
        lenient: bool = False,
        default_world: str = "regatta.wbt",
        vary: Sequence[str] = (),
    ):
        _check_arguments(render_mode, duration)
        path, text = _world_source(world, default_world)
        control = None if robot is None else [robot]
        vary = list(vary)
        self._world = World(
            path, text=text, lenient=lenient, control=control, fitness=fitness, vary=vary
        )
        if robot is None and len(self._world.controlled) != 1:
            # Several robots: the first is driven, the others run their own controllers.
            robot = self._world.robots[0].name
            self._world = World(
                path, text=text, lenient=lenient, control=[robot], fitness=fitness, vary=vary
            )
        self._episode_steps = int(np.ceil(duration / self._world.time_step - 1e-9))
        self.observation_space, self.action_space = _spaces(self._world.observation_bounds)
        self.observation_names = self._world.observation_names
        self.render_mode = render_mode
        self.render_size = render_size
        self._visits_seen = 0

    @property
    def world(self) -> World:
        """The :class:`regatta.World` underneath (its robots, summary and log)."""
        return self._world

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        super().reset(seed=seed)
        if seed is None:
            # A new episode's seed from the environment's generator: reproducible from the
            # first reset's seed.
            seed = int(self.np_random.integers(0, 2**63))
        observation = self._world.reset(seed)
        self._visits_seen = 0
        return observation[0], {"seed": seed}

    def step(self, action):
        observation = self._world.step(action)
        reward = float(self._world.rewards[0])
        truncated = self._world.steps >= self._episode_steps
        return observation[0], reward, False, truncated, self._step_info(reward)

    def _step_info(self, reward: float) -> dict:
        info = step_info(self._world, self._world.controlled[0], self._visits_seen, reward)
        self._visits_seen = info["visits"]
        return info

    def render(self):
        if self.render_mode == "rgb_array":
            return self._world.render(self.render_size)
        return None


class RegattaVectorEnv(VectorEnv):
    """``num_envs`` copies of a regatta world stepped together in Rust (one call per step,
    on a thread pool, GIL released). Arguments as :class:`RegattaEnv`, plus ``threads`` (the
    pool's size, 0: one per core; results do not depend on it) and ``autoreset_mode``.

    With ``SameStep`` autoreset the info of a step that ended episodes holds ``final_obs``
    and ``final_info`` with their ``_final_obs``/``_final_info`` masks, as Gymnasium's
    ``SyncVectorEnv`` gives them. ``reset(options={"reset_mask": mask})`` restarts some
    copies (``Disabled`` autoreset).

    ``step``'s info holds, as arrays of ``num_envs`` with Gymnasium's ``_name`` masks, each
    copy's driven robot: ``time`` (s into its episode), ``visits`` (buoy visits so far),
    ``contacts`` (contacts begun so far), ``touching``, ``reward`` (the step's fitness term)
    and ``fitness`` (the chosen fitness's value so far); a copy that has just restarted
    gives its new episode's.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(
        self,
        num_envs: int = 1,
        world: Optional[Union[str, os.PathLike]] = None,
        *,
        robot: Optional[str] = None,
        fitness: str = "regatta",
        duration: float = 60.0,
        threads: int = 0,
        autoreset_mode: Union[str, AutoresetMode] = AutoresetMode.NEXT_STEP,
        render_mode: Optional[str] = None,
        render_size: int = 256,
        lenient: bool = False,
        default_world: str = "regatta.wbt",
        vary: Sequence[str] = (),
    ):
        _check_arguments(render_mode, duration)
        self.autoreset_mode = (
            autoreset_mode
            if isinstance(autoreset_mode, AutoresetMode)
            else AutoresetMode(autoreset_mode)
        )
        mode = {
            AutoresetMode.NEXT_STEP: "next_step",
            AutoresetMode.SAME_STEP: "same_step",
            AutoresetMode.DISABLED: "disabled",
        }[self.autoreset_mode]
        path, text = _world_source(world, default_world)
        self._vector = VectorWorld(
            path,
            num_envs,
            text=text,
            lenient=lenient,
            robot=robot,
            fitness=fitness,
            duration=duration,
            threads=threads,
            autoreset=mode,
            vary=list(vary),
        )
        self.num_envs = num_envs
        self.single_observation_space, self.single_action_space = _spaces(
            self._vector.observation_bounds
        )
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.observation_names = self._vector.observation_names
        self.render_mode = render_mode
        self.render_size = render_size
        self.metadata = dict(self.metadata, autoreset_mode=self.autoreset_mode)

    @property
    def vector_world(self) -> VectorWorld:
        """The :class:`regatta.VectorWorld` underneath."""
        return self._vector

    def reset(self, *, seed: Optional[Union[int, list]] = None, options: Optional[dict] = None):
        mask = None
        if options is not None and "reset_mask" in options:
            mask = [bool(m) for m in np.asarray(options["reset_mask"]).reshape(-1)]
        if seed is not None:
            # Gymnasium's convention: an int s seeds copy i with s + i.
            self._np_random, self._np_random_seed = gymnasium.utils.seeding.np_random(
                seed if isinstance(seed, int) else None
            )
        observation = self._vector.reset(seed=seed, mask=mask)
        return observation, {}

    def step(self, actions):
        observation, rewards, terminated, truncated, _, finals = self._vector.step(actions)
        infos: dict[str, Any] = {}
        every = np.ones(self.num_envs, dtype=bool)
        step_info = self._vector.info()
        step_info["reward"] = rewards.copy()
        for key in ("time", "visits", "contacts", "touching", "reward", "fitness"):
            infos[key] = step_info[key]
            infos["_" + key] = every.copy()
        if finals is not None:
            ended = terminated | truncated
            if ended.any():
                final_obs = np.full(self.num_envs, None, dtype=object)
                final_info = np.full(self.num_envs, None, dtype=object)
                for i in np.flatnonzero(ended):
                    final_obs[i] = finals[i]
                    final_info[i] = {}
                infos["final_obs"] = final_obs
                infos["_final_obs"] = ended.copy()
                infos["final_info"] = {}
                infos["_final_info"] = ended.copy()
        return observation, rewards, terminated, truncated, infos

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        return tuple(self._vector.render(i, self.render_size) for i in range(self.num_envs))


def _entry_points(name: str, fitness: str):
    """The entry point and vector entry point of ``regatta/<name>``: the environment classes
    with that environment's world, fitness and episode length as defaults."""

    def defaults(kwargs: dict) -> dict:
        kwargs.setdefault("default_world", DEFAULT_WORLDS[name])
        kwargs.setdefault("fitness", fitness)
        kwargs.setdefault("duration", DEFAULT_DURATION[name])
        return kwargs

    def entry(**kwargs) -> RegattaEnv:
        return RegattaEnv(**defaults(kwargs))

    def vector(num_envs: int = 1, **kwargs) -> RegattaVectorEnv:
        return RegattaVectorEnv(num_envs, **defaults(kwargs))

    entry.__doc__ = f"``regatta/{name}``'s entry point."
    vector.__doc__ = f"``regatta/{name}``'s vector entry point."
    return entry, vector


make_regatta, make_regatta_vector = _entry_points("Regatta-v0", "regatta")
make_avoidance, make_avoidance_vector = _entry_points("Avoidance-v0", "avoidance")


def register_environments() -> None:
    """Registers ``regatta/Regatta-v0`` and ``regatta/Avoidance-v0`` (done on import)."""
    for name, entry, vector in [
        ("Regatta-v0", make_regatta, make_regatta_vector),
        ("Avoidance-v0", make_avoidance, make_avoidance_vector),
    ]:
        env_id = f"regatta/{name}"
        if env_id in gymnasium.envs.registry:
            continue
        gymnasium.register(
            id=env_id,
            entry_point=entry,
            vector_entry_point=vector,
            nondeterministic=False,
        )


def step_info(world, robot_name: str, visits_seen: int, reward: float) -> dict:
    """A robot's step info: the time, its visits (all, and those since ``visits_seen``),
    contacts, whether it touches something, the step's reward and its fitness so far."""
    robot = world[robot_name]
    visits = robot.visits
    return {
        "time": world.time,
        "visits": len(visits),
        "new_visits": visits[visits_seen:],
        "contacts": robot.contacts,
        "touching": robot.touching,
        "reward": reward,
        "fitness": robot.fitness,
    }
