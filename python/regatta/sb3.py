"""Stable-Baselines3: the Rust-batched vector environment as an SB3 ``VecEnv``.

SB3 trains on its own ``VecEnv`` interface rather than Gymnasium's ``VectorEnv``; this adapter
puts :class:`regatta.gym.RegattaVectorEnv` (the copies still step in Rust, in one call, on a
thread pool) behind it, with SB3's conventions: autoreset in the step that ends an episode,
the last observation in ``info["terminal_observation"]`` and ``info["TimeLimit.truncated"]``
set for truncated episodes::

    envs = gymnasium.make_vec("regatta/Avoidance-v0", num_envs=16,
                              vectorization_mode="vector_entry_point",
                              autoreset_mode=gymnasium.vector.AutoresetMode.SAME_STEP)
    model = stable_baselines3.PPO("MlpPolicy", regatta.sb3.VecEnv(envs))
"""

from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env.base_vec_env import VecEnv as _VecEnv

from .gym import RegattaVectorEnv


class VecEnv(_VecEnv):
    """An SB3 ``VecEnv`` over a :class:`regatta.gym.RegattaVectorEnv` made with
    ``autoreset_mode=SAME_STEP`` (SB3's convention)."""

    def __init__(self, envs):
        vector = envs.unwrapped if hasattr(envs, "unwrapped") else envs
        if not isinstance(vector, RegattaVectorEnv):
            raise TypeError(f"expected a regatta.gym.RegattaVectorEnv, found {type(vector).__name__}")
        if vector.autoreset_mode != AutoresetMode.SAME_STEP:
            raise ValueError(
                "SB3 resets a finished episode in the step that ends it: make the environment "
                "with autoreset_mode=gymnasium.vector.AutoresetMode.SAME_STEP"
            )
        self.envs = vector
        self._world = vector.vector_world
        self._actions: Optional[np.ndarray] = None
        self.render_mode = vector.render_mode
        super().__init__(vector.num_envs, vector.single_observation_space, vector.single_action_space)

    def reset(self):
        seeds = self._seeds
        if any(s is not None for s in seeds):
            observation = self._world.reset(seed=[None if s is None else int(s) for s in seeds])
        else:
            observation = self._world.reset()
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = [{} for _ in range(self.num_envs)]
        return observation

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=np.float64)

    def step_wait(self):
        observation, rewards, terminated, truncated, _, finals = self._world.step(self._actions)
        dones = terminated | truncated
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for i in np.flatnonzero(dones):
            infos[i]["terminal_observation"] = finals[i]
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return observation, rewards.astype(np.float32), dones, infos

    def close(self) -> None:
        self.envs.close()

    def _indices(self, indices) -> Sequence[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, int):
            return [indices]
        return indices

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        value = getattr(self, attr_name) if attr_name == "render_mode" else getattr(self.envs, attr_name)
        return [value for _ in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        setattr(self.envs, attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
        raise AttributeError(
            f"the copies of a regatta vector environment are not Python environments; "
            f"there is no per-copy method {method_name!r}"
        )

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._indices(indices)]

    def get_images(self) -> Sequence[Optional[np.ndarray]]:
        return [self._world.render(i, self.envs.render_size) for i in range(self.num_envs)]
