"""Sensor.listen_to_gbuffer: CARLA's G-buffer textures of a camera, from the render
service's passes. Each texture the render service has a pass for comes from a companion
camera of that pass (same mount, image size and field of view) that the module spawns on
the first listen and destroys with the camera or on stop_gbuffer; the textures it has no
pass for arrive black, as CARLA sends the textures a scene does not fill. As CARLA's,
listen_to_gbuffer returns at once: the companion is spawned on a thread of its own."""
import sys
import threading

import lockstep

import numpy as np

from .sensor_data import GBufferTextureID, Image, make_sensor_data

# The render pass of each texture: (blueprint, how its image becomes the texture).
_PASSES = {
    GBufferTextureID.SceneColor: 'sensor.camera.rgb',
    GBufferTextureID.SceneDepth: 'sensor.camera.depth',
    GBufferTextureID.CustomDepth: 'sensor.camera.depth',
    GBufferTextureID.SceneStencil: 'sensor.camera.semantic_segmentation',
    GBufferTextureID.CustomStencil: 'sensor.camera.semantic_segmentation',
    GBufferTextureID.GBufferA: 'sensor.camera.normals',
    GBufferTextureID.Velocity: 'sensor.camera.optical_flow',
}
_BLACK = 'sensor.camera.rgb#black'  # a 1 x 1 camera whose frames time the black textures
_CAMERA_ATTRIBUTES = ('image_size_x', 'image_size_y', 'fov')
_MAX_IMAGE_BYTES = 8294400  # idl/lockstep/sensor.idl Image.data


class _Texture(Image):
    """A G-buffer texture: a carla.Image of the pass's BGRA pixels (or black)."""

    def __init__(self, data, pixels):
        self._sample = data._sample
        self._world = data._world
        self._fields = data._fields
        self.frame, self.frame_number, self.timestamp = data.frame, data.frame_number, data.timestamp
        self.sensor_id, self.transform = data.sensor_id, data.transform
        self.height, self.width = pixels.shape[:2]
        self.fov = data.fov
        self.encoding = 'bgra8'
        self._pixels = np.ascontiguousarray(pixels, dtype=np.uint8)


def _velocity_pixels(flow):
    """UE's velocity buffer layout: R, G = flow / 4 + 0.5 (the [-2, 2] screen units), B 0."""
    out = np.zeros(flow.shape[:2] + (4,), dtype=np.uint8)
    rg = np.clip(np.asarray(flow, dtype=np.float32) / 4.0 + 0.5, 0.0, 1.0) * 255.0 + 0.5
    out[..., 2] = rg[..., 0].astype(np.uint8)
    out[..., 1] = rg[..., 1].astype(np.uint8)
    out[..., 3] = 255
    return out


