#!/usr/bin/env python3
"""AirSim's hello_drone, unmodified in spirit: connect, arm, take off, fly a box, land.
Run: lockstep python examples/drone_hello.py   (against a running simulation)"""
import airsim

client = airsim.MultirotorClient()
client.confirmConnection()
client.enableApiControl(True)
client.armDisarm(True)

state = client.getMultirotorState()
print("landed state: %d" % state.landed_state)

print("taking off...")
client.takeoffAsync().join()
state = client.getMultirotorState()
print("position after takeoff: %s" % state.kinematics_estimated.position)

print("flying a 10 m box at 5 m altitude")
for x, y in [(10, 0), (10, 10), (0, 10), (0, 0)]:
    client.moveToPositionAsync(x, y, -5, 4).join()
    pos = client.getMultirotorState().kinematics_estimated.position
    print("  at (%.1f, %.1f, %.1f)" % (pos.x_val, pos.y_val, pos.z_val))

collision = client.simGetCollisionInfo()
print("collided: %s" % collision.has_collided)

print("landing...")
client.landAsync().join()
client.armDisarm(False)
client.enableApiControl(False)
print("done: landed state %d" % client.getMultirotorState().landed_state)
