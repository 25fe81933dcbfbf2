"""carla.Client, World, WorldSettings, WeatherParameters, TrafficManager, snapshots."""
import glob
import os
import random
import threading
import time

import lockstep

from . import command as _command
from .actors import ActorList, make_actor, state_transform
from .blueprints import BlueprintLibrary
from .constants import WEATHER_FIELDS, WEATHER_PRESETS
from .errors import unsupported
from .geometry import Color, Location, Transform, Vector3D, from_enu_vector, shift_up, to_enu_vector, to_wire_pose
from .map import Map

__all__ = ['Client', 'World', 'WorldSettings', 'WeatherParameters', 'TrafficManager', 'WorldSnapshot', 'ActorSnapshot',
           'Timestamp', 'maps_path', 'DebugHelper', 'OpendriveGenerationParameters', 'LabelledPoint']


class LabelledPoint:
    """carla.LabelledPoint: a location and the carla.CityObjectLabel of what is there."""

    def __init__(self, location=None, label=0):
        self.location = Location(location) if location is not None else Location()
        self.label = label

    def __repr__(self):
        return 'LabelledPoint(%r, %s)' % (self.location, self.label)


class OpendriveGenerationParameters:
    """carla.OpendriveGenerationParameters: how CARLA meshes an OpenDRIVE-only world.
    Lockstep builds its town meshes from the map itself: the values are kept, not used."""

    def __init__(self, vertex_distance=2.0, max_road_length=50.0, wall_height=1.0, additional_width=0.6,
                 smooth_junctions=True, enable_mesh_visibility=True, enable_pedestrian_navigation=True):
        self.vertex_distance, self.max_road_length = float(vertex_distance), float(max_road_length)
        self.wall_height, self.additional_width = float(wall_height), float(additional_width)
        self.smooth_junctions, self.enable_mesh_visibility = bool(smooth_junctions), bool(enable_mesh_visibility)
        self.enable_pedestrian_navigation = bool(enable_pedestrian_navigation)


class WorldSettings:
    def __init__(self, synchronous_mode=False, no_rendering_mode=False, fixed_delta_seconds=None, substepping=True,
                 max_substep_delta_time=0.01, max_substeps=10, max_culling_distance=0.0, deterministic_ragdolls=True,
                 tile_stream_distance=3000.0, actor_active_distance=2000.0, spectator_as_ego=True, **lockstep_extra):
        self.synchronous_mode = synchronous_mode
        self.no_rendering_mode = no_rendering_mode
        self.fixed_delta_seconds = fixed_delta_seconds
        self.substepping = substepping
        self.max_substep_delta_time = max_substep_delta_time
        self.max_substeps = max_substeps
        self.max_culling_distance = max_culling_distance
        self.deterministic_ragdolls = deterministic_ragdolls
        self.tile_stream_distance = tile_stream_distance
        self.actor_active_distance = actor_active_distance
        self.spectator_as_ego = spectator_as_ego
        # Lockstep's own: 'strict' / 'pipelined' perception, real-time pacing when free-running.
        self.perception_mode = lockstep_extra.pop('perception_mode', 'strict')
        self.real_time_factor = lockstep_extra.pop('real_time_factor', 0.0)
        if lockstep_extra:
            raise TypeError('WorldSettings: unknown argument(s) %s' % ', '.join(lockstep_extra))

    @classmethod
    def _from_wire(cls, d):
        return cls(synchronous_mode=d['synchronous_mode'], no_rendering_mode=d['no_rendering_mode'],
                   fixed_delta_seconds=d['fixed_delta_seconds'], substepping=d['max_substeps'] > 1,
                   max_substep_delta_time=d['max_substep_delta_time'], max_substeps=d['max_substeps'],
                   perception_mode=d['perception_mode'], real_time_factor=d['real_time_factor'])

    def _to_wire(self):
        d = {'synchronous_mode': bool(self.synchronous_mode), 'no_rendering_mode': bool(self.no_rendering_mode),
             'perception_mode': self.perception_mode, 'real_time_factor': float(self.real_time_factor)}
        # fixed_delta_seconds=None (CARLA's variable step; CARLA reads <= 0 as None) keeps the current
        # fixed step: Lockstep is always fixed-step. Any positive step is accepted, as CARLA's.
        if self.fixed_delta_seconds is not None and float(self.fixed_delta_seconds) > 0:
            d['fixed_delta_seconds'] = float(self.fixed_delta_seconds)
        if self.substepping:
            d['max_substep_delta_time'] = float(self.max_substep_delta_time)
            d['max_substeps'] = int(self.max_substeps)
        else:
            d['max_substeps'] = 1
            fixed = self.fixed_delta_seconds
            d['max_substep_delta_time'] = float(fixed) if fixed is not None and float(fixed) > 0 else 0.05
        return d

    def __repr__(self):
        return ('WorldSettings(synchronous_mode=%s, no_rendering_mode=%s, fixed_delta_seconds=%s, substepping=%s, '
                'max_substep_delta_time=%s, max_substeps=%s)' % (self.synchronous_mode, self.no_rendering_mode,
                                                                 self.fixed_delta_seconds, self.substepping,
                                                                 self.max_substep_delta_time, self.max_substeps))


