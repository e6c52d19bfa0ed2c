"""Webots' `Gyro`: the robot's planar motion (regatta's robots are kinematic)."""

from . import _wb
from ._wb import c_double_p, c_int, c_ushort, function
from .device import Sensor, sampled

_get_values = function('wb_gyro_get_values', c_double_p, c_ushort)
_get_lookup_table_size = function('wb_gyro_get_lookup_table_size', c_int, c_ushort)
_get_lookup_table = function('wb_gyro_get_lookup_table', c_double_p, c_ushort)


class Gyro(Sensor):
    _enable, _disable, _get_sampling_period = sampled('gyro')

    def getValues(self):
        return _wb.values(_get_values(self._tag), 3)

    def getLookupTable(self):
        return _wb.values(_get_lookup_table(self._tag), 3 * _get_lookup_table_size(self._tag)) or []

    @property
    def value(self):
        return self.getValues()
