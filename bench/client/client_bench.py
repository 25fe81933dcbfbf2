"""The Python half of bench_client: tick round trips, get_waypoint, and the delay from a
720p image's publication to a numpy view of it in a listen callback. Prints one JSON line."""
import json
import statistics
import sys
import time

import lockstep
from lockstep.carla.map import Map

domain, ticks = int(sys.argv[1]), int(sys.argv[2])
c = lockstep.Client(domain=domain, timeout=30)
c.wait_ready(30)
for _ in range(100):
    c.tick()
rt = []
for _ in range(ticks):
    t0 = time.perf_counter()
    c.tick()
    rt.append((time.perf_counter() - t0) * 1e6)

import lockstep.carla as carla  # noqa: E402
m = Map(c.map(), 'bench')
loc = m.get_spawn_points()[0].location
calls = 20000
t0 = time.perf_counter()
for i in range(calls):
    m.get_waypoint(loc)
waypoint_us = (time.perf_counter() - t0) / calls * 1e6

camera = c.spawn('sensor.camera.rgb', (0, 0, 2, 1, 0, 0, 0))
delays = []


def on_image(sample):
    a = sample.array()  # the numpy view (no copy)
    published = sample.fields()['transform'][0]  # the camera's write time (steady clock, s)
    assert a.shape == (720, 1280, 4)
    delays.append((time.monotonic() - published) * 1e3)


c.tick()
c.listen(camera, on_image)
for _ in range(200):
    c.tick()
c.stop(camera)
print(json.dumps({'tick_us': statistics.median(rt), 'waypoint_us': waypoint_us,
                  'image_ms': statistics.median(delays) if delays else -1, 'images': len(delays)}))
