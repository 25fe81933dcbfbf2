#!/usr/bin/env python3
"""bench/run compat [--only S] [--list carla|airsim|all] [--out DIR]: run CARLA's and
AirSim's own example scripts, unmodified, each on a fresh simulation (the shared runner
../shared/tools/compat), and write the result as a Markdown table (script, result, reason,
seconds) to DIR/compat.md, for docs/compatibility.md. Prints one JSON line per script and
a summary line last, like the other benchmarks."""
import argparse
import json
import os
import re
import subprocess
import sys
import time

BIN = os.path.dirname(os.path.abspath(__file__))
BUILD = os.path.dirname(BIN)
ROOT = os.path.dirname(BUILD)
SHARED = os.path.join(ROOT, '..', 'shared')
LINE = re.compile(r'^(PASS|FAIL) (\S+)\s+(\d+)s ?(.*)$')


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--list', choices=['carla', 'airsim', 'all'], default='all')
    ap.add_argument('--only', default='')
    ap.add_argument('--out', default=os.path.join(ROOT, 'out', 'compat'))
    ap.add_argument('--domain', default=os.environ.get('LOCKSTEP_COMPAT_DOMAIN', '57'))
    args = ap.parse_args()
    runner = os.path.join(SHARED, 'tools', 'compat')
    if not os.path.exists(runner):
        sys.exit('bench compat: %s not found (the shared folder sits beside the checkout)' % runner)
    names = ['carla', 'airsim'] if args.list == 'all' else [args.list]
    lists = [os.path.join(SHARED, 'compat', n + '.list') for n in names]
    os.makedirs(args.out, exist_ok=True)
    cmd = [runner] + lists + ['--build', BUILD, '--out', os.path.join(args.out, 'logs'), '--domain', args.domain]
    if args.only:
        cmd += ['--only', args.only]
    rows = []
    start = time.time()
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, text=True)
    for line in proc.stdout:
        sys.stderr.write(line)
        m = LINE.match(line.rstrip('\n'))
        if m:
            result, name, seconds, why = m.groups()
            rows.append({'script': name, 'result': result, 'seconds': int(seconds), 'reason': why.strip()})
            print(json.dumps(rows[-1]), flush=True)
    proc.wait()
    passed = sum(r['result'] == 'PASS' for r in rows)
    with open(os.path.join(args.out, 'compat.md'), 'w') as f:
        f.write('| script | result | reason | s |\n|---|---|---|---|\n')
        for r in rows:
            script = r['script'].split('__', 1)[-1]
            f.write('| `%s` | %s | %s | %d |\n' % (script, r['result'].lower(), r['reason'].replace('|', '\\|'),
                                                 r['seconds']))
    print(json.dumps({'summary': 'compat', 'passed': passed, 'failed': len(rows) - passed, 'scripts': len(rows),
                      'seconds': round(time.time() - start), 'table': os.path.join(args.out, 'compat.md')}))
    return 0 if rows else 1


if __name__ == '__main__':
    sys.exit(main())
