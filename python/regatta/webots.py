"""A Gymnasium environment over a Webots project: ``regatta/Webots-v0``.

People who train on Webots today wrap it by hand: a controller that is also the environment,
a supervisor that resets the world. :class:`WebotsEnv` does that over regatta instead. One
robot of a Webots world (``project/worlds/W.wbt``) is the agent; every other robot runs its
project's own controller (C or Python) as ``regatta run`` runs it, and the world steps in
lock-step with the agent:

- **actions**: the velocities (rad/s, or m/s for a linear motor) of the agent robot's motors,
  in their device order: a float32 ``Box`` bounded by each motor's ``maxVelocity``;
- **observations**: a ``Dict`` of the robot's sensors by device name, each enabled at the
  world's basic time step (distance, light and position sensors: one value; GPS, compass,
  accelerometer, gyro: three; inertial unit: roll, pitch, yaw; camera: height × width × RGB
  bytes). ``devices=`` narrows it to the named ones.
- **reward** and **termination**: functions of the observation and ``info`` that the caller
  gives (``reward=``, ``terminated=``); by default 0 and never. An episode is truncated after
  ``duration`` simulated seconds.

Each episode is one ``regatta run --extern`` process (the agent robot's controller replaced by
``<extern>``), seeded by ``reset(seed=…)``: the same seed gives the same episode, bit for bit.
The agent's side speaks to it through regatta's Webots controller library (``regatta
webots-sdk``, built once into a cache folder), in this process.

The ``regatta`` command line is needed: ``regatta=`` names it, else ``$REGATTA_BIN``, else
``regatta`` on the ``PATH``; so is a C compiler (``cc``) the first time, to build the library.
"""

from __future__ import annotations

import collections
import importlib
import json
import math
import os
import shutil
import subprocess
import sys
import threading
from typing import Any, Callable, Optional, Sequence, Union

import gymnasium
import numpy as np
from gymnasium import spaces

#: Observation and reward functions take the observation and the step's info.
StepFunction = Callable[[dict, dict], Any]

_URL = "REGATTA_CONTROLLER_URL="


def _regatta_binary(given: Optional[Union[str, os.PathLike]]) -> str:
    for candidate in (given, os.environ.get("REGATTA_BIN"), shutil.which("regatta")):
        if candidate and os.path.exists(candidate):
            return os.fspath(candidate)
    raise FileNotFoundError(
        "the regatta command line is needed: pass regatta=PATH, set REGATTA_BIN, or put "
        "`regatta` on the PATH (cargo install --path tools, or cargo build -p regatta)"
    )


def _controller_module(binary: str, sdk: Optional[Union[str, os.PathLike]]):
    """Imports the ``controller`` package that ``regatta webots-sdk`` writes (built once into
    ``sdk``, by default a cache folder per regatta version)."""
    if sdk is None:
        version = subprocess.run(
            [binary, "--version"], capture_output=True, text=True, check=True
        ).stdout.split()[-1]
        cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(
            os.path.expanduser("~"), ".cache"
        )
        sdk = os.path.join(cache, "regatta", f"webots-sdk-{version}")
    sdk = os.fspath(sdk)
    package = os.path.join(sdk, "python")
    if not os.path.exists(os.path.join(package, "controller", "libregatta_controller.so")):
        result = subprocess.run(
            [binary, "webots-sdk", sdk], capture_output=True, text=True
        )
        if result.returncode != 0:
            raise RuntimeError(f"regatta webots-sdk {sdk} failed:\n{result.stderr}")
    if package not in sys.path:
        sys.path.insert(0, package)
    controller = importlib.import_module("controller")
    library = controller._wb.lib
    # A vanished simulator ends the step (-1), not this process.
    library.regatta_controller_embed(1)
    return controller


class _Episode:
    """One ``regatta run --extern`` process and the agent's connection to it."""

    def __init__(self, command: list, cwd: Optional[str], timeout: float):
        self.process = subprocess.Popen(
            command,
            cwd=cwd,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            errors="replace",
        )
        self.lines: collections.deque = collections.deque(maxlen=40)
        found = threading.Event()
        self.url: Optional[str] = None

        def drain() -> None:
            # Everything the run prints is read, so that it never blocks on a full pipe.
            for line in self.process.stderr:
                self.lines.append(line.rstrip("\n"))
                if self.url is None and _URL in line:
                    self.url = line.split(_URL, 1)[1].split()[0]
                    found.set()
            found.set()

        self.reader = threading.Thread(target=drain, daemon=True)
        self.reader.start()
        found.wait(timeout)
        if self.url is None:
            self.close()
            raise RuntimeError(
                "regatta did not start the episode:\n" + "\n".join(self.lines)
            )

    def failure(self) -> str:
        return "\n".join(self.lines)

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.reader.join(5)


