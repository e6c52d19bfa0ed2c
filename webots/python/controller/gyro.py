"""Webots' `Gyro`: the robot's planar motion (regatta's robots are kinematic)."""

from .device import VectorSensor


class Gyro(VectorSensor, kind='gyro'):
    pass
