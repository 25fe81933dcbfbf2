"""lockstep.airsim: AirSim 1.8's `airsim` Python API over Lockstep (NED metres from each
vehicle's start; degrees in YawMode and rotate* calls, radians in moveByRollPitchYaw*, as
AirSim). `import airsim` resolves here with the drop-in package on the path. AirSim's
settings.json is read from ~/Documents/AirSim/settings.json ($LOCKSTEP_AIRSIM_SETTINGS).
Calls Lockstep cannot do raise LockstepUnsupported naming the call and why
(docs/compatibility.md)."""
import inspect
import logging
import re
import sys

from lockstep import ClientError, CommandRejected  # noqa: F401

from .client import CarClient, LockstepUnsupported, MultirotorClient, VehicleClient  # noqa: F401
from .settings import SettingsError  # noqa: F401
from .types import *  # noqa: F401,F403

if not logging.getLogger('lockstep.airsim').handlers:
    _h = logging.StreamHandler()
    _h.setFormatter(logging.Formatter('%(message)s'))
    logging.getLogger('lockstep.airsim').addHandler(_h)
    logging.getLogger('lockstep.airsim').propagate = False


def string_to_uint8_array(bstr):
    import numpy as np
    return np.fromstring(bstr, np.uint8) if isinstance(bstr, str) else np.frombuffer(bstr, np.uint8)


def string_to_float_array(bstr):
    import numpy as np
    return np.frombuffer(bstr, np.float32)


def list_to_2d_float_array(flst, width, height):
    import numpy as np
    return np.reshape(np.asarray(flst, np.float32), (height, width))


def get_pfm_array(response):
    return list_to_2d_float_array(response.image_data_float, response.width, response.height)


def get_public_fields(obj):
    return [attr for attr in dir(obj) if not (attr.startswith('_') or inspect.isbuiltin(attr) or
                                              inspect.isfunction(attr) or inspect.ismethod(attr))]


def to_dict(obj):
    return dict([attr, getattr(obj, attr)] for attr in get_public_fields(obj))


def to_str(obj):
    return str(to_dict(obj))


def write_file(filename, bstr):
    with open(filename, 'wb') as afile:
        afile.write(bstr)


def wait_key(message=''):
    """AirSim's helper waits for a key press; scripts run unattended here, so it prints and returns."""
    if message:
        print(message)


def read_pfm(file):
    """AirSim's read_pfm: (data, scale) of a PFM file (rows bottom first on disk, top first here)."""
    import numpy as np
    with open(file, 'rb') as f:
        header = f.readline().rstrip()
        if header == b'PF':
            color = True
        elif header == b'Pf':
            color = False
        else:
            raise Exception('Not a PFM file.')
        dim = re.match(br'^(\d+)\s(\d+)\s$', f.readline())
        if not dim:
            raise Exception('Malformed PFM header.')
        width, height = map(int, dim.groups())
        scale = float(f.readline().rstrip())
        endian = '<' if scale < 0 else '>'
        scale = abs(scale)
        data = np.fromfile(f, endian + 'f')
    shape = (height, width, 3) if color else (height, width)
    return np.flipud(np.reshape(data, shape)), scale


def write_pfm(file, image, scale=1):
    """AirSim's write_pfm: float32 image (H x W or H x W x 3), rows written bottom first."""
    import numpy as np
    image = np.asarray(image)
    if image.dtype.name != 'float32':
        raise Exception('Image dtype must be float32.')
    image = np.flipud(image)
    if image.ndim == 3 and image.shape[2] == 3:
        color = True
    elif image.ndim == 2 or image.ndim == 3 and image.shape[2] == 1:
        color = False
    else:
        raise Exception('Image must have H x W x 3, H x W x 1 or H x W dimensions.')
    with open(file, 'wb') as f:
        f.write(b'PF\n' if color else b'Pf\n')
        f.write(b'%d %d\n' % (image.shape[1], image.shape[0]))
        endian = image.dtype.byteorder
        if endian == '<' or endian == '=' and sys.byteorder == 'little':
            scale = -scale
        f.write(b'%f\n' % scale)
        image.tofile(f)


def write_png(filename, image):
    """AirSim's write_png: an H x W x 3 (BGR, as AirSim's) or H x W x 4 uint8 image."""
    import numpy as np
    from .client import _png
    image = np.asarray(image, dtype=np.uint8)
    if image.ndim == 3 and image.shape[2] == 3:
        image = np.concatenate([image[..., ::-1], np.full(image.shape[:2] + (1,), 255, np.uint8)], axis=2)
    elif image.ndim == 3 and image.shape[2] == 4:
        image = image[..., [2, 1, 0, 3]]
    with open(filename, 'wb') as f:
        f.write(_png(image))