class WeatherParameters:
    def __init__(self, cloudiness=0.0, precipitation=0.0, precipitation_deposits=0.0, wind_intensity=0.0,
                 sun_azimuth_angle=0.0, sun_altitude_angle=0.0, fog_density=0.0, fog_distance=0.0, wetness=0.0,
                 fog_falloff=0.0, scattering_intensity=0.0, mie_scattering_scale=0.0, rayleigh_scattering_scale=0.0331,
                 dust_storm=0.0):
        for k, v in locals().items():
            if k != 'self':
                setattr(self, k, float(v))

    def _to_wire(self):
        d = {k: getattr(self, k) for k in WEATHER_FIELDS}
        if all(v == -1.0 for k, v in d.items() if k not in ('scattering_intensity', 'mie_scattering_scale',
                                                            'rayleigh_scattering_scale', 'dust_storm')):
            d.update({k: v for k, v in WEATHER_PRESETS['ClearNoon'].items()})  # CARLA's Default = the map's default
        return d

    def __eq__(self, o):
        return isinstance(o, WeatherParameters) and all(getattr(self, k) == getattr(o, k) for k in WEATHER_FIELDS)

    def __repr__(self):
        return 'WeatherParameters(%s)' % ', '.join('%s=%g' % (k, getattr(self, k)) for k in WEATHER_FIELDS)


for _name, _values in WEATHER_PRESETS.items():
    setattr(WeatherParameters, _name, WeatherParameters(**_values))


class Timestamp:
    def __init__(self, frame, elapsed_seconds, delta_seconds):
        self.frame = frame
        self.frame_count = frame
        self.elapsed_seconds = elapsed_seconds
        self.delta_seconds = delta_seconds
        self.platform_timestamp = time.time()

    def __eq__(self, o):
        return isinstance(o, Timestamp) and (self.frame, self.elapsed_seconds, self.delta_seconds) == (
            o.frame, o.elapsed_seconds, o.delta_seconds)

    def __ne__(self, o):
        return not self == o

    def __repr__(self):
        return 'Timestamp(frame=%d, elapsed_seconds=%f, delta_seconds=%f, platform_timestamp=%f)' % (
            self.frame, self.elapsed_seconds, self.delta_seconds, self.platform_timestamp)


class ActorSnapshot:
    def __init__(self, state):
        self.id = state['id']
        self._s = state

    def get_transform(self):
        """As Actor.get_transform of that frame (a vehicle's origin is the base of its box)."""
        return state_transform(self._s)

    def get_velocity(self):
        return from_enu_vector(self._s['velocity'])

    def get_angular_velocity(self):
        return from_enu_vector(self._s['angular_velocity'])

    def get_acceleration(self):
        return from_enu_vector(self._s['acceleration'])


class WorldSnapshot:
    def __init__(self, world):
        client = world._client
        run, frame, sim_time, _, _ = client.snapshot_frame()
        self.id = run
        self.frame = frame
        self.timestamp = Timestamp(frame, sim_time, world._dt())
        self._states = {k: ActorSnapshot(v) for k, v in client.states().items()}

    # CARLA's deprecated WorldSnapshot properties (on_tick callbacks read them: automatic_control.py).
    @property
    def frame_count(self):
        return self.timestamp.frame

    @property
    def elapsed_seconds(self):
        return self.timestamp.elapsed_seconds

    @property
    def delta_seconds(self):
        return self.timestamp.delta_seconds

    @property
    def platform_timestamp(self):
        return self.timestamp.platform_timestamp

    def __eq__(self, o):
        return isinstance(o, WorldSnapshot) and (self.id, self.frame) == (o.id, o.frame)

    def __ne__(self, o):
        return not self == o

    def find(self, actor_id):
        return self._states.get(actor_id)

    def has_actor(self, actor_id):
        return actor_id in self._states

    def __iter__(self):
        return iter(self._states.values())

    def __len__(self):
        return len(self._states)


# OpenDRIVE texts this process loaded (Map.to_opendrive): {map name: text}.
_opendrive_texts = {}


def _remember_opendrive(path, name=None, text=None):
    if text is None:
        try:
            with open(path) as f:
                text = f.read()
        except OSError:
            return
    if name is None:
        name = os.path.splitext(os.path.basename(path))[0]
    _opendrive_texts[name] = text


def opendrive_text(name, native):
    """The OpenDRIVE text of the running map `name`: what this process loaded, else the
    `<name>.xodr` on the maps path that parses to the same road network as `native`."""
    if name in _opendrive_texts:
        return _opendrive_texts[name]
    from lockstep._lockstep import Map as _NativeMap
    for d in maps_path():
        p = os.path.join(d, name + '.xodr')
        if not os.path.isfile(p):
            continue
        try:
            candidate = _NativeMap.load(p)
        except Exception:  # noqa: BLE001 (an unreadable file is not the map)
            continue
        if (candidate.geo_reference == native.geo_reference and len(candidate.topology()) == len(native.topology())
                and candidate.spawn_points(25.0) == native.spawn_points(25.0)):
            _remember_opendrive(p, name)
            return _opendrive_texts[name]
    return None


def maps_path():
    """Where load_world looks for <name>.xodr: $LOCKSTEP_MAPS_PATH (':'-separated), the
    generated towns of the build, and the shared CARLA towns."""
    dirs = [d for d in os.environ.get('LOCKSTEP_MAPS_PATH', '').split(':') if d]
    here = os.path.dirname(os.path.abspath(lockstep.__file__))   # build/python/lockstep
    build = os.path.dirname(os.path.dirname(here))
    dirs.append(os.path.join(build, 'maps', 'generated'))
    dirs.append(os.path.join(os.path.dirname(os.path.dirname(build)), 'shared', 'maps', 'carla'))
    return dirs


