"""Webots' `DistanceSensor`."""

from . import _wb
from ._wb import c_double, c_double_p, c_int, c_ushort, function
from .device import Sensor, sampled

_get_value = function('wb_distance_sensor_get_value', c_double, c_ushort)
_get_min_value = function('wb_distance_sensor_get_min_value', c_double, c_ushort)
_get_max_value = function('wb_distance_sensor_get_max_value', c_double, c_ushort)
_get_aperture = function('wb_distance_sensor_get_aperture', c_double, c_ushort)
_get_type = function('wb_distance_sensor_get_type', c_int, c_ushort)
_get_lookup_table_size = function('wb_distance_sensor_get_lookup_table_size', c_int, c_ushort)
_get_lookup_table = function('wb_distance_sensor_get_lookup_table', c_double_p, c_ushort)


class DistanceSensor(Sensor):
    GENERIC = 0
    INFRA_RED = 1
    SONAR = 2
    LASER = 3
    _enable, _disable, _get_sampling_period = sampled('distance_sensor')

    def getValue(self):
        return _get_value(self._tag)

    def getMinValue(self):
        return _get_min_value(self._tag)

    def getMaxValue(self):
        return _get_max_value(self._tag)

    def getAperture(self):
        return _get_aperture(self._tag)

    def getType(self):
        return _get_type(self._tag)

    def getLookupTable(self):
        """The lookup table, flat: distance, value, noise of each row."""
        return _wb.values(_get_lookup_table(self._tag), 3 * _get_lookup_table_size(self._tag)) or []

    @property
    def value(self):
        return self.getValue()

    @property
    def lookup_table(self):
        return self.getLookupTable()
