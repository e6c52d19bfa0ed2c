"""Webots' `Supervisor`: a robot that reads and changes the world."""

from . import _wb
from ._wb import c_char_p, c_int, c_void_p, function
from .node import Field, Node
from .robot import Robot

_get_root = function('wb_supervisor_node_get_root', c_void_p)
_get_self = function('wb_supervisor_node_get_self', c_void_p)
_get_from_def = function('wb_supervisor_node_get_from_def', c_void_p, c_char_p)
_get_from_id = function('wb_supervisor_node_get_from_id', c_void_p, c_int)
_quit = function('wb_supervisor_simulation_quit', None, c_int)
_reset = function('wb_supervisor_simulation_reset', None)
_reset_physics = function('wb_supervisor_simulation_reset_physics', None)
_get_mode = function('wb_supervisor_simulation_get_mode', c_int)
_set_mode = function('wb_supervisor_simulation_set_mode', None, c_int)


class Supervisor(Robot):
    SIMULATION_MODE_PAUSE = 0
    SIMULATION_MODE_REAL_TIME = 1
    SIMULATION_MODE_FAST = 2

    def getRoot(self):
        return Node.of(_get_root())

    def getSelf(self):
        return Node.of(_get_self())

    def getFromDef(self, name):
        """The node `DEF name` (a path `A.B` reaches inside PROTOs); None when there is none."""
        return Node.of(_get_from_def(_wb.cstr(name)))

    def getFromId(self, id):
        return Node.of(_get_from_id(int(id)))

    def simulationQuit(self, status):
        _quit(int(status))

    def simulationReset(self):
        _reset()

    def simulationResetPhysics(self):
        _reset_physics()

    def simulationGetMode(self):
        return _get_mode()

    def simulationSetMode(self, mode):
        _set_mode(int(mode))

    @property
    def simulation_mode(self):
        return self.simulationGetMode()

    @simulation_mode.setter
    def simulation_mode(self, mode):
        self.simulationSetMode(mode)


__all__ = ['Supervisor', 'Node', 'Field']