class Client:
    """carla.Client. Host and port are accepted and ignored: the simulation is found on the
    DDS domain $LOCKSTEP_DOMAIN (default 0), on this machine or any other on the network."""

    def __init__(self, host='localhost', port=2000, worker_threads=0):
        self.host, self.port = host, port
        self._timeout = float(os.environ.get('LOCKSTEP_CONNECT_TIMEOUT', '10'))
        self._native = None
        self._world = None

    def _client(self):
        if self._native is None:
            self._native = lockstep.session(timeout=self._timeout)
        return self._native

    def set_timeout(self, seconds):
        self._timeout = float(seconds)

    def get_client_version(self):
        return '0.9.15-lockstep'

    def get_server_version(self):
        self._client()
        return '0.9.15-lockstep'

    def get_world(self):
        if self._world is None:
            self._world = World(self._client(), self)
        return self._world

    def get_available_maps(self):
        names = []
        for d in maps_path():
            names += [os.path.splitext(os.path.basename(p))[0] for p in sorted(glob.glob(os.path.join(d, '*.xodr')))]
        return names

    def _find_map(self, name):
        base = os.path.basename(name.rstrip('/'))
        if os.path.isfile(name):
            return os.path.abspath(name)
        for d in maps_path():
            p = os.path.join(d, base if base.endswith('.xodr') else base + '.xodr')
            if os.path.isfile(p):
                return p
        raise RuntimeError("map '%s' not found in %s (set LOCKSTEP_MAPS_PATH)" % (name, ':'.join(maps_path())))

    def _reset_settings(self, reset_settings):
        """CARLA's reset_settings=True: the new episode starts with CARLA's default settings
        (asynchronous, rendering, substepping 0.01 s x 10); False keeps the current ones
        (Lockstep keeps them across a reset). The fixed step is kept: CARLA's default is a
        variable step, which Lockstep does not have."""
        if reset_settings:
            s = self.get_world().get_settings()
            s.synchronous_mode, s.no_rendering_mode = False, False
            s.substepping, s.max_substep_delta_time, s.max_substeps = True, 0.01, 10
            self.get_world().apply_settings(s)

    def load_world(self, map_name, reset_settings=True, map_layers=None):
        c = self._client()
        path = self._find_map(map_name)
        c.load_map(path)
        _remember_opendrive(path)
        self._reset_settings(reset_settings)
        return self.get_world()

    def load_world_if_different(self, map_name, reset_settings=True, map_layers=None):
        if self.get_world().get_map().name == os.path.splitext(os.path.basename(map_name))[0]:
            return None
        return self.load_world(map_name, reset_settings, map_layers)

    def reload_world(self, reset_settings=True):
        self._client().reset(0)
        self._reset_settings(reset_settings)
        return self.get_world()

    def generate_opendrive_world(self, opendrive, parameters=None, reset_settings=True):
        self._client().load_map('opendrive', opendrive)
        _remember_opendrive(None, 'opendrive', opendrive)
        self._reset_settings(reset_settings)
        return self.get_world()

    def get_trafficmanager(self, client_connection=8000):
        return TrafficManager(self.get_world(), client_connection)

    def _prepare(self, commands, world):
        for cmd in commands:
            if isinstance(cmd, _command.ApplyForce):
                cmd._dt = world._dt()
            elif isinstance(cmd, _command.ApplyVehiclePhysicsControl) and cmd.actor_id:
                cmd._current = world._client.vehicle_physics(cmd.actor_id)
            elif isinstance(cmd, _command.SpawnActor):
                parent = cmd.parent
                if isinstance(parent, int):
                    parent = world.get_actor(parent) if parent else None
                cmd._wire_transform = world._wire_spawn_transform(cmd.blueprint.id, cmd.blueprint.kind, cmd.transform,
                                                                  parent)
            elif isinstance(cmd, _command.ApplyTransform) and cmd.actor_id:
                actor = world.get_actor(cmd.actor_id)
                if actor is not None:
                    t = cmd.transform
                    if isinstance(cmd, _command.ApplyLocation):  # CARLA's ApplyLocation keeps the rotation
                        t = Transform(t.location, actor.get_transform().rotation)
                    cmd._wire_transform = actor._to_wire_transform(t)
            self._prepare(getattr(cmd, '_then', []), world)

    def _submit(self, c, commands, actor=0):
        dicts = [cmd.to_dict(actor) for cmd in commands]
        replies = c.submit_batch(dicts)
        for cmd, d, (ok, _, _, frame) in zip(commands, dicts, replies):
            watch = getattr(cmd, '_watch', None)
            if ok and watch:
                c.watch(cmd.actor_id or actor, frame, watch)  # a failure in ground_sim: raised by the next tick
                self.get_world()._note_applied(d, frame)
        return replies

    def _run(self, commands, due_tick_cue):
        world = self.get_world()
        c = self._client()
        self._prepare(commands, world)
        replies = self._submit(c, commands)
        out = []
        for cmd, (ok, reason, actor, _) in zip(commands, replies):
            actor_id = actor if ok else 0
            if ok and getattr(cmd, '_then', None):
                for follow in self._submit(c, cmd._then, actor_id):
                    if not follow[0]:
                        reason = follow[1]
            out.append(_command.Response(actor_id if not reason else actor_id, reason))
        if due_tick_cue and world.get_settings().synchronous_mode:
            world.tick()
        return out

    def apply_batch(self, commands):
        self._run(commands, False)

    def apply_batch_sync(self, commands, due_tick_cue=False):
        return self._run(commands, due_tick_cue)

    # --- CARLA's recorder (docs/compatibility.md, "Recorder") ---
    def start_recorder(self, name, additional_data=False):
        """CARLA's: records the run from the next tick into `name` (a name without '/', '\\'
        or ':' goes into the recordings folder: $LOCKSTEP_RECORDINGS_DIR, else
        ~/.local/share/lockstep/recordings); returns the file's path, as CARLA's does."""
        return self._client().start_recorder(str(name), bool(additional_data))

    def stop_recorder(self):
        self._client().stop_recorder()

    def replay_file(self, name, time_start=0.0, duration=0.0, follow_id=0, replay_sensors=False, follow_offset=None,
                    map_override=''):
        """CARLA's: the simulation plays the log back from `time_start` s (< 0: from the end)
        for `duration` s (0: to the end); recorded actors are spawned and follow their recorded
        poses, physics off, from the next tick. Returns CARLA's text. follow_id and
        follow_offset move CARLA's spectator camera, which Lockstep does not have;
        map_override is loaded first, as CARLA does (the log must have been recorded on it)."""
        if map_override and self.get_world().get_map().name != os.path.splitext(os.path.basename(map_override))[0]:
            self.load_world(map_override, reset_settings=False)
        return self._client().replay_file(str(name), float(time_start), float(duration), int(follow_id),
                                          bool(replay_sensors))

    def stop_replayer(self, keep_actors):
        self._client().stop_replayer(bool(keep_actors))

    def set_replayer_time_factor(self, time_factor=1.0):
        self._client().set_replayer_time_factor(float(time_factor))

    def set_replayer_ignore_hero(self, ignore_hero):
        self._client().set_replayer_ignore_hero(bool(ignore_hero))

    def set_replayer_ignore_spectator(self, ignore_spectator):
        self._client().set_replayer_ignore_spectator(bool(ignore_spectator))

    def show_recorder_file_info(self, name, show_all=False):
        """CARLA's text of the log's header, frames and events (read here, not on a server)."""
        return _lockstep_native().recorder_file_info(str(name), bool(show_all))

    def show_recorder_collisions(self, name, type1, type2):
        """CARLA's table of the log's collisions between actors of the two types ('a' any, 'h'
        hero, 'v' vehicle, 'w' walker, 't' traffic light, 'o' other)."""
        for t in (type1, type2):
            if not isinstance(t, str) or len(t) != 1:
                raise ValueError('show_recorder_collisions: a type is one character (a, h, v, w, t, o), got %r' % (t,))
        return _lockstep_native().recorder_collisions(str(name), type1, type2)

    def show_recorder_actors_blocked(self, name, min_time, min_distance):
        """CARLA's table of actors that moved less than `min_distance` cm in `min_time` s."""
        return _lockstep_native().recorder_actors_blocked(str(name), float(min_time), float(min_distance))


