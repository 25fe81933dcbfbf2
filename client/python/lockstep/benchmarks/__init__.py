"""lockstep.benchmarks: CARLA's driving benchmarks (CoRL 2017, NoCrash, Leaderboard-style
routes) and a Gymnasium-style learning environment, on the public `carla` API.

    build/bin/lockstep python -m lockstep.benchmarks corl2017 --agent autopilot --episodes 2
    build/bin/lockstep python -m lockstep.benchmarks --help

docs/benchmarks.md describes the protocol, the episode files and what differs from CARLA."""
