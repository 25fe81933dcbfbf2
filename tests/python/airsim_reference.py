"""AirSim 1.8's public client API and message types, as names (from AirSim's
PythonClient/airsim/client.py and types.py): what tests/python/test_airsim_api.py holds
Lockstep's airsim module and docs/compatibility.md to."""

VEHICLE_CLIENT = [
    'reset', 'ping', 'getClientVersion', 'getServerVersion', 'getMinRequiredServerVersion',
    'getMinRequiredClientVersion', 'enableApiControl', 'isApiControlEnabled', 'armDisarm', 'simPause', 'simIsPause',
    'simContinueForTime', 'simContinueForFrames', 'getHomeGeoPoint', 'confirmConnection', 'simSetLightIntensity',
    'simSwapTextures', 'simSetObjectMaterial', 'simSetObjectMaterialFromTexture', 'simSetTimeOfDay',
    'simEnableWeather', 'simSetWeatherParameter', 'simGetImage', 'simGetImages', 'simGetPresetLensSettings',
    'simGetLensSettings', 'simSetPresetLensSettings', 'simGetPresetFilmbackSettings', 'simSetPresetFilmbackSettings',
    'simGetFilmbackSettings', 'simSetFilmbackSettings', 'simGetFocalLength', 'simSetFocalLength',
    'simEnableManualFocus', 'simGetFocusDistance', 'simSetFocusDistance', 'simGetFocusAperture',
    'simSetFocusAperture', 'simEnableFocusPlane', 'simGetCurrentFieldOfView', 'simTestLineOfSightToPoint',
    'simTestLineOfSightBetweenPoints', 'simGetWorldExtents', 'simRunConsoleCommand',
    'simGetMeshPositionVertexBuffers', 'simGetCollisionInfo', 'simSetVehiclePose', 'simGetVehiclePose',
    'simSetTraceLine', 'simGetObjectPose', 'simSetObjectPose', 'simGetObjectScale', 'simSetObjectScale',
    'simListSceneObjects', 'simLoadLevel', 'simListAssets', 'simSpawnObject', 'simDestroyObject',
    'simSetSegmentationObjectID', 'simGetSegmentationObjectID', 'simAddDetectionFilterMeshName',
    'simSetDetectionFilterRadius', 'simClearDetectionMeshNames', 'simGetDetections', 'simPrintLogMessage',
    'simGetCameraInfo', 'simGetDistortionParams', 'simSetDistortionParams', 'simSetDistortionParam',
    'simSetCameraPose', 'simSetCameraFov', 'simGetGroundTruthKinematics', 'simSetKinematics',
    'simGetGroundTruthEnvironment', 'simCreateVoxelGrid', 'getImuData', 'getBarometerData', 'getMagnetometerData',
    'getGpsData', 'getDistanceSensorData', 'getLidarData', 'simGetLidarSegmentation', 'simFlushPersistentMarkers',
    'simPlotPoints', 'simPlotLineStrip', 'simPlotLineList', 'simPlotArrows', 'simPlotStrings', 'simPlotTransforms',
    'simPlotTransformsWithNames', 'cancelLastTask', 'startRecording', 'stopRecording', 'isRecording', 'simSetWind',
    'simAddVehicle', 'listVehicles', 'getSettingsString',
]

MULTIROTOR_CLIENT = [
    'takeoffAsync', 'landAsync', 'goHomeAsync', 'moveByVelocityBodyFrameAsync', 'moveByVelocityZBodyFrameAsync',
    'moveByAngleZAsync', 'moveByAngleThrottleAsync', 'moveByVelocityAsync', 'moveByVelocityZAsync',
    'moveOnPathAsync', 'moveToPositionAsync', 'moveToGPSAsync', 'moveToZAsync', 'moveByManualAsync',
    'rotateToYawAsync', 'rotateByYawRateAsync', 'hoverAsync', 'moveByRC', 'moveByMotorPWMsAsync',
    'moveByRollPitchYawZAsync', 'moveByRollPitchYawThrottleAsync', 'moveByRollPitchYawrateThrottleAsync',
    'moveByRollPitchYawrateZAsync', 'moveByAngleRatesZAsync', 'moveByAngleRatesThrottleAsync',
    'setAngleRateControllerGains', 'setAngleLevelControllerGains', 'setVelocityControllerGains',
    'setPositionControllerGains', 'getMultirotorState', 'getRotorStates',
]

CAR_CLIENT = ['setCarControls', 'getCarState', 'getCarControls']

