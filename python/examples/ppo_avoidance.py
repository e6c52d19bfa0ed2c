"""PPO (Stable-Baselines3) learns Floreano and Mondada's obstacle avoidance on the
Rust-batched vector environment `regatta/Avoidance-v0`: 16 copies of worlds/avoidance.wbt
step in Rust in one call per step. Prints the mean per-step Φ of the policy before and after
training (a random policy scores about 0.0x; going straight into a wall scores 0).

    python python/examples/ppo_avoidance.py --timesteps 300000 --out out/ppo
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3 import PPO

import regatta
import regatta.sb3


def mean_phi(model, envs, steps: int) -> float:
    """The policy's mean per-step reward (Φ) over `steps` steps of every copy."""
    obs = envs.reset()
    total = 0.0
    for _ in range(steps):
        actions, _ = model.predict(obs, deterministic=True)
        obs, rewards, dones, infos = envs.step(actions)
        total += float(rewards.mean())
    return total / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--timesteps", type=int, default=300_000)
    parser.add_argument("--envs", type=int, default=16)
    parser.add_argument("--duration", type=float, default=20.0, help="simulated seconds per episode")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--out", default="out/ppo")
    args = parser.parse_args()

    vector = gymnasium.make_vec(
        "regatta/Avoidance-v0",
        num_envs=args.envs,
        vectorization_mode="vector_entry_point",
        autoreset_mode=AutoresetMode.SAME_STEP,
        duration=args.duration,
        threads=args.threads,
    )
    envs = regatta.sb3.VecEnv(vector)
    envs.seed(args.seed)
    model = PPO(
        "MlpPolicy",
        envs,
        n_steps=256,
        batch_size=1024,
        learning_rate=3e-4,
        gamma=0.98,
        seed=args.seed,
        device="cpu",
        verbose=0,
    )
    before = mean_phi(model, envs, 200)
    began = time.perf_counter()
    model.learn(total_timesteps=args.timesteps)
    seconds = time.perf_counter() - began
    after = mean_phi(model, envs, 200)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    model.save(out / "ppo_avoidance")
    print(f"{args.timesteps} steps of PPO in {seconds:.1f} s ({args.timesteps / seconds:.0f} steps/s)")
    print(f"mean avoidance Φ per step: before {before:.3f}, after {after:.3f}")


if __name__ == "__main__":
    main()
