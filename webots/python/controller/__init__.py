"""Webots' Python controller API, as regatta runs it: `from controller import Robot`.

Written from Webots' published reference manual (the class and method names, arguments and
results are Webots'); the code is regatta's: a layer of Python classes over regatta's
controller library (the same C library C controllers link), loaded through ctypes.
"""

from .accelerometer import Accelerometer
from .ansi_codes import AnsiCodes
from .camera import Camera
from .compass import Compass
from .device import Device
from .distance_sensor import DistanceSensor
from .emitter import Emitter
from .gps import GPS
from .gyro import Gyro
from .inertial_unit import InertialUnit
from .keyboard import Keyboard
from .led import LED
from .light_sensor import LightSensor
from .motor import LinearMotor, Motor, RotationalMotor
from .node import Field, Node
from .position_sensor import PositionSensor
from .receiver import Receiver
from .robot import Robot
from .supervisor import Supervisor
from .touch_sensor import TouchSensor

__all__ = [
    'Accelerometer', 'AnsiCodes', 'Camera', 'Compass', 'Device', 'DistanceSensor', 'Emitter',
    'Field', 'GPS', 'Gyro', 'InertialUnit', 'Keyboard', 'LED', 'LightSensor', 'LinearMotor',
    'Motor', 'Node', 'PositionSensor', 'Receiver', 'Robot', 'RotationalMotor', 'Supervisor',
    'TouchSensor',
]
