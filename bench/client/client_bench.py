"""The Python client process of bench_client, driven over stdin / stdout:
  (with --embedded CONFIG TICKS: step 5, see below)
  "tick N"  -> N world.tick() round trips (us) on one line (lockstep.carla, as a script would)
  "rest"    -> get_waypoint (mean us per call), then the delay from a 720p camera image's
               publication to a numpy view of it in a listen callback; one JSON line, exit.
The simulation is the one on $LOCKSTEP_DOMAIN. Logging goes to stderr."""
import json
import os
import statistics
import sys
import time

answers = os.fdopen(os.dup(1), 'w')
os.dup2(2, 1)  # the native module's logging must not mix with the answers

import lockstep  # noqa: E402
import lockstep.carla as carla  # noqa: E402
from lockstep.carla.map import Map  # noqa: E402


def answer(line):
    answers.write(line + '\n')
    answers.flush()


if len(sys.argv) == 4 and sys.argv[1] == '--embedded':
    # Step 5: this process hosts the coordinator of CONFIG (lockstep.Coordinator) and ticks
    # TICKS times after 100 warm-up ticks; one JSON line with both medians, then exit.
    config, ticks = sys.argv[2], int(sys.argv[3])
    with lockstep.Coordinator(config) as coordinator:
        client = carla.Client('localhost', 2000)
        client.set_timeout(30)
        world = client.get_world()
        client._client().wait_ready(30)
        for _ in range(100):
            world.tick()
        before = len(coordinator.stats()['barrier_us'])
        rt = []
        for _ in range(ticks):
            t0 = time.perf_counter()
            world.tick()
            rt.append((time.perf_counter() - t0) * 1e6)
        barrier = coordinator.stats()['barrier_us'][before:]
        del world, client
        answer(json.dumps({'tick_us': statistics.median(rt), 'barrier_us': statistics.median(barrier) if barrier else -1,
                           'ticks': len(rt), 'barriers': len(barrier)}))
    sys.exit(0)


client = carla.Client('localhost', 2000)
client.set_timeout(30)
world = client.get_world()
native = client._client()
native.wait_ready(30)
answer('ready')
while True:
    cmd = sys.stdin.readline().split()
    if cmd == ['rest']:
        break
    if len(cmd) != 2 or cmd[0] != 'tick':
        sys.exit(0)  # end of input (the bench stopped early)
    rt = []
    for _ in range(int(cmd[1])):
        t0 = time.perf_counter()
        world.tick()
        rt.append((time.perf_counter() - t0) * 1e6)
    answer(' '.join('%.1f' % v for v in rt))

m = Map(native.map(), 'bench')
loc = m.get_spawn_points()[0].location
calls = 20000
t0 = time.perf_counter()
for i in range(calls):
    m.get_waypoint(loc)
waypoint_us = (time.perf_counter() - t0) / calls * 1e6

# The camera service joins now: wait until its blueprint is declared.
deadline = time.monotonic() + 30
while True:
    try:
        camera = native.spawn('sensor.camera.rgb', (0, 0, 2, 1, 0, 0, 0))
        break
    except carla.CommandRejected:
        if time.monotonic() > deadline:
            raise
        time.sleep(0.05)
delays = []


def on_image(sample):
    a = sample.array()  # the numpy view (no copy)
    published = sample.fields()['transform'][0]  # the camera's write time (steady clock, s)
    assert a.shape == (720, 1280, 4)
    delays.append((time.monotonic() - published) * 1e3)


world.tick()  # the spawn frame
# The camera service is not required, so the barrier does not wait for it, and its tick
# reader keeps the newest tick only: a tick sent before it stepped the spawn frame could
# replace that one. Wait until the bench says the camera exists.
answer('spawned')
if sys.stdin.readline().strip() != 'go':
    sys.exit(1)
native.listen(camera, on_image)
for _ in range(200):
    world.tick()
native.stop(camera)
answer(json.dumps({'waypoint_us': waypoint_us, 'image_ms': statistics.median(delays) if delays else -1,
                   'images': len(delays)}))
