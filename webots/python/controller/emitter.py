"""Webots' `Emitter`."""

import struct

from . import _wb
from ._wb import c_char_p, c_double, c_int, c_ushort, function
from .device import Device

_send = function('wb_emitter_send', c_int, c_ushort, c_char_p, c_int)
_get_buffer_size = function('wb_emitter_get_buffer_size', c_int, c_ushort)
_get_channel = function('wb_emitter_get_channel', c_int, c_ushort)
_set_channel = function('wb_emitter_set_channel', None, c_ushort, c_int)
_get_range = function('wb_emitter_get_range', c_double, c_ushort)
_set_range = function('wb_emitter_set_range', None, c_ushort, c_double)


class Emitter(Device):
    CHANNEL_BROADCAST = -1

    def send(self, message, length=None):
        """Queues a packet: bytes as they are, text as UTF-8 with a terminating NUL (what a C
        receiver reads as a string), a list or tuple of numbers as doubles (what
        `Receiver.getFloats` reads). Returns 1 when queued, 0 when the buffer is full."""
        if isinstance(message, str):
            data = message.encode('utf-8') + b'\0'
        elif isinstance(message, (bytes, bytearray, memoryview)):
            data = bytes(message)
        elif isinstance(message, (list, tuple)):
            data = struct.pack('%dd' % len(message), *[float(v) for v in message])
        else:
            raise TypeError('Emitter.send: a message is str, bytes, or a list of numbers, not %s'
                            % type(message).__name__)
        if length is not None:
            data = data[:int(length)]
        return _send(self._tag, data, len(data))

    def getBufferSize(self):
        return _get_buffer_size(self._tag)

    def getChannel(self):
        return _get_channel(self._tag)

    def setChannel(self, channel):
        _set_channel(self._tag, int(channel))

    def getRange(self):
        return _get_range(self._tag)

    def setRange(self, range):
        _set_range(self._tag, range)

    @property
    def channel(self):
        return self.getChannel()

    @channel.setter
    def channel(self, channel):
        self.setChannel(channel)

    @property
    def range(self):
        return self.getRange()

    @range.setter
    def range(self, range):
        self.setRange(range)
