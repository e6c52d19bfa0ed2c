"""Webots' `GPS`."""

from . import _wb
from ._wb import c_char_p, c_double, c_double_p, c_int, c_ushort, function
from .device import Sensor, sampled

_get_values = function('wb_gps_get_values', c_double_p, c_ushort)
_get_speed = function('wb_gps_get_speed', c_double, c_ushort)
_get_speed_vector = function('wb_gps_get_speed_vector', c_double_p, c_ushort)
_get_coordinate_system = function('wb_gps_get_coordinate_system', c_int, c_ushort)
_convert = function('wb_gps_convert_to_degrees_minutes_seconds', c_char_p, c_double)


class GPS(Sensor):
    LOCAL = 0
    WGS84 = 1
    _enable, _disable, _get_sampling_period = sampled('gps')

    def getValues(self):
        return _wb.values(_get_values(self._tag), 3)

    def getSpeed(self):
        return _get_speed(self._tag)

    def getSpeedVector(self):
        return _wb.values(_get_speed_vector(self._tag), 3)

    def getCoordinateSystem(self):
        return _get_coordinate_system(self._tag)

    @staticmethod
    def convertToDegreesMinutesSeconds(decimalDegrees):
        return _wb.text(_convert(decimalDegrees))

    @property
    def value(self):
        return self.getValues()
