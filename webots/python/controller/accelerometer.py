"""Webots' `Accelerometer`: the robot's planar motion (regatta's robots are kinematic)."""

from .device import VectorSensor


class Accelerometer(VectorSensor, kind='accelerometer'):
    pass
