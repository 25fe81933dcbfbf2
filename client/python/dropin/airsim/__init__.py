"""Drop-in `airsim`: this package is lockstep.airsim (see docs/python.md)."""
import sys

import lockstep.airsim as _impl

sys.modules['airsim'] = _impl
