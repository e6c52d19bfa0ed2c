"""Webots' `InertialUnit`."""

from . import _wb
from ._wb import c_double, c_double_p, c_ushort, function
from .device import Sensor, sampled

_get_roll_pitch_yaw = function('wb_inertial_unit_get_roll_pitch_yaw', c_double_p, c_ushort)
_get_quaternion = function('wb_inertial_unit_get_quaternion', c_double_p, c_ushort)
_get_noise = function('wb_inertial_unit_get_noise', c_double, c_ushort)


class InertialUnit(Sensor):
    _enable, _disable, _get_sampling_period = sampled('inertial_unit')

    def getRollPitchYaw(self):
        return _wb.values(_get_roll_pitch_yaw(self._tag), 3)

    def getQuaternion(self):
        return _wb.values(_get_quaternion(self._tag), 4)

    def getNoise(self):
        return _get_noise(self._tag)

    @property
    def roll_pitch_yaw(self):
        return self.getRollPitchYaw()
