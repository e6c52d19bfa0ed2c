"""Webots' `Compass`."""

from .device import VectorSensor


class Compass(VectorSensor, kind='compass'):
    pass