def _lockstep_native():
    from lockstep import _lockstep
    return _lockstep


class _Spectator:
    """CARLA's spectator is the Unreal viewport camera. Lockstep has no viewport: this one
    only remembers its transform (documented as partly supported)."""

    def __init__(self):
        self.id = 0
        self.type_id = 'spectator'
        self._t = Transform()

    def get_transform(self):
        return self._t

    def set_transform(self, t):
        self._t = t

    def get_location(self):
        return self._t.location


class World:
    def __init__(self, native, carla_client):
        self._client = native
        self._carla_client = carla_client
        self._actors = {}
        self._map = None
        self._map_key = None
        self._bp_cache = None
        self._spectator = _Spectator()
        # CARLA's navigation randomness (set_pedestrians_seed): get_random_location_from_navigation.
        self._pedestrians_random = random.Random()
        self._on_tick = {}
        self._next_cb = 1
        # (actor, 'physics' | 'light_state') -> (frame, value) this client applied: shown
        # until the state of that frame arrives (CARLA applies them at once).
        self._applied = {}
        # Blueprint declarations by id (Actor.attributes, vehicles' sizes and physics at spawn).
        self._decls = {}
        self._decls_read = None
        # Actor.enable_constant_velocity: {actor id: velocity in the actor's frame}.
        self._constant_velocity = {}

    def _apply_constant_velocities(self):
        for actor_id, local in list(self._constant_velocity.items()):
            actor = self.get_actor(actor_id)
            if actor is None:
                self._constant_velocity.pop(actor_id, None)
                continue
            try:
                actor.set_target_velocity(actor.get_transform().transform_vector(Vector3D(local)))
            except lockstep.CommandRejected:
                self._constant_velocity.pop(actor_id, None)  # gone meanwhile

    def _note_applied(self, cmd, frame):
        if cmd['type'] == 'vehicle_physics':
            self._applied[(cmd['actor'], 'physics')] = (frame, cmd['physics'])
        elif cmd['type'] == 'actor_physics' and cmd['kind'] == 'set_light_state':
            self._applied[(cmd['actor'], 'light_state')] = (frame, cmd['light_state'])

    def _applied_value(self, actor, key, reported):
        a = self._applied.get((actor, key))
        if a is None:
            return reported
        ground_frame = self._client.snapshot_frame()[3]  # the frame of the latest GroundState
        if ground_frame >= a[0]:
            del self._applied[(actor, key)]
            return reported
        return a[1]

    @property
    def id(self):
        return self._client.run()

    def _dt(self):
        return self._client.world_info()['settings']['fixed_delta_seconds']

    def _require(self, kind, call):
        st = self._client.run_status()
        if st is None or not any(k == kind and alive for _, k, alive, _ in st['members']):
            unsupported(call, 'no %s service is running in this simulation' % kind)

    # --- settings and time ---
    def get_settings(self):
        return WorldSettings._from_wire(self._client.world_info()['settings'])

    def apply_settings(self, settings):
        return self._client.apply_settings(settings._to_wire())

    def tick(self, seconds=10.0):
        """The frame the tick produced. Asynchronous, CARLA's tick cue is only counted by the
        server and the call waits for the next frame: the same here (no CommandRejected)."""
        if self._constant_velocity:
            self._apply_constant_velocities()
        try:
            return self._client.tick(seconds)
        except lockstep.CommandRejected as e:
            if 'synchronous' not in str(getattr(e, 'reason', e)):
                raise
        self._client.wait_for_tick(seconds)
        return self._client.snapshot_frame()[1]

    def wait_for_tick(self, seconds=10.0):
        self._client.wait_for_tick(seconds)
        if self._constant_velocity:
            self._apply_constant_velocities()
        return WorldSnapshot(self)

    def on_tick(self, callback):
        cb_id = self._next_cb
        self._next_cb += 1
        stop = threading.Event()

        def loop():
            while not stop.is_set():
                try:
                    self._client.wait_for_tick(1.0)
                except lockstep.ClientError:
                    if self._client.closed:  # the process is exiting
                        return
                    continue
                if not stop.is_set():
                    callback(WorldSnapshot(self))

        t = threading.Thread(target=loop, daemon=True)
        self._on_tick[cb_id] = stop
        t.start()
        return cb_id

    def remove_on_tick(self, callback_id):
        stop = self._on_tick.pop(callback_id, None)
        if stop:
            stop.set()

    def get_snapshot(self):
        return WorldSnapshot(self)

    # --- map, weather ---
    def get_map(self):
        info = self._client.world_info()
        key = (info['run'], info['map_name'])
        if self._map is None or self._map_key != key:
            self._map = Map(self._client.map(), info['map_name'])
            self._map_key = key
        return self._map

    def get_weather(self):
        return WeatherParameters(**self._client.world_info()['weather'])

    def set_weather(self, weather):
        self._client.set_weather(weather._to_wire())

    def get_blueprint_library(self):
        return BlueprintLibrary(self._client.blueprints())

    def get_spectator(self):
        return self._spectator

    # --- actors ---
    def _declaration(self, blueprint_id):
        """The declaration (dict) of a blueprint, None if no running service declares it."""
        d = self._decls.get(blueprint_id)
        now = time.monotonic()
        if d is None and (self._decls_read is None or now - self._decls_read > 1.0):
            self._decls = {x['id']: x for x in self._client.blueprints(0.0)}
            self._decls_read = now
            d = self._decls.get(blueprint_id)
        return d

    def _wire_spawn_transform(self, blueprint_id, kind, transform, parent):
        """CARLA's transform of a spawn -> the wire's: a vehicle's origin is the base of its
        box (the wire carries the box centre). What is attached to a vehicle keeps CARLA's
        transform as it is: the services mount it on the base of the parent's box, CARLA's
        vehicle origin (sensors' MountPose, render's rig, Actor._wire_pose)."""
        if kind == 'vehicle':
            d = self._declaration(blueprint_id)
            if d is not None:
                transform = shift_up(transform, d['half_extents'][2])
        return transform

    def _wrap(self, info):
        a = self._actors.get(info['id'])
        if a is None or a.type_id != info['blueprint']:
            a = make_actor(self, info)
            self._actors[info['id']] = a
        return a

    def get_actor(self, actor_id):
        info = self._client.actor(actor_id)
        return self._wrap(info) if info else None

    def get_actors(self, actor_ids=None):
        infos = self._client.actors()
        if actor_ids is not None:
            # As CARLA's cached actor list: in the order asked for (generate_traffic.py pairs
            # each walker controller with its walker by position), unknown ids left out.
            by_id = {i['id']: i for i in infos}
            infos = [by_id[a] for a in actor_ids if a in by_id]
        return ActorList(self._wrap(i) for i in infos)

    def _spawn_dict(self, blueprint, transform, attach_to):
        transform = self._wire_spawn_transform(blueprint.id, blueprint.kind, transform, attach_to)
        return {'type': 'spawn', 'blueprint': blueprint.id, 'transform': to_wire_pose(transform),
                'attributes': blueprint.spawn_attributes(), 'parent': attach_to.id if attach_to is not None else 0}

    def spawn_actor(self, blueprint, transform, attach_to=None, attachment_type=0, bone=None):
        """Raises lockstep.CommandRejected (a RuntimeError) with the service's reason."""
        if isinstance(blueprint, str):
            blueprint = self.get_blueprint_library().find(blueprint)
        d = self._spawn_dict(blueprint, transform, attach_to)
        actor_id = self._client.spawn(d['blueprint'], d['transform'], d['attributes'], d['parent'])
        info = self._client.actor(actor_id) or {'id': actor_id, 'blueprint': blueprint.id, 'kind': blueprint.kind,
                                                'attributes': d['attributes'], 'parent': d['parent'],
                                                'spawn_transform': d['transform']}
        return self._wrap(info)

    def try_spawn_actor(self, blueprint, transform, attach_to=None, attachment_type=0, bone=None):
        try:
            return self.spawn_actor(blueprint, transform, attach_to, attachment_type)
        except lockstep.CommandRejected:
            return None

    def _lights_by_signal(self):
        return {a.get_opendrive_id(): a for a in self.get_actors().filter('traffic.traffic_light*')}

    def get_traffic_light(self, landmark):
        """The traffic light actor of a landmark (its OpenDRIVE signal id), None if none."""
        return self._lights_by_signal().get(landmark.id)

    def get_traffic_sign(self, landmark):
        """The traffic sign actor of a landmark (its OpenDRIVE signal id), None if none: as
        CARLA's. Lockstep's services spawn no sign actors, so only lights have actors."""
        for a in self.get_actors().filter('traffic.*'):
            if a.type_id.startswith('traffic.traffic_light'):
                continue
            if str(a.attributes.get('opendrive_id', '')) == str(landmark.id):
                return a
        return None

    def get_traffic_light_from_opendrive_id(self, traffic_light_id):
        return self._lights_by_signal().get(str(traffic_light_id))

    def get_traffic_lights_from_waypoint(self, waypoint, distance):
        """The traffic lights of the dynamic landmarks ahead of `waypoint` within
        `distance` m, nearest first, each once (CARLA's semantics)."""
        lights, out = self._lights_by_signal(), []
        for l in waypoint.get_landmarks(distance):
            tl = lights.get(l.id) if l.is_dynamic else None
            if tl is not None and tl not in out:
                out.append(tl)
        return out

    def get_traffic_lights_in_junction(self, junction_id):
        """The traffic lights whose controlled lanes drive into that junction."""
        m = self.get_map()
        ids = {i['signal_id'] for i in m._native.traffic_light_infos()
               if i['junction'] >= 0 and m._junction_id(i['junction']) == junction_id}
        return [tl for sid, tl in sorted(self._lights_by_signal().items()) if sid in ids]

    def freeze_all_traffic_lights(self, frozen):
        for a in self.get_actors().filter('traffic.traffic_light*'):
            a.freeze(frozen)

    def reset_all_traffic_lights(self):
        """Every light group back to the start of its cycle (its first light green)."""
        self._require('ground_sim', 'World.reset_all_traffic_lights')
        self._client.submit({'type': 'traffic_light', 'actor': 0, 'action': 'reset_all'})

    def set_pedestrians_cross_factor(self, percentage):
        """The share (0..1) of AI walkers that cross the road (ground_sim: at crosswalks)."""
        self._require('ground_sim', 'World.set_pedestrians_cross_factor')
        self._client.submit({'type': 'pedestrians', 'cross_factor': float(percentage)})

    def set_pedestrians_seed(self, seed):
        """Seeds CARLA's navigation randomness: get_random_location_from_navigation here,
        and the walker AI controllers' choices in ground_sim (mixed with the run seed)."""
        self._pedestrians_random = random.Random(int(seed))
        st = self._client.run_status()
        if st is not None and any(k == 'ground_sim' and alive for _, k, alive, _ in st['members']):
            self._client.submit({'type': 'pedestrians', 'seed': int(seed) & 0xFFFFFFFFFFFFFFFF})

    def get_random_location_from_navigation(self):
        points = self._client.map().pedestrian_spawn_points(20.0)
        if not points:
            return None
        from .map import _transform
        return _transform(self._pedestrians_random.choice(points)).location

    def get_vehicles_light_states(self):
        """{vehicle id: carla.VehicleLightState bits} from the latest GroundState."""
        return {i: st['light_state'] for i, st in self._client.states().items() if 'light_state' in st}

    def get_lightmanager(self):
        unsupported('World.get_lightmanager', 'street and vehicle lights are not simulated')

    def get_level_bbs(self, actor_type=None):
        unsupported('World.get_level_bbs', 'the static scene is not exposed over the wire')

    def get_environment_objects(self, object_type=None):
        unsupported('World.get_environment_objects', 'the static scene is not exposed over the wire')

    def _rays(self):
        """The client's ray queries (lockstep.RayCaster): the town's meshes of the map in use,
        built once per map, with the sensors service's semantic tags, and the actor boxes of the
        latest frame, as the LiDAR sees them."""
        rays = getattr(self, '_ray_caster', None)
        if rays is None:
            from lockstep._lockstep import RayCaster
            rays = self._ray_caster = RayCaster(self._client)
        return rays

    def cast_ray(self, initial_location, final_location):
        """CARLA's: a carla.LabelledPoint for every object the segment crosses, nearest first,
        each object once (its first surface), labelled with its carla.CityObjectLabel."""
        hits = self._rays().cast_ray(to_enu_vector(initial_location), to_enu_vector(final_location))
        return [LabelledPoint(from_enu_vector(p, Location), label) for p, label in hits]

    def ground_projection(self, location, search_distance):
        """CARLA's: project_point(location, straight down, search_distance): the first surface
        below `location` within `search_distance` m, as a carla.LabelledPoint, None if none."""
        return self.project_point(location, Vector3D(0.0, 0.0, -1.0), search_distance)

    def project_point(self, location, direction, search_distance):
        """CARLA's: the first surface along `direction` within `search_distance` m of
        `location` as a carla.LabelledPoint, None if there is none."""
        hit = self._rays().project_point(to_enu_vector(location), to_enu_vector(direction), float(search_distance))
        if hit is None:
            return None
        p, label = hit
        return LabelledPoint(from_enu_vector(p, Location), label)

    def load_map_layer(self, map_layers):
        unsupported('World.load_map_layer', 'Lockstep towns have no Unreal layers')

    def unload_map_layer(self, map_layers):
        unsupported('World.unload_map_layer', 'Lockstep towns have no Unreal layers')

    @property
    def debug(self):
        return DebugHelper(self)

    def __repr__(self):
        return 'World(id=%d)' % self.id


