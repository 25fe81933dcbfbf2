"""lockstep.benchmarks: CARLA's driving benchmarks (CoRL 2017, NoCrash, Leaderboard-style
routes) with the autopilot, CARLA's agents and the paper's modular pipeline, Gymnasium-style
learning environments, and CARLA-Air's workloads, on the public `carla` and `airsim` APIs.

    build/bin/lockstep bench corl2017 --agent autopilot --episodes 2
    build/bin/lockstep bench --help          (= lockstep python -m lockstep.benchmarks --help)

docs/benchmarks.md describes the protocol, the episode files and what differs from CARLA."""