class WebotsEnv(gymnasium.Env):
    """One robot of a Webots project's world as a Gymnasium environment.

    Args:
        world: the world file (``project/worlds/W.wbt``).
        robot: the robot the agent drives (None: the world's first robot).
        duration: simulated seconds after which an episode is truncated.
        devices: the sensors observed, by name (None: every sensor the robot has).
        reward: ``reward(observation, info) -> float`` (None: 0).
        terminated: ``terminated(observation, info) -> bool`` (None: never).
        lenient: read the world leniently (Webots nodes regatta skips are warnings).
        regatta: the ``regatta`` command line (None: ``$REGATTA_BIN``, else the ``PATH``'s).
        sdk: the folder of the controller library (None: a cache folder).
        timeout: wall-clock seconds to wait for an episode's process to start.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        world: Union[str, os.PathLike],
        robot: Optional[str] = None,
        duration: float = 20.0,
        devices: Optional[Sequence[str]] = None,
        reward: Optional[StepFunction] = None,
        terminated: Optional[StepFunction] = None,
        lenient: bool = False,
        regatta: Optional[Union[str, os.PathLike]] = None,
        sdk: Optional[Union[str, os.PathLike]] = None,
        timeout: float = 30.0,
    ):
        if not (duration > 0 and math.isfinite(duration)):
            raise ValueError(f"duration must be a positive number of seconds, found {duration}")
        self.world = os.path.abspath(os.fspath(world))
        if not os.path.isfile(self.world):
            raise FileNotFoundError(f"no world file {self.world}")
        self.duration = float(duration)
        self.lenient = lenient
        self.timeout = timeout
        self._reward = reward
        self._terminated = terminated
        self._binary = _regatta_binary(regatta)
        self._controller = _controller_module(self._binary, sdk)
        self.robot_name = robot if robot is not None else self._first_robot()
        self._episode: Optional[_Episode] = None
        self._robot = None
        # The spaces come from the robot's devices: one episode's start describes them.
        self._connect(seed=None)
        self._sensors = self._choose_sensors(devices)
        self._motors = [
            d for d in self._devices() if self._kind(d) in ("RotationalMotor", "LinearMotor")
        ]
        limits = np.array([m.getMaxVelocity() for m in self._motors], dtype=np.float32)
        limits[~np.isfinite(limits)] = np.finfo(np.float32).max
        self.action_space = spaces.Box(low=-limits, high=limits, dtype=np.float32)
        self.observation_space = spaces.Dict(
            {d.getName(): self._space(d) for d in self._sensors}
        )
        self.motor_names = [m.getName() for m in self._motors]

    # -- the world and its robot ----------------------------------------------------------

    def _run(self, args: list) -> subprocess.CompletedProcess:
        return subprocess.run(
            [self._binary, *args], capture_output=True, text=True, errors="replace"
        )

    def _first_robot(self) -> str:
        # Nothing of the project's runs: its controllers are left out.
        args = ["run", self.world, "--steps", "0", "--json", "--builtin-only", "--lenient"]
        result = self._run(args)
        if result.returncode != 0:
            raise ValueError(f"{self.world} does not run:\n{result.stderr}")
        robots = json.loads(result.stdout)["robots"]
        if not robots:
            raise ValueError(f"{self.world} has no robot")
        return robots[0]["name"]

    def _command(self, seed: Optional[int]) -> list:
        command = [
            self._binary,
            "run",
            self.world,
            "--extern",
            "--controller",
            f"{self.robot_name}=<extern>",
            # A little more than an episode, so that the run never ends before it.
            "--duration",
            repr(self.duration + 1.0),
        ]
        if seed is not None:
            command += ["--seed", str(seed)]
        if self.lenient:
            command.append("--lenient")
        return command

    def _connect(self, seed: Optional[int]) -> None:
        self._disconnect()
        self._episode = _Episode(self._command(seed), os.path.dirname(self.world), self.timeout)
        os.environ["REGATTA_CONTROLLER_URL"] = self._episode.url
        controller = self._controller
        init = controller._wb.function("wb_robot_init", controller._wb.c_int)
        if not init():
            failure = self._episode.failure()
            self._disconnect()
            raise RuntimeError(f"cannot connect to the episode:\n{failure}")
        # Device objects are per connection.
        importlib.import_module("controller.device")._devices.clear()
        self._robot = controller.Robot()
        self._step_ms = int(self._robot.getBasicTimeStep())

    def _disconnect(self) -> None:
        if self._robot is not None:
            cleanup = self._controller._wb.function("wb_robot_cleanup", None)
            cleanup()
            self._robot = None
        if self._episode is not None:
            self._episode.close()
            self._episode = None

    def _devices(self) -> list:
        return list(self._robot.devices.values())

    @staticmethod
    def _kind(device) -> str:
        return type(device).__name__

    _SENSORS = {
        "DistanceSensor": 1,
        "LightSensor": 1,
        "PositionSensor": 1,
        "TouchSensor": 1,
        "GPS": 3,
        "Compass": 3,
        "Accelerometer": 3,
        "Gyro": 3,
        "InertialUnit": 3,
        "Camera": None,
    }

    def _choose_sensors(self, names: Optional[Sequence[str]]) -> list:
        sensors = [d for d in self._devices() if self._kind(d) in self._SENSORS]
        if names is None:
            return sensors
        by_name = {d.getName(): d for d in sensors}
        missing = [n for n in names if n not in by_name]
        if missing:
            raise ValueError(
                f"robot '{self.robot_name}' has no sensor {', '.join(map(repr, missing))}; "
                f"it has {', '.join(sorted(by_name))}"
            )
        return [by_name[n] for n in names]

    def _space(self, device) -> spaces.Space:
        kind = self._kind(device)
        if kind == "Camera":
            shape = (device.getHeight(), device.getWidth(), 3)
            return spaces.Box(low=0, high=255, shape=shape, dtype=np.uint8)
        # Unbounded: a lookup table's noise reads beyond its values, as in Webots.
        size = self._SENSORS[kind]
        return spaces.Box(low=-np.inf, high=np.inf, shape=(size,), dtype=np.float64)

    def _start_episode(self) -> None:
        for device in self._sensors:
            device.enable(self._step_ms)
        for motor in self._motors:
            motor.setPosition(float("inf"))
            motor.setVelocity(0.0)

    def _read(self, device) -> np.ndarray:
        kind = self._kind(device)
        if kind == "Camera":
            image = device.getImage()
            h, w = device.getHeight(), device.getWidth()
            if not image:
                return np.zeros((h, w, 3), dtype=np.uint8)
            # Webots' BGRA, as RGB.
            return np.frombuffer(image, dtype=np.uint8).reshape(h, w, 4)[:, :, 2::-1].copy()
        if kind == "InertialUnit":
            return np.asarray(device.getRollPitchYaw(), dtype=np.float64)
        if self._SENSORS[kind] == 3:
            return np.asarray(device.getValues(), dtype=np.float64)
        return np.asarray([device.getValue()], dtype=np.float64)

    def _observation(self) -> dict:
        return {d.getName(): self._read(d) for d in self._sensors}

    def _info(self) -> dict:
        return {"time": self._robot.getTime(), "robot": self.robot_name}

    # -- Gymnasium -------------------------------------------------------------------------

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        super().reset(seed=seed)
        run_seed = seed if seed is not None else int(self.np_random.integers(0, 2**31 - 1))
        self._connect(run_seed)
        self._start_episode()
        if self._robot.step(self._step_ms) == -1:
            raise RuntimeError(f"the episode ended at once:\n{self._episode.failure()}")
        return self._observation(), self._info()

    def step(self, action):
        if self._robot is None:
            raise RuntimeError("call reset() before step()")
        action = np.asarray(action, dtype=np.float64).reshape(-1)
        if action.shape != (len(self._motors),):
            raise ValueError(
                f"an action is {len(self._motors)} motor velocities "
                f"({', '.join(self.motor_names)}), found shape {action.shape}"
            )
        for motor, velocity, limit in zip(self._motors, action, self.action_space.high):
            motor.setVelocity(float(np.clip(velocity, -limit, limit)))
        if self._robot.step(self._step_ms) == -1:
            raise RuntimeError(
                f"the simulation of robot '{self.robot_name}' ended before its episode:\n"
                + self._episode.failure()
            )
        observation = self._observation()
        info = self._info()
        reward = float(self._reward(observation, info)) if self._reward else 0.0
        terminated = bool(self._terminated(observation, info)) if self._terminated else False
        truncated = info["time"] >= self.duration - 1e-9
        return observation, reward, terminated, truncated, info

    def close(self) -> None:
        self._disconnect()


def register() -> None:
    """Registers ``regatta/Webots-v0`` (done on import when Gymnasium is installed)."""
    if "regatta/Webots-v0" not in gymnasium.envs.registry:
        gymnasium.register(id="regatta/Webots-v0", entry_point="regatta.webots:WebotsEnv")


__all__ = ["WebotsEnv", "register"]
