"""Two Kheperas sail the regatta together as PettingZoo agents, each driven by a small
Python policy: Braitenberg's obstacle avoidance on the IR readings, plus turning toward the
brightest retina sector. Prints each agent's return and buoy visits.

    python python/examples/pettingzoo_loop.py --duration 120
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import regatta.pettingzoo

ROOT = Path(__file__).resolve().parents[2]

# K-Team's Braitenberg weights (IR sensors 0..7), per wheel, in units of the speed scale.
LEFT = np.array([4, 4, 6, -18, -15, -5, 5, 3]) / 20.0
RIGHT = np.array([-5, -15, -18, 6, 4, 4, 3, 5]) / 20.0


def policy(observation: np.ndarray, names: list[str]) -> np.ndarray:
    ir = observation[[names.index(f"ir{i}") for i in range(8)]]
    retina = observation[[i for i, n in enumerate(names) if n.startswith("retina")]]
    # Sector 0 is the retina's left end: a bright sector left of centre turns left.
    steer = (np.argmax(retina) - (len(retina) - 1) / 2) / len(retina) if len(retina) else 0.0
    left = 0.5 + ir @ LEFT * 4 + 0.3 * steer
    right = 0.5 + ir @ RIGHT * 4 - 0.3 * steer
    return np.clip([left, right], -1.0, 1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--world", default=str(ROOT / "worlds" / "regatta_pair.wbt"))
    parser.add_argument("--duration", type=float, default=120.0)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    env = regatta.pettingzoo.parallel_env(args.world, duration=args.duration)
    names = env.observation_names
    observations, infos = env.reset(seed=args.seed)
    returns = dict.fromkeys(env.possible_agents, 0.0)
    while env.agents:
        actions = {agent: policy(observations[agent], names) for agent in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)
        for agent, reward in rewards.items():
            returns[agent] += reward
    for agent in env.possible_agents:
        robot = env.world[agent]
        print(f"{agent}: return {returns[agent]:.2f}, buoy visits {robot.visits}, contacts {robot.contacts}")
    env.close()


if __name__ == "__main__":
    main()
