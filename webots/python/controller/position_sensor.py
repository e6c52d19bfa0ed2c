"""Webots' `PositionSensor`."""

from ._wb import c_double, c_int, c_ushort, function
from .device import Sensor, device_of, sampled

_get_value = function('wb_position_sensor_get_value', c_double, c_ushort)
_get_type = function('wb_position_sensor_get_type', c_int, c_ushort)
_get_motor = function('wb_position_sensor_get_motor', c_ushort, c_ushort)
_get_brake = function('wb_position_sensor_get_brake', c_ushort, c_ushort)


class PositionSensor(Sensor):
    ROTATIONAL = 0
    LINEAR = 1
    _enable, _disable, _get_sampling_period = sampled('position_sensor')

    def getValue(self):
        return _get_value(self._tag)

    def getType(self):
        """ROTATIONAL (0) or LINEAR (1)."""
        from .motor import _joint_type
        return _joint_type(_get_type(self._tag))

    def getMotor(self):
        return device_of(_get_motor(self._tag))

    def getBrake(self):
        return device_of(_get_brake(self._tag))

    @property
    def value(self):
        return self.getValue()