class DebugHelper:
    """carla.DebugHelper (world.debug). Each call is a debug_draw command; the render service
    draws points, lines, arrows and boxes into its colour cameras from the frame of the next
    tick, for life_time seconds of simulation time (<= 0: until the world is reloaded, as
    CARLA's persistent line batcher keeps them). Strings and the draw_hud_* shapes go, as in
    CARLA, to the spectator's HUD, which no camera sensor sees. Without a render service the
    calls draw nothing and send nothing."""

    def __init__(self, world):
        self._world = world

    def _send(self, kind, color, life_time, persistent_lines, **shape):
        st = self._world._client.run_status()
        if st is None or not any(k == 'render' and alive for _, k, alive, _ in st['members']):
            return None
        c = color if color is not None else Color(255, 0, 0)
        shape.update(kind=kind, color=(int(c.r), int(c.g), int(c.b), int(getattr(c, 'a', 255))),
                     life_time=float(life_time), persistent_lines=bool(persistent_lines))
        self._world._client.submit({'type': 'debug_draw', 'shapes': [shape]})
        return None

    def draw_point(self, location, size=0.1, color=None, life_time=-1.0, persistent_lines=True):
        return self._send('point', color, life_time, persistent_lines, begin=to_enu_vector(location), size=float(size))

    def draw_hud_point(self, location, size=0.1, color=None, life_time=-1.0, persistent_lines=True):
        return self._send('point', color, life_time, persistent_lines, hud=True, begin=to_enu_vector(location),
                          size=float(size))

    def draw_line(self, begin, end, thickness=0.1, color=None, life_time=-1.0, persistent_lines=True):
        return self._send('line', color, life_time, persistent_lines, begin=to_enu_vector(begin), end=to_enu_vector(end),
                          size=float(thickness))

    def draw_hud_line(self, begin, end, thickness=0.1, color=None, life_time=-1.0, persistent_lines=True):
        return self._send('line', color, life_time, persistent_lines, hud=True, begin=to_enu_vector(begin),
                          end=to_enu_vector(end), size=float(thickness))

    def draw_arrow(self, begin, end, thickness=0.1, arrow_size=0.1, color=None, life_time=-1.0, persistent_lines=True):
        return self._send('arrow', color, life_time, persistent_lines, begin=to_enu_vector(begin), end=to_enu_vector(end),
                          size=float(thickness), arrow_size=float(arrow_size))

    def draw_hud_arrow(self, begin, end, thickness=0.1, arrow_size=0.1, color=None, life_time=-1.0, persistent_lines=True):
        return self._send('arrow', color, life_time, persistent_lines, hud=True, begin=to_enu_vector(begin),
                          end=to_enu_vector(end), size=float(thickness), arrow_size=float(arrow_size))

    def _box(self, box, rotation, hud, thickness, color, life_time, persistent_lines):
        pose = to_wire_pose(Transform(box.location, rotation))
        return self._send('box', color, life_time, persistent_lines, hud=hud, begin=pose[:3], rotation=pose[3:],
                          extent=(abs(box.extent.x), abs(box.extent.y), abs(box.extent.z)), size=float(thickness))

    def draw_box(self, box, rotation, thickness=0.1, color=None, life_time=-1.0, persistent_lines=True):
        return self._box(box, rotation, False, thickness, color, life_time, persistent_lines)

    def draw_hud_box(self, box, rotation, thickness=0.1, color=None, life_time=-1.0, persistent_lines=True):
        return self._box(box, rotation, True, thickness, color, life_time, persistent_lines)

    def draw_string(self, location, text, draw_shadow=False, color=None, life_time=-1.0, persistent_lines=True):
        return self._send('string', color, life_time, persistent_lines, begin=to_enu_vector(location), text=str(text)[:256],
                          draw_shadow=bool(draw_shadow))


