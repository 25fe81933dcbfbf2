"""The carla and airsim modules have the names, fields and conventions scripts rely on
(no simulation needed)."""
import math

import pytest

import airsim
import carla


def test_drop_in_modules_are_lockstep():
    import lockstep.airsim
    import lockstep.carla
    assert carla is lockstep.carla
    assert airsim is lockstep.airsim
    assert carla.command.SpawnActor is lockstep.carla.command.SpawnActor


@pytest.mark.parametrize('name', [
    'Client', 'World', 'WorldSettings', 'Location', 'Rotation', 'Transform', 'Vector3D', 'BoundingBox',
    'VehicleControl', 'WalkerControl', 'WeatherParameters', 'Waypoint', 'Map', 'LaneType', 'LaneChange',
    'LaneMarking', 'LaneMarkingType', 'LaneMarkingColor', 'ColorConverter', 'TrafficManager', 'TrafficLightState',
    'AttachmentType', 'Image', 'LidarMeasurement', 'SemanticLidarMeasurement', 'IMUMeasurement', 'GnssMeasurement',
    'CollisionEvent', 'LaneInvasionEvent', 'ObstacleDetectionEvent', 'RadarMeasurement', 'Actor', 'Vehicle', 'Walker',
    'TrafficLight', 'Sensor', 'ActorBlueprint', 'BlueprintLibrary', 'WorldSnapshot', 'Timestamp', 'GeoLocation',
    'VehicleAckermannControl', 'AckermannControllerSettings', 'VehiclePhysicsControl', 'WheelPhysicsControl',
    'GearPhysicsControl', 'WalkerAIController', 'Junction', 'Landmark', 'LandmarkOrientation', 'LandmarkType',
    'VehicleLightState'])
def test_carla_names(name):
    assert hasattr(carla, name)


@pytest.mark.parametrize('name', ['SpawnActor', 'DestroyActor', 'ApplyVehicleControl', 'ApplyWalkerControl',
                                  'ApplyTransform', 'SetAutopilot', 'FutureActor', 'Response', 'SetSimulatePhysics',
                                  'ApplyVehicleAckermannControl', 'ApplyImpulse', 'ApplyForce', 'ApplyTargetVelocity',
                                  'ApplyTargetAngularVelocity', 'SetVehicleLightState', 'ApplyVehiclePhysicsControl'])
def test_carla_commands(name):
    assert hasattr(carla.command, name)


@pytest.mark.parametrize('name', [
    'MultirotorClient', 'Vector3r', 'Quaternionr', 'Pose', 'YawMode', 'DrivetrainType', 'ImageRequest', 'ImageType',
    'ImageResponse', 'MultirotorState', 'KinematicsState', 'CollisionInfo', 'LandedState', 'ImuData', 'GpsData',
    'BarometerData', 'MagnetometerData', 'DistanceSensorData', 'LidarData', 'WeatherParameter', 'to_quaternion',
    'to_eularian_angles', 'write_file', 'string_to_uint8_array', 'PIDGains', 'AngleRateControllerGains',
    'AngleLevelControllerGains', 'VelocityControllerGains', 'PositionControllerGains'])
def test_airsim_names(name):
    assert hasattr(airsim, name)


@pytest.mark.parametrize('method', [
    'confirmConnection', 'enableApiControl', 'armDisarm', 'takeoffAsync', 'landAsync', 'goHomeAsync', 'hoverAsync',
    'moveToPositionAsync', 'moveToZAsync', 'moveOnPathAsync', 'moveByVelocityAsync', 'moveByVelocityZAsync',
    'moveByVelocityBodyFrameAsync', 'rotateToYawAsync', 'rotateByYawRateAsync', 'moveByRollPitchYawThrottleAsync',
    'moveByRollPitchYawZAsync', 'moveByAngleRatesThrottleAsync', 'moveByMotorPWMsAsync', 'simGetImages',
    'getMultirotorState', 'getImuData', 'getGpsData', 'getBarometerData', 'getMagnetometerData',
    'getDistanceSensorData', 'getLidarData', 'simSetWeatherParameter', 'simPause', 'simContinueForTime',
    'simContinueForFrames', 'simGetVehiclePose', 'simSetVehiclePose', 'simGetCollisionInfo', 'listVehicles',
    'simAddVehicle', 'reset', 'moveByRollPitchYawrateThrottleAsync', 'moveByRollPitchYawrateZAsync',
    'moveByAngleRatesZAsync', 'moveToGPSAsync', 'simSetWind', 'simSetKinematics', 'setAngleRateControllerGains',
    'setAngleLevelControllerGains', 'setVelocityControllerGains', 'setPositionControllerGains'])
def test_multirotor_client_methods(method):
    assert callable(getattr(airsim.MultirotorClient, method))


def test_weather_presets_are_carlas():
    w = carla.WeatherParameters.HardRainNoon
    assert (w.cloudiness, w.precipitation, w.precipitation_deposits, w.wind_intensity) == (100, 100, 90, 100)
    assert carla.WeatherParameters.ClearNoon.sun_altitude_angle == 45


def test_left_handed_conversion_round_trips():
    from lockstep.carla.geometry import from_wire_pose, to_wire_pose
    t = carla.Transform(carla.Location(10, 20, 3), carla.Rotation(pitch=5, yaw=30, roll=-7))
    pose = to_wire_pose(t)
    assert pose[:3] == (10, -20, 3)  # ENU y = -CARLA y
    back = from_wire_pose(pose)
    assert back.location == t.location
    for a, b in ((back.rotation.pitch, 5), (back.rotation.yaw, 30), (back.rotation.roll, -7)):
        assert a == pytest.approx(b, abs=1e-9)


