"""lockstep.airsim: the `airsim` Python API over Lockstep (NED metres from each drone's
spawn point; degrees in YawMode and rotate* calls, radians in moveByRollPitchYaw*, as
AirSim). `import airsim` resolves here with the drop-in package on the path. Calls Lockstep
cannot do raise LockstepUnsupported naming the call and why (docs/compatibility.md)."""
import sys
import time

from lockstep import ClientError, CommandRejected  # noqa: F401

from .client import LockstepUnsupported, MultirotorClient, VehicleClient  # noqa: F401
from .types import *  # noqa: F401,F403


def wait_key(message=''):
    """AirSim's helper waits for a key press; scripts run unattended here, so it returns at once."""
    if message:
        print(message)


def string_to_uint8_array(bstr):
    import numpy as np
    return np.frombuffer(bstr, np.uint8)


def string_to_float_array(bstr):
    import numpy as np
    return np.frombuffer(bstr, np.float32)


def list_to_2d_float_array(flst, width, height):
    import numpy as np
    return np.reshape(np.asarray(flst, np.float32), (height, width))


def get_pfm_array(response):
    return list_to_2d_float_array(response.image_data_float, response.width, response.height)


def write_file(filename, bstr):
    with open(filename, 'wb') as afile:
        afile.write(bstr)


def write_png(filename, image):
    from lockstep.carla.sensor_data import write_png as _w
    _w(filename, image[..., ::-1] if image.ndim == 3 else image)


def write_pfm(file, image, scale=1):
    import numpy as np
    image = np.flipud(np.asarray(image, dtype=np.float32))
    color = image.ndim == 3 and image.shape[2] == 3
    with open(file, 'wb') as f:
        f.write(b'PF\n' if color else b'Pf\n')
        f.write(b'%d %d\n' % (image.shape[1], image.shape[0]))
        f.write(b'%f\n' % (-scale if sys.byteorder == 'little' else scale))
        image.tofile(f)