class TrafficManager:
    """carla.TrafficManager: its settings go to ground_sim's Traffic Manager as commands."""

    def __init__(self, world, port=8000):
        self._world = world
        self._port = port

    def get_port(self):
        return self._port

    def _set(self, parameter, value, actor=None, call='TrafficManager', **extra):
        self._world._require('ground_sim', 'TrafficManager.' + call)
        cmd = {'type': 'traffic_manager', 'parameter': parameter, 'actor': actor.id if actor is not None else 0,
               'value': float(value)}
        cmd.update(extra)
        self._world._client.submit(cmd, watch='TrafficManager.' + call)

    def set_synchronous_mode(self, mode=True):
        # Lockstep's Traffic Manager always steps inside the tick: there is nothing to switch.
        return None

    def set_global_distance_to_leading_vehicle(self, distance):
        self._set('distance_to_leading_vehicle', distance, call='set_global_distance_to_leading_vehicle')

    def distance_to_leading_vehicle(self, actor, distance):
        self._set('distance_to_leading_vehicle', distance, actor, 'distance_to_leading_vehicle')

    def global_percentage_speed_difference(self, percentage):
        self._set('percentage_speed_difference', percentage, call='global_percentage_speed_difference')

    def vehicle_percentage_speed_difference(self, actor, percentage):
        self._set('percentage_speed_difference', percentage, actor, 'vehicle_percentage_speed_difference')

    def ignore_lights_percentage(self, actor, perc):
        self._set('ignore_lights_percentage', perc, actor, 'ignore_lights_percentage')

    def ignore_signs_percentage(self, actor, perc):
        self._set('ignore_signs_percentage', perc, actor, 'ignore_signs_percentage')

    def ignore_vehicles_percentage(self, actor, perc):
        self._set('ignore_vehicles_percentage', perc, actor, 'ignore_vehicles_percentage')

    def ignore_walkers_percentage(self, actor, perc):
        self._set('ignore_walkers_percentage', perc, actor, 'ignore_walkers_percentage')

    def auto_lane_change(self, actor, enable):
        self._set('auto_lane_change', 1 if enable else 0, actor, 'auto_lane_change')

    def set_hybrid_physics_mode(self, enabled=False):
        self._set('hybrid_physics_mode', 1 if enabled else 0, call='set_hybrid_physics_mode')

    def set_hybrid_physics_radius(self, r=50.0):
        self._set('hybrid_physics_radius', r, call='set_hybrid_physics_radius')

    def set_random_device_seed(self, value):
        self._set('random_seed', value, call='set_random_device_seed')

    def set_respawn_dormant_vehicles(self, mode_switch=True):
        self._set('respawn_dormant_vehicles', 1 if mode_switch else 0, call='set_respawn_dormant_vehicles')

    def set_desired_speed(self, actor, speed):
        """km/h, as CARLA."""
        self._set('desired_speed', float(speed) / 3.6, actor, 'set_desired_speed')

    def keep_right_rule_percentage(self, actor, perc):
        self._set('keep_right_rule_percentage', perc, actor, 'keep_right_rule_percentage')

    def random_left_lanechange_percentage(self, actor, percentage):
        self._set('random_left_lanechange_percentage', percentage, actor, 'random_left_lanechange_percentage')

    def random_right_lanechange_percentage(self, actor, percentage):
        self._set('random_right_lanechange_percentage', percentage, actor, 'random_right_lanechange_percentage')

    def set_osm_mode(self, mode_switch=True):
        if mode_switch:
            unsupported('TrafficManager.set_osm_mode', 'OpenStreetMap import is not supported')

    def force_lane_change(self, actor, direction):
        """direction True = left, as CARLA."""
        self._set('force_lane_change', 1 if direction else 0, actor, 'force_lane_change')

    def set_path(self, actor, path):
        """carla.Locations to pass, in order."""
        self._set('set_path', 0, actor, 'set_path', path=[to_enu_vector(p) for p in path])

    def set_route(self, actor, path):
        """'Left' / 'Right' / 'Straight' at the next junctions, as CARLA."""
        self._set('set_route', 0, actor, 'set_route', route=[str(r) for r in path])

    def vehicle_lane_offset(self, actor, offset):
        """m from the lane centre, > 0 right (CARLA's sign); overrides global_lane_offset."""
        self._set('lane_offset', offset, actor, 'vehicle_lane_offset')

    def global_lane_offset(self, offset):
        """m from the lane centre for every vehicle without its own, > 0 right (CARLA's sign)."""
        self._set('lane_offset', offset, call='global_lane_offset')

    def collision_detection(self, reference_actor, other_actor, detect_collision):
        """False: the Traffic Manager's reference_actor ignores other_actor (one way), as CARLA's."""
        self._set('collision_detection', 1 if detect_collision else 0, reference_actor, 'collision_detection',
                  other_actor=other_actor.id)

    def set_boundaries_respawn_dormant_vehicles(self, lower_bound=25.0, upper_bound=None):
        """m from the hero where dormant vehicles respawn; ground_sim clamps them to
        [20 m, actor_active_distance] as CARLA's (upper_bound None: actor_active_distance)."""
        if upper_bound is None:
            upper_bound = 2000.0
        self._set('respawn_boundaries', lower_bound, call='set_boundaries_respawn_dormant_vehicles',
                  value2=float(upper_bound))

    def update_vehicle_lights(self, actor, do_update):
        """While it drives the vehicle, the TM sets its position lights and low beams from the
        sun, heavy rain and fog, fog lights in fog, and brake lights on a hard brake (CARLA's
        light stage)."""
        self._set('update_vehicle_lights', 1 if do_update else 0, actor, 'update_vehicle_lights')

    def shut_down(self):
        return None
