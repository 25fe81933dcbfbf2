"""CARLA calls Lockstep cannot do, each raising LockstepUnsupported with its reason
(docs/compatibility.md lists them with the rest)."""
from .actors import Sensor, TrafficLight, Vehicle
from .errors import add_unsupported
from .map import Map
from .world import Client, TrafficManager, World

_NO_SCENE = 'the static scene (Unreal objects) is not on the wire'
_ROS_ALL = ("the per-sensor ROS switch is not on the wire: `lockstep up --ros2` (CARLA's server --ros2) "
            "publishes every supported sensor on CARLA's ROS 2 topics (docs/deployment.md, ROS 2)")

add_unsupported(Vehicle, {
    'close_door': 'doors are not simulated',
    'use_carsim_road': 'CarSim is an Unreal plug-in',
    'enable_chrono_physics': 'Chrono is an Unreal plug-in; ground_sim simulates vehicles with ODE',
    'show_debug_telemetry': 'there is no viewport to draw in',
})
add_unsupported(World, {
    'get_names_of_all_objects': _NO_SCENE,
    'set_annotations_traverse_translucency': 'render has no translucent annotations to traverse',
    'enable_environment_objects': _NO_SCENE,
})
add_unsupported(Sensor, {
    'listen_to_gbuffer': 'render publishes no G-buffers',
    'stop_gbuffer': 'render publishes no G-buffers',
    'enable_for_ros': _ROS_ALL,
    'disable_for_ros': _ROS_ALL,
    'is_enabled_for_ros': _ROS_ALL,
})
add_unsupported(Map, {
    'save_to_disk': 'the .xodr file the run was started with is the map',
    'cook_in_memory_map': 'there is no Unreal map to cook',
})
add_unsupported(TrafficManager, {
    'get_next_action': "the Traffic Manager's plans are not on the wire",
    'get_all_actions': "the Traffic Manager's plans are not on the wire",
})
add_unsupported(Client, {
    'set_files_base_folder': 'there are no server-side asset files',
    'get_required_files': 'there are no server-side asset files',
    'request_file': 'there are no server-side asset files',
})
add_unsupported(TrafficLight, {'get_light_boxes': 'the light meshes are not in the client'})
