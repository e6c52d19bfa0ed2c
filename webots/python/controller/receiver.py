"""Webots' `Receiver`."""

import ctypes
import struct

from . import _wb
from ._wb import c_double, c_double_p, c_int, c_ushort, c_void_p, function
from .device import Sensor, sampled

_get_queue_length = function('wb_receiver_get_queue_length', c_int, c_ushort)
_next_packet = function('wb_receiver_next_packet', None, c_ushort)
_get_data_size = function('wb_receiver_get_data_size', c_int, c_ushort)
_get_data = function('wb_receiver_get_data', c_void_p, c_ushort)
_get_signal_strength = function('wb_receiver_get_signal_strength', c_double, c_ushort)
_get_emitter_direction = function('wb_receiver_get_emitter_direction', c_double_p, c_ushort)
_set_channel = function('wb_receiver_set_channel', None, c_ushort, c_int)
_get_channel = function('wb_receiver_get_channel', c_int, c_ushort)


class Receiver(Sensor):
    CHANNEL_BROADCAST = -1
    _enable, _disable, _get_sampling_period = sampled('receiver')

    def getQueueLength(self):
        return _get_queue_length(self._tag)

    def nextPacket(self):
        _next_packet(self._tag)

    def getDataSize(self):
        return _get_data_size(self._tag)

    def getBytes(self):
        """The head packet's bytes (b'' when the queue is empty)."""
        pointer = _get_data(self._tag)
        if not pointer:
            return b''
        return ctypes.string_at(pointer, _get_data_size(self._tag))

    def getData(self):
        """The head packet's bytes (Webots' older name of `getBytes`)."""
        return self.getBytes()

    def getString(self):
        """The head packet as text, up to its first NUL."""
        return self.getBytes().split(b'\0', 1)[0].decode('utf-8', 'replace')

    def getFloats(self):
        """The head packet as doubles."""
        data = self.getBytes()
        return list(struct.unpack('%dd' % (len(data) // 8), data[:len(data) // 8 * 8]))

    def getSignalStrength(self):
        return _get_signal_strength(self._tag)

    def getEmitterDirection(self):
        return _wb.values(_get_emitter_direction(self._tag), 3)

    def setChannel(self, channel):
        _set_channel(self._tag, int(channel))

    def getChannel(self):
        return _get_channel(self._tag)

    @property
    def queue_length(self):
        return self.getQueueLength()

    @property
    def channel(self):
        return self.getChannel()

    @channel.setter
    def channel(self, channel):
        self.setChannel(channel)