# types.py: class -> its fields (the instance attributes AirSim's from_msgpack fills).
TYPES = {
    'Vector2r': ['x_val', 'y_val'],
    'Vector3r': ['x_val', 'y_val', 'z_val'],
    'Quaternionr': ['w_val', 'x_val', 'y_val', 'z_val'],
    'Pose': ['position', 'orientation'],
    'CollisionInfo': ['has_collided', 'normal', 'impact_point', 'position', 'penetration_depth', 'time_stamp',
                      'object_name', 'object_id'],
    'GeoPoint': ['latitude', 'longitude', 'altitude'],
    'YawMode': ['is_rate', 'yaw_or_rate'],
    'RCData': ['timestamp', 'pitch', 'roll', 'throttle', 'yaw', 'switch1', 'switch2', 'switch3', 'switch4', 'switch5',
               'switch6', 'switch7', 'switch8', 'is_initialized', 'is_valid'],
    'ImageRequest': ['camera_name', 'image_type', 'pixels_as_float', 'compress'],
    'ImageResponse': ['image_data_uint8', 'image_data_float', 'camera_position', 'camera_orientation', 'time_stamp',
                      'message', 'pixels_as_float', 'compress', 'width', 'height', 'image_type'],
    'CarControls': ['throttle', 'steering', 'brake', 'handbrake', 'is_manual_gear', 'manual_gear', 'gear_immediate'],
    'KinematicsState': ['position', 'orientation', 'linear_velocity', 'angular_velocity', 'linear_acceleration',
                        'angular_acceleration'],
    'EnvironmentState': ['position', 'geo_point', 'gravity', 'air_pressure', 'temperature', 'air_density'],
    'CarState': ['speed', 'gear', 'rpm', 'maxrpm', 'handbrake', 'collision', 'kinematics_estimated', 'timestamp'],
    'MultirotorState': ['collision', 'kinematics_estimated', 'gps_location', 'timestamp', 'landed_state', 'rc_data',
                        'ready', 'ready_message', 'can_arm'],
    'RotorStates': ['timestamp', 'rotors'],
    'ProjectionMatrix': ['matrix'],
    'CameraInfo': ['pose', 'fov', 'proj_mat'],
    'LidarData': ['point_cloud', 'time_stamp', 'pose', 'segmentation'],
    'ImuData': ['time_stamp', 'orientation', 'angular_velocity', 'linear_acceleration'],
    'BarometerData': ['time_stamp', 'altitude', 'pressure', 'qnh'],
    'MagnetometerData': ['time_stamp', 'magnetic_field_body', 'magnetic_field_covariance'],
    'GnssReport': ['geo_point', 'eph', 'epv', 'velocity', 'fix_type', 'time_utc'],
    'GpsData': ['time_stamp', 'gnss', 'is_valid'],
    'DistanceSensorData': ['time_stamp', 'distance', 'min_distance', 'max_distance', 'relative_pose'],
    'Box2D': ['min', 'max'],
    'Box3D': ['min', 'max'],
    'DetectionInfo': ['name', 'geo_point', 'box2D', 'box3D', 'relative_pose'],
    'MeshPositionVertexBuffersResponse': ['position', 'orientation', 'vertices', 'indices', 'name'],
}

CONSTANTS = {
    'ImageType': {'Scene': 0, 'DepthPlanar': 1, 'DepthPerspective': 2, 'DepthVis': 3, 'DisparityNormalized': 4,
                  'Segmentation': 5, 'SurfaceNormals': 6, 'Infrared': 7, 'OpticalFlow': 8, 'OpticalFlowVis': 9},
    'DrivetrainType': {'MaxDegreeOfFreedom': 0, 'ForwardOnly': 1},
    'LandedState': {'Landed': 0, 'Flying': 1},
    'WeatherParameter': {'Rain': 0, 'Roadwetness': 1, 'Snow': 2, 'RoadSnow': 3, 'MapleLeaf': 4, 'RoadLeaf': 5,
                         'Dust': 6, 'Fog': 7, 'Enabled': 8},
    'GnssFixType': {'GNSS_FIX_NO_FIX': 0, 'GNSS_FIX_TIME_ONLY': 1, 'GNSS_FIX_2D_FIX': 2, 'GNSS_FIX_3D_FIX': 3},
}

HELPERS = ['string_to_uint8_array', 'string_to_float_array', 'list_to_2d_float_array', 'get_pfm_array',
           'get_public_fields', 'to_dict', 'to_str', 'write_file', 'to_eularian_angles', 'to_quaternion', 'wait_key',
           'read_pfm', 'write_pfm', 'write_png']
