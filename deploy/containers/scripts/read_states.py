"""A CARLA script for the client container: it ticks the synchronous world TICKS times and
prints the state of every vehicle and drone as one JSON line (frame, type, role,
location, rotation, velocity), the same in every deployment of deploy/containers/sim.yaml,
then a TIMING line (ticks per second of wall time: the benchmark figure).

  lockstep python read_states.py [--ticks 200]
"""
import argparse
import json
import time

import carla


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument('--host', default='localhost')
    ap.add_argument('--port', type=int, default=2000)
    ap.add_argument('--ticks', type=int, default=200)
    a = ap.parse_args()
    client = carla.Client(a.host, a.port)
    client.set_timeout(60.0)
    world = client.get_world()
    t0 = time.monotonic()
    frames = [world.tick() for _ in range(a.ticks)]
    wall = time.monotonic() - t0
    snapshot = world.get_snapshot()
    states = []
    for actor in world.get_actors():
        if not actor.type_id.startswith(('vehicle.', 'drone.')):
            continue
        t = actor.get_transform()
        v = actor.get_velocity()
        states.append({'id': actor.id, 'type': actor.type_id, 'role': actor.attributes.get('role_name', ''),
                       'location': [round(t.location.x, 6), round(t.location.y, 6), round(t.location.z, 6)],
                       'rotation': [round(t.rotation.pitch, 5), round(t.rotation.yaw, 5), round(t.rotation.roll, 5)],
                       'velocity': [round(v.x, 6), round(v.y, 6), round(v.z, 6)]})
    states.sort(key=lambda s: s['id'])
    print('STATES ' + json.dumps({'first_frame': frames[0], 'frame': snapshot.frame, 'ticks': len(frames),
                                  'actors': states}, sort_keys=True), flush=True)
    # Wall-clock figures (not part of the states: they differ from run to run).
    print('TIMING %d ticks in %.3f s: %.1f ticks/s' % (len(frames), wall, len(frames) / wall if wall > 0 else 0.0),
          flush=True)


if __name__ == '__main__':
    main()
