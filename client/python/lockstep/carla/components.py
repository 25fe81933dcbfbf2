"""Actor components and bones (CARLA's get_component_*/get_bone_*/get_socket_* and the
walker pose calls) over Lockstep's actors, which are boxes and capsules in ground_sim.

Walkers get one fixed skeleton with CARLA's bone names (the `crl_*` rig of its pedestrians),
standing upright, scaled to the blueprint's height; vehicles get bones at their wheels and
named light components at the corners of their bounding box. Transforms are in CARLA's
frames: `relative` to the parent bone, `component` to the actor's origin, `world`."""
from .geometry import Location, Rotation, Transform

__all__ = ['BoneTransformDataIn', 'BoneTransformDataOut', 'WalkerBoneControlIn', 'WalkerBoneControlOut']


class BoneTransformDataIn:
    """carla.BoneTransformDataIn: a bone name and its transform relative to its parent."""

    def __init__(self, bone_name='', transform=None):
        self.bone_name = str(bone_name)
        self.transform = Transform(transform.location, transform.rotation) if transform is not None else Transform()


class BoneTransformDataOut:
    """carla.BoneTransformDataOut: name, world, component and relative transforms."""

    def __init__(self, name, world, component, relative):
        self.name, self.world, self.component, self.relative = name, world, component, relative

    def __repr__(self):
        return 'BoneTransformDataOut(name=%s, world=%r)' % (self.name, self.world)


class WalkerBoneControlIn:
    """carla.WalkerBoneControlIn(list of (bone name, Transform) or BoneTransformDataIn)."""

    def __init__(self, bone_transforms=None):
        self.bone_transforms = []
        for b in bone_transforms or []:
            self.bone_transforms.append(b if isinstance(b, BoneTransformDataIn) else BoneTransformDataIn(b[0], b[1]))


class WalkerBoneControlOut:
    """carla.WalkerBoneControlOut: `bone_transforms`, a list of BoneTransformDataOut."""

    def __init__(self, bone_transforms):
        self.bone_transforms = list(bone_transforms)


def _walker_rig():
    """(name, parent, (x, y, z) as a share of the height, from the feet; y < 0 = left)."""
    rig = [('crl_root', None, (0.0, 0.0, 0.0)), ('crl_hips__C', 'crl_root', (0.0, 0.0, 0.53)),
           ('crl_spine__C', 'crl_hips__C', (0.0, 0.0, 0.60)), ('crl_spine01__C', 'crl_spine__C', (0.0, 0.0, 0.72)),
           ('crl_neck__C', 'crl_spine01__C', (0.0, 0.0, 0.84)), ('crl_Head__C', 'crl_neck__C', (0.0, 0.0, 0.89)),
           ('crl_eye__L', 'crl_Head__C', (0.06, -0.018, 0.935)), ('crl_eye__R', 'crl_Head__C', (0.06, 0.018, 0.935))]
    fingers = {'Thumb': (0.025, -0.005), 'Index': (0.02, 0.0), 'Middle': (0.008, 0.0), 'Ring': (-0.004, 0.0),
               'Pinky': (-0.014, 0.0)}
    for side, s in (('L', -1.0), ('R', 1.0)):
        rig += [('crl_shoulder__' + side, 'crl_spine01__C', (0.0, s * 0.03, 0.80)),
                ('crl_arm__' + side, 'crl_shoulder__' + side, (0.0, s * 0.11, 0.80)),
                ('crl_foreArm__' + side, 'crl_arm__' + side, (0.0, s * 0.12, 0.62)),
                ('crl_hand__' + side, 'crl_foreArm__' + side, (0.0, s * 0.125, 0.48))]
        for f, (fx, fy) in fingers.items():
            parent = 'crl_hand__' + side
            for i, suffix in enumerate(('', '01', '02', 'End')):
                name = 'crl_hand%s%s__%s' % (f, suffix, side)
                rig.append((name, parent, (fx, s * (0.128 + fy), 0.465 - 0.018 * i)))
                parent = name
        rig += [('crl_thigh__' + side, 'crl_hips__C', (0.0, s * 0.05, 0.52)),
                ('crl_leg__' + side, 'crl_thigh__' + side, (0.01, s * 0.05, 0.285)),
                ('crl_foot__' + side, 'crl_leg__' + side, (0.0, s * 0.05, 0.04)),
                ('crl_toe__' + side, 'crl_foot__' + side, (0.07, s * 0.05, 0.012)),
                ('crl_toeEnd__' + side, 'crl_toe__' + side, (0.1, s * 0.05, 0.0))]
    return rig


_WALKER_RIG = _walker_rig()


def walker_bones(height):
    """[(name, parent, component Location)] of a walker of `height` m; the actor's origin
    is the capsule centre, as CARLA's walkers."""
    return [(n, p, Location(x * height, y * height, z * height - height / 2)) for n, p, (x, y, z) in _WALKER_RIG]


def vehicle_bones(half, wheel_radius=0.35):
    """CARLA's vehicle skeleton: Root at the origin (the base), one bone per wheel."""
    hx, hy = half[0], half[1]
    wx, wy = 0.6 * hx, 0.85 * hy
    return [('Root', None, Location(0, 0, 0)),
            ('Wheel_Front_Left', 'Root', Location(wx, -wy, wheel_radius)),
            ('Wheel_Front_Right', 'Root', Location(wx, wy, wheel_radius)),
            ('Wheel_Rear_Left', 'Root', Location(-wx, -wy, wheel_radius)),
            ('Wheel_Rear_Right', 'Root', Location(-wx, wy, wheel_radius))]


def vehicle_components(half):
    """Named components of a vehicle (CARLA's light components and its mesh), relative to
    the vehicle's origin (the base centre): lights at the corners of the bounding box."""
    hx, hy, hz = half
    out = {'VehicleMesh': Transform(Location(0, 0, 0))}
    for end, x, yaw in (('front', hx, 0.0), ('back', -hx, 180.0)):
        for side, y in (('l', -0.8 * hy), ('r', 0.8 * hy)):
            out['%s-blinker-%s-1' % (end, side)] = Transform(Location(x, y, 0.9 * hz), Rotation(yaw=yaw))
            out['%s-light-%s-1' % (end, side)] = Transform(Location(x, 0.6 * y / 0.8, 0.85 * hz), Rotation(yaw=yaw))
    return out
