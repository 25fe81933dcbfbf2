#!/usr/bin/env python3
"""bench/run benchmarks [--episodes N] [--domain D] [--agent A] [--suites corl2017,nocrash,leaderboard]:
episodes per hour of each driving benchmark suite on this machine (lockstep.benchmarks,
each suite at reduced size on simulations of its own), one JSON line per suite and a
summary line last, like the other benchmarks. Everything a suite writes goes to
out/benchmarks/bench-<suite>/."""
import argparse
import json
import os
import subprocess
import sys
import time

BIN = os.path.dirname(os.path.abspath(__file__))
BUILD = os.path.dirname(BIN)
ROOT = os.path.dirname(BUILD)

SUITES = {
    # suite: arguments at reduced size (1 episode per task and weather by default)
    'corl2017': ['--towns', 'Town01,Town02', '--train-weathers', '1', '--test-weathers', '4'],
    'nocrash': ['--towns', 'Town01', '--train-weathers', '1', '--test-weathers', '10'],
    'leaderboard': ['--towns', 'Town01', '--traffic', 'Regular'],
}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--episodes', type=int, default=1)
    ap.add_argument('--domain', default=os.environ.get('LOCKSTEP_DOMAIN', '0') or '0')
    ap.add_argument('--agent', default='autopilot')
    ap.add_argument('--suites', default=','.join(SUITES))
    args = ap.parse_args()
    load0 = os.getloadavg()[0]
    summary = {'bench': 'benchmarks', 'agent': args.agent, 'episodes_per_hour': {}, 'episodes': {}}
    for suite in args.suites.split(','):
        if suite not in SUITES:
            sys.exit('bench benchmarks: unknown suite %s (%s)' % (suite, ', '.join(SUITES)))
        out = os.path.join(ROOT, 'out', 'benchmarks', 'bench-%s' % suite)
        cmd = [os.path.join(BIN, 'lockstep'), 'python', '-m', 'lockstep.benchmarks', suite, '--agent', args.agent,
               '--episodes', str(args.episodes), '--domain', str(args.domain), '--out', out] + SUITES[suite]
        started = time.time()
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, text=True)
        sys.stderr.write(proc.stdout)
        if proc.returncode != 0:
            sys.exit('bench benchmarks: %s failed (exit %d)' % (suite, proc.returncode))
        last = json.loads([line for line in proc.stdout.splitlines() if line.startswith('{')][-1])
        line = {'suite': suite, 'episodes': last.get('episodes', last.get('routes')),
                'episodes_per_hour': last['episodes_per_hour'], 'wall_s': round(time.time() - started, 1),
                'out': os.path.relpath(out, ROOT)}
        for k in ('success_%', 'driving_score_2_0', 'driving_score_2_1', 'route_completion_%'):
            if k in last:
                line[k] = last[k]
        print(json.dumps(line), flush=True)
        summary['episodes_per_hour'][suite] = line['episodes_per_hour']
        summary['episodes'][suite] = line['episodes']
    summary['load_avg_1m'] = [round(load0, 2), round(os.getloadavg()[0], 2)]
    print(json.dumps(summary))


if __name__ == '__main__':
    main()