def test_yaw_is_clockwise_from_above_in_carla():
    from lockstep.carla.geometry import to_wire_pose
    # CARLA yaw 90 faces +y (left-handed: "south" on a map with y up), which is ENU -y.
    w, x, y, z = to_wire_pose(carla.Transform(carla.Location(), carla.Rotation(yaw=90)))[3:]
    enu_yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    assert enu_yaw == pytest.approx(-math.pi / 2)
    f = carla.Rotation(yaw=90).get_forward_vector()
    assert (f.x, f.y) == (pytest.approx(0, abs=1e-12), pytest.approx(1))


def test_transform_matches_carlas_matrix():
    t = carla.Transform(carla.Location(1, 2, 3), carla.Rotation(yaw=90))
    p = t.transform(carla.Location(1, 0, 0))
    assert (p.x, p.y, p.z) == (pytest.approx(1), pytest.approx(3), pytest.approx(3))
    m = t.get_matrix()
    inv = t.get_inverse_matrix()
    prod = [[sum(m[i][k] * inv[k][j] for k in range(4)) for j in range(4)] for i in range(4)]
    for i in range(4):
        for j in range(4):
            assert prod[i][j] == pytest.approx(1.0 if i == j else 0.0, abs=1e-12)


def test_vector_arithmetic():
    a, b = carla.Location(1, 2, 3), carla.Location(4, 6, 3)
    assert a.distance(b) == 5
    assert (b - a).length() == 5
    assert type(a + b) is carla.Vector3D  # CARLA's geom bindings: Location arithmetic gives a Vector3D
    assert carla.Location(a + b) == carla.Location(5, 8, 6)
    assert carla.Vector3D(3, 4, 0).make_unit_vector().x == pytest.approx(0.6)


def test_airsim_quaternion_helpers_match_airsim():
    q = airsim.to_quaternion(0.1, -0.2, 0.3)
    pitch, roll, yaw = airsim.to_eularian_angles(q)
    assert (pitch, roll, yaw) == (pytest.approx(0.1), pytest.approx(-0.2), pytest.approx(0.3))
    assert airsim.DrivetrainType.MaxDegreeOfFreedom == 0 and airsim.DrivetrainType.ForwardOnly == 1


def test_vehicle_control_defaults_match_carla():
    c = carla.VehicleControl()
    assert (c.throttle, c.steer, c.brake, c.hand_brake, c.reverse, c.manual_gear_shift, c.gear) == \
        (0, 0, 0, False, False, False, 0)


def test_calls_lockstep_lacks_raise_naming_themselves_not_attribute_error():
    """Every CARLA call without a Lockstep counterpart exists and raises LockstepUnsupported
    whose message names it (never AttributeError, never a silent no-op)."""
    calls = {carla.Vehicle: ['close_door', 'use_carsim_road', 'enable_chrono_physics', 'show_debug_telemetry',
                             'open_door', 'enable_carsim', 'get_ackermann_controller_settings'],
             carla.World: ['get_names_of_all_objects', 'enable_environment_objects', 'get_lightmanager'],
             carla.Sensor: ['disable_for_ros', 'enable_for_ros', 'is_enabled_for_ros'],
             carla.Map: ['save_to_disk', 'cook_in_memory_map'],
             carla.TrafficManager: ['get_next_action', 'get_all_actions'],
             carla.Client: ['request_file'],
             carla.TrafficLight: ['get_light_boxes'],
             carla.Actor: ['set_enable_gravity', 'add_torque']}
    for cls, names in calls.items():
        obj = cls.__new__(cls)
        for name in names:
            with pytest.raises(carla.LockstepUnsupported, match=r'\.%s is not supported by Lockstep: .+' % name):
                getattr(obj, name)(*([None] * (getattr(obj, name).__code__.co_argcount - 1)))


def test_physics_control_shapes_and_units():
    front, rear = carla.WheelPhysicsControl(), carla.WheelPhysicsControl(max_steer_angle=0.0)
    p = carla.VehiclePhysicsControl(wheels=[front, front, rear, rear])  # as CARLA's tutorial builds them
    assert p.max_rpm == 5000 and p.wheels[0].radius == 30.0 and p.wheels[0].max_steer_angle == 70.0
    assert carla.GearPhysicsControl().up_ratio == 0.65
    a = carla.VehicleAckermannControl(steer=0.1, speed=3.0)
    assert (a.steer, a.speed, a.acceleration) == (0.1, 3.0, 0.0)
    from lockstep.carla.physics import to_wire
    current = {'wheelbase': 2.8, 'track': 1.6, 'suspension_stiffness': 5e4, 'suspension_damping': 3500.0}
    d = to_wire(p, current)
    assert d['wheel_radius'] == pytest.approx(0.30) and d['max_steer_angle'] == pytest.approx(math.radians(70))
    assert d['wheelbase'] == 2.8  # Lockstep's own fields left None keep the vehicle's
    p.wheels[2].max_steer_angle = 10.0
    with pytest.raises(carla.LockstepUnsupported, match='rear wheels'):
        to_wire(p, current)


def test_airsim_calls_lockstep_lacks_raise_naming_themselves():
    c = airsim.MultirotorClient.__new__(airsim.MultirotorClient)
    # (every call of AirSim's that raises: tests/python/test_airsim_api.py, from docs/compatibility.md)
    for name in ('simRunConsoleCommand', 'simSetLightIntensity', 'simSwapTextures', 'simCreateVoxelGrid',
                 'simGetFocalLength'):
        with pytest.raises(airsim.LockstepUnsupported, match=name):
            f = getattr(c, name)
            f(*(['x'] * (f.__code__.co_argcount - 1) if f.__code__.co_argcount > 1 else []))
