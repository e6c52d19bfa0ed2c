"""regatta's Webots controller library, loaded once through ctypes.

Every class of this package is a thin layer over the C library that C controllers link
(webots/c/regatta_controller.c), built as a shared library beside this file: the library is
the one implementation of the controller protocol, and Python only converts types.
"""

import ctypes
import os

_HERE = os.path.dirname(os.path.abspath(__file__))
_PATH = os.environ.get('REGATTA_CONTROLLER_LIBRARY') or os.path.join(_HERE, 'libregatta_controller.so')

try:
    lib = ctypes.CDLL(_PATH)
except OSError as error:
    raise ImportError(
        "regatta's controller library is missing (%s): this module is prepared by `regatta run`, "
        'which runs Python controllers (%s)' % (_PATH, error)) from None

c_double_p = ctypes.POINTER(ctypes.c_double)
c_char_p = ctypes.c_char_p
c_void_p = ctypes.c_void_p
c_int = ctypes.c_int
c_double = ctypes.c_double
c_bool = ctypes.c_bool
c_ushort = ctypes.c_ushort
c_ubyte_p = ctypes.POINTER(ctypes.c_ubyte)


_INTEGERS = (ctypes.c_int, ctypes.c_ushort)


def function(name, restype, *argtypes):
    """The C function `name`, with its result and argument types declared. A function whose
    arguments are all integers (device tags, periods) is called without conversions, which
    costs half as much: this package passes it Python ints only."""
    f = getattr(lib, name)
    f.restype = restype
    if not all(t in _INTEGERS for t in argtypes):
        f.argtypes = list(argtypes)
    return f


def text(value):
    """A C string as Python text (None stays None)."""
    return None if value is None else value.decode('utf-8', 'replace')


def cstr(value):
    """Python text as a C string."""
    if isinstance(value, bytes):
        return value
    return str(value).encode('utf-8')


def values(pointer, count):
    """`count` doubles from a C pointer as a list (None for a NULL pointer)."""
    if not pointer:
        return None
    return pointer[:count]


def doubles(values_, count):
    """A Python sequence of numbers as a C array of `count` doubles."""
    values_ = list(values_)
    if len(values_) != count:
        raise ValueError('expected %d values, got %d' % (count, len(values_)))
    return (ctypes.c_double * count)(*[float(v) for v in values_])