def _resize(a, w, h):
    """Nearest-pixel resampling of an (h', w', ...) array to (h, w, ...)."""
    if a.shape[0] == h and a.shape[1] == w:
        return a
    rows = (np.arange(h) * a.shape[0] // h).astype(np.intp)
    cols = (np.arange(w) * a.shape[1] // w).astype(np.intp)
    return a[rows][:, cols]


class GBuffers:
    """The companion cameras of one camera and the callbacks listening to its textures."""

    def __init__(self, sensor):
        self._sensor = sensor
        self._lock = threading.Lock()
        self._callbacks = {}   # texture id -> callback
        self._companions = {}  # pass key -> companion actor id
        self._pending = set()  # pass keys whose companion is being spawned
        self._closed = False

    def _size(self):
        a = self._sensor.attributes
        return int(a.get('image_size_x', 800)), int(a.get('image_size_y', 600))

    def _spawn(self, blueprint, tiny=False):
        world = self._sensor._world
        info = self._sensor._info
        attrs = {k: str(self._sensor.attributes[k]) for k in _CAMERA_ATTRIBUTES if k in self._sensor.attributes}
        if tiny:
            attrs.update(image_size_x='1', image_size_y='1')
        elif blueprint == 'sensor.camera.optical_flow':
            # 8 bytes a pixel: above the wire's image bound (8294400 bytes, 1920 x 1080 BGRA8)
            # the pass is rendered smaller and scaled up (nearest pixel).
            w, h = self._size()
            if w * h * 8 > _MAX_IMAGE_BYTES:
                k = (_MAX_IMAGE_BYTES / (w * h * 8.0)) ** 0.5
                attrs.update(image_size_x=str(max(1, int(w * k))), image_size_y=str(max(1, int(h * k))))
        mount = info.get('spawn_transform') or (0, 0, 0, 1, 0, 0, 0)
        parent = info.get('parent', 0)
        if not parent:
            mount = self._sensor._wire_pose()
        attrs['role_name'] = self._role(blueprint, tiny)
        return world._client.spawn(blueprint, mount, attrs, parent)

    def _role(self, blueprint, tiny):
        return '_gbuffer_%d_%s%s' % (self._sensor.id, blueprint.split('.')[-1], '_black' if tiny else '')

    def _start(self, key):
        """Spawns the pass's companion (a late reply of a busy simulation is looked up by its
        role name), then listens to it, unless the textures were stopped meanwhile."""
        blueprint, tiny = key.split('#')[0], key.endswith('#black')
        client = self._sensor._world._client
        actor, why = None, ''
        for _ in range(3):
            try:
                actor = self._spawn(blueprint, tiny)
                break
            except lockstep.CommandRejected as e:
                why = str(e)
                break
            except lockstep.ClientError as e:
                why = str(e)
                role = self._role(blueprint, tiny)
                try:
                    found = [i['id'] for i in client.actors() if i.get('attributes', {}).get('role_name') == role]
                except lockstep.ClientError:  # the client closed (the script ends)
                    return
                if found:
                    actor = found[0]
                    break
        with self._lock:
            self._pending.discard(key)
            keep = actor is not None and not self._closed and key in {_PASSES.get(t, _BLACK) for t in self._callbacks}
            if keep:
                self._companions[key] = actor
        if actor is None:
            sys.stderr.write('WARNING: listen_to_gbuffer: the %s pass of camera %d could not start: %s\n'
                             % (blueprint, self._sensor.id, why))
        elif not keep:
            self._drop([actor])
        else:
            try:
                client.listen(actor, lambda s, k=key: self._deliver(k, s))
            except lockstep.ClientError:  # the client closed (the script ends)
                pass

    def _deliver(self, key, sample):
        data = make_sensor_data(sample, self._sensor._world)
        with self._lock:
            wanted = [(t, cb) for t, cb in self._callbacks.items() if _PASSES.get(t, _BLACK) == key]
        w, h = self._size()
        for texture, callback in wanted:
            if texture not in _PASSES:
                pixels = np.zeros((h, w, 4), dtype=np.uint8)
                pixels[..., 3] = 255
            elif texture == GBufferTextureID.Velocity:
                pixels = _velocity_pixels(_resize(data.to_numpy(), w, h))
            else:
                pixels = data._bgra()
            callback(_Texture(data, pixels))

    def listen(self, texture, callback):
        texture = int(texture)
        if not 0 <= texture <= GBufferTextureID.CustomStencil:
            raise ValueError('listen_to_gbuffer: no G-buffer texture %d (carla.GBufferTextureID: 0..12)' % texture)
        key = _PASSES.get(texture, _BLACK)
        with self._lock:
            self._callbacks[texture] = callback
            new = key not in self._companions and key not in self._pending
            if new:
                self._pending.add(key)
        if new:
            threading.Thread(target=self._start, args=(key,), name='gbuffer-%d' % self._sensor.id, daemon=True).start()

    def stop(self, texture):
        texture = int(texture)
        with self._lock:
            self._callbacks.pop(texture, None)
            used = {_PASSES.get(t, _BLACK) for t in self._callbacks}
            gone = [(k, a) for k, a in self._companions.items() if k not in used]
            for k, _ in gone:
                del self._companions[k]
        self._drop([a for _, a in gone])

    def is_listening(self, texture):
        with self._lock:
            return int(texture) in self._callbacks

    def close(self):
        with self._lock:
            self._closed = True
            actors = list(self._companions.values())
            self._companions.clear()
            self._callbacks.clear()
        self._drop(actors)

    def _drop(self, actors):
        client = self._sensor._world._client
        for a in actors:
            try:
                client.stop(a)
            except Exception:  # already gone with the camera or its parent
                pass
            try:
                client.destroy(a)
            except Exception:
                pass
