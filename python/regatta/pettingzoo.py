"""PettingZoo: a world with several robots as a ``ParallelEnv``, one agent per robot.

``parallel_env(world_path)`` drives every robot of the world (or those named in ``agents``)
from Python; each agent observes, acts and is rewarded as in :class:`regatta.World`: its IR,
ambient and pooled retina observation, two wheel speeds in ``[-1, 1]`` (units of its speed
scale), the step's contribution to ``fitness``. All robots share one simulation (they see and
bump into each other); the world moves once per ``step``, after every agent's action is in.
Episodes are truncated after ``duration`` simulated seconds; nothing terminates an agent
earlier. Each agent's info is its step, as :class:`regatta.gym.RegattaEnv` gives it:
``time``, ``visits``, ``new_visits``, ``contacts``, ``touching``, ``reward`` and ``fitness``.
"""

from __future__ import annotations

import os
from typing import Optional, Sequence, Union

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from pettingzoo import ParallelEnv

from ._regatta import World
from .gym import step_info


class RegattaParallelEnv(ParallelEnv):
    """Every driven robot of a regatta world is an agent (see :func:`parallel_env`)."""

    metadata = {"render_modes": ["rgb_array"], "name": "regatta_v0", "is_parallelizable": True}

    def __init__(
        self,
        world: Union[str, os.PathLike],
        *,
        agents: Optional[Sequence[str]] = None,
        fitness: str = "regatta",
        duration: float = 60.0,
        render_mode: Optional[str] = None,
        render_size: int = 256,
        lenient: bool = False,
        vary: Sequence[str] = (),
    ):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or 'rgb_array', found {render_mode!r}")
        if not (duration > 0):
            raise ValueError(f"duration must be a positive number of seconds, found {duration}")
        control = None if agents is None else list(agents)
        # Variations are drawn anew from each reset's seed (as `regatta run --vary`).
        self._world = World(
            os.fspath(world), lenient=lenient, control=control, fitness=fitness, vary=list(vary)
        )
        self._episode_steps = int(np.ceil(duration / self._world.time_step - 1e-9))
        self.possible_agents = list(self._world.controlled)
        self.agents: list[str] = []
        low, high = self._world.observation_bounds
        self._observation_spaces = {
            a: spaces.Box(low=low, high=high, dtype=np.float32) for a in self.possible_agents
        }
        self._action_spaces = {
            a: spaces.Box(low=-1.0, high=1.0, shape=(2,), dtype=np.float32)
            for a in self.possible_agents
        }
        self.observation_names = self._world.observation_names
        self.render_mode = render_mode
        self.render_size = render_size
        self._np_random, _ = seeding.np_random(None)
        self._actions = np.zeros((len(self.possible_agents), 2))
        self._visits_seen: dict[str, int] = {}

    @property
    def world(self) -> World:
        """The :class:`regatta.World` underneath."""
        return self._world

    def observation_space(self, agent: str) -> spaces.Box:
        return self._observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Box:
        return self._action_spaces[agent]

    def reset(self, seed: Optional[int] = None, options: Optional[dict] = None):
        if seed is not None:
            self._np_random, _ = seeding.np_random(seed)
        else:
            # The next episode's seed comes from the generator the first seed started.
            seed = int(self._np_random.integers(0, 2**63))
        observation = self._world.reset(seed)
        self.agents = list(self.possible_agents)
        self._actions[:] = 0.0
        self._visits_seen = {}
        observations = {a: observation[i] for i, a in enumerate(self.possible_agents)}
        return observations, {a: {"seed": seed} for a in self.agents}

    def step(self, actions: dict):
        # An agent that gives no action keeps its wheels stopped this step.
        self._actions[:] = 0.0
        for i, agent in enumerate(self.possible_agents):
            action = actions.get(agent)
            if action is not None and agent in self.agents:
                self._actions[i] = np.asarray(action, dtype=np.float64).reshape(2)
        observation = self._world.step(self._actions)
        rewards = self._world.rewards
        truncated = self._world.steps >= self._episode_steps
        live = self.agents
        index = {a: i for i, a in enumerate(self.possible_agents)}
        observations = {a: observation[index[a]] for a in live}
        reward = {a: float(rewards[index[a]]) for a in live}
        terminations = {a: False for a in live}
        truncations = {a: truncated for a in live}
        infos = {a: self._step_info(a, reward[a]) for a in live}
        if truncated:
            self.agents = []
        return observations, reward, terminations, truncations, infos

    def _step_info(self, agent: str, reward: float) -> dict:
        """An agent's step, as :class:`regatta.gym.RegattaEnv` gives it."""
        info = step_info(self._world, agent, self._visits_seen.get(agent, 0), reward)
        self._visits_seen[agent] = info["visits"]
        return info

    def render(self):
        if self.render_mode == "rgb_array":
            return self._world.render(self.render_size)
        return None

    def state(self) -> np.ndarray:
        """Every agent's observation, concatenated in ``possible_agents`` order."""
        return self._world.observation.reshape(-1)

    def close(self):
        self._world.close()


def parallel_env(world: Union[str, os.PathLike], **kwargs) -> RegattaParallelEnv:
    """A PettingZoo ``ParallelEnv`` of the world at ``world``: one agent per robot (or per
    robot named in ``agents=``), named as the robots are. Keyword arguments: ``fitness``
    (``regatta``), ``duration`` (60 simulated seconds), ``render_mode`` (None or
    ``"rgb_array"``), ``render_size``, ``lenient``."""
    return RegattaParallelEnv(world, **kwargs)
