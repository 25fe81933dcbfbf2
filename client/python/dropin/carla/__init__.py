"""Drop-in `carla`: this package is lockstep.carla (see docs/python.md)."""
import sys

import lockstep.carla as _impl
from lockstep.carla import command as _command

sys.modules['carla'] = _impl
sys.modules['carla.command'] = _command
