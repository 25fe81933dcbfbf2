"""The paper's tables side by side with ours: CSV, Markdown and a matplotlib plot.

Paper figures: ../shared/reference/anchors.md and corl2017.md §5 (CARLA paper, Table 1:
success %, Table 2: km between infractions in Nav. dynamic; columns MP / CIL / RL)."""
import csv
import json
import os

from . import metrics

CONDITIONS = ['Training', 'New weather', 'New town', 'New town & weather']
TASKS = ['Straight', 'One turn', 'Navigation', 'Nav. dynamic']

# CARLA paper Table 1 (success %), per task: {condition: (MP, CIL, RL)}.
PAPER_SUCCESS = {
    'Straight': {'Training': (98, 95, 89), 'New town': (92, 97, 74), 'New weather': (100, 98, 86),
                 'New town & weather': (50, 80, 68)},
    'One turn': {'Training': (82, 89, 34), 'New town': (61, 59, 12), 'New weather': (95, 90, 16),
                 'New town & weather': (50, 48, 20)},
    'Navigation': {'Training': (80, 86, 14), 'New town': (24, 40, 3), 'New weather': (94, 84, 2),
                   'New town & weather': (47, 44, 6)},
    'Nav. dynamic': {'Training': (77, 83, 7), 'New town': (24, 38, 2), 'New weather': (89, 82, 2),
                     'New town & weather': (44, 42, 4)},
}
# Table 2 (km between infractions, Nav. dynamic); '>57' printed as 57.
PAPER_KM = {
    'intersection_otherlane': {'Training': (10.2, 33.4, 0.18), 'New town': (0.45, 1.12, 0.23),
                               'New weather': (16.1, 57.3, 0.09), 'New town & weather': (0.40, 0.78, 0.21)},
    'intersection_offroad': {'Training': (18.3, 12.9, 0.75), 'New town': (0.46, 0.76, 0.43),
                             'New weather': (24.2, 57.0, 0.72), 'New town & weather': (0.43, 0.81, 0.48)},
    'collision_other': {'Training': (10.0, 5.38, 0.42), 'New town': (0.44, 0.40, 0.23),
                        'New weather': (16.1, 4.05, 0.24), 'New town & weather': (0.45, 0.28, 0.25)},
    'collision_vehicles': {'Training': (16.4, 3.26, 0.58), 'New town': (0.51, 0.59, 0.41),
                           'New weather': (20.2, 1.86, 0.85), 'New town & weather': (0.47, 0.44, 0.37)},
    'collision_pedestrians': {'Training': (18.9, 6.35, 17.8), 'New town': (1.40, 1.88, 2.55),
                              'New weather': (20.4, 11.2, 20.6), 'New town & weather': (1.46, 1.41, 2.99)},
}
# NoCrash: LBC's README, CARLA 0.9.6, its autopilot (success %), per town:
# (empty train, empty new weather, regular train, regular new, dense train, dense new).
PAPER_NOCRASH_AUTOPILOT = {'Town01': (100, 100, 98.7, 99.3, 86.3, 82.7), 'Town02': (100, 100, 99.0, 98.0, 60.0, 58.7)}


def condition(town, weather, train_weathers, train_town='Town01'):
    new_town = town != train_town
    new_weather = weather not in train_weathers
    if new_town and new_weather:
        return 'New town & weather'
    if new_town:
        return 'New town'
    if new_weather:
        return 'New weather'
    return 'Training'


def corl2017_tables(results, train_weathers, agent):
    """results: the episode summaries (dicts with town, exp_id, weather, result, km, infraction
    counts). Returns (success rows, km rows, per-weather rows)."""
    by = {}
    for r in results:
        c = condition(r['town'], r['weather'], train_weathers)
        by.setdefault((r['exp_id'], c), []).append(r)
    success = []
    for task in TASKS:
        for c in CONDITIONS:
            rs = by.get((task, c))
            if not rs:
                continue
            per_w = {}
            for r in rs:
                per_w.setdefault(r['weather'], []).append(r['result'])
            ours = 100.0 * metrics.success_rate(per_w)
            mp, cil, rl = PAPER_SUCCESS[task][c]
            success.append({'task': task, 'condition': c, 'episodes': len(rs), 'agent': agent,
                            'ours_%': round(ours, 1), 'paper_MP_%': mp, 'paper_CIL_%': cil, 'paper_RL_%': rl})
    kms = []
    for c in CONDITIONS:
        rs = by.get(('Nav. dynamic', c))
        if not rs:
            continue
        km = sum(r['km'] for r in rs)
        for key in metrics.INFRACTIONS:
            n = sum(r[key] for r in rs)
            value, text = metrics.km_between(km, n)
            mp, cil, rl = PAPER_KM[key][c]
            kms.append({'infraction': metrics.INFRACTION_NAMES[key], 'condition': c, 'episodes': len(rs),
                        'km_driven': round(km, 3), 'count': n, 'ours_km': text, 'ours_km_value': round(value, 3),
                        'paper_MP_km': mp, 'paper_CIL_km': cil, 'paper_RL_km': rl})
    per_weather = []
    ws = {}
    for r in results:
        ws.setdefault((r['town'], r['exp_id'], r['weather']), []).append(r['result'])
    for (town, task, w), v in sorted(ws.items(), key=lambda kv: (kv[0][0], TASKS.index(kv[0][1]), kv[0][2])):
        per_weather.append({'town': town, 'task': task, 'weather': w, 'episodes': len(v),
                            'success_%': round(100.0 * sum(v) / len(v), 1)})
    return success, kms, per_weather


def write_csv(path, rows):
    if not rows:
        open(path, 'w').close()
        return
    with open(path, 'w', newline='') as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)


def markdown(rows, columns=None):
    if not rows:
        return '(no episodes)\n'
    cols = columns or list(rows[0].keys())
    out = ['| ' + ' | '.join(cols) + ' |', '|' + '---|' * len(cols)]
    for r in rows:
        out.append('| ' + ' | '.join(str(r.get(c, '')) for c in cols) + ' |')
    return '\n'.join(out) + '\n'


def plot_success(path, rows, title):
    """Grouped bars: ours and the paper's per task and condition (PNG). Returns False when
    matplotlib is missing."""
    try:
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    if not rows:
        return False
    labels = ['%s\n%s' % (r['task'], r['condition']) for r in rows]
    series = [('ours', 'ours_%')] + [(k.replace('paper_', 'paper ').replace('_%', ''), k)
                                     for k in rows[0] if k.startswith('paper_')]
    fig, ax = plt.subplots(figsize=(max(6, 1.3 * len(rows)), 4.5))
    width = 0.8 / len(series)
    for i, (name, key) in enumerate(series):
        ax.bar([x + i * width for x in range(len(rows))], [r[key] for r in rows], width, label=name)
    ax.set_xticks([x + 0.4 - width / 2 for x in range(len(rows))])
    ax.set_xticklabels(labels, fontsize=7)
    ax.set_ylabel('success %')
    ax.set_ylim(0, 105)
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return True


def write_corl2017(out_dir, results, train_weathers, agent, header):
    success, kms, per_weather = corl2017_tables(results, train_weathers, agent)
    write_csv(os.path.join(out_dir, 'success.csv'), success)
    write_csv(os.path.join(out_dir, 'km_between_infractions.csv'), kms)
    write_csv(os.path.join(out_dir, 'success_per_weather.csv'), per_weather)
    md = ['# CoRL 2017 (CARLA paper, Table 1 and 2) with agent `%s`' % agent, '', header, '',
          '## Success rate (%), ours next to the paper\'s MP / CIL / RL', '', markdown(success),
          '## km between infractions, Nav. dynamic', '',
          markdown(kms, ['infraction', 'condition', 'episodes', 'km_driven', 'count', 'ours_km', 'paper_MP_km',
                         'paper_CIL_km', 'paper_RL_km']),
          '## Success per town, task and weather (CARLA 0.8 weather numbers)', '', markdown(per_weather)]
    with open(os.path.join(out_dir, 'tables.md'), 'w') as f:
        f.write('\n'.join(md))
    plot_success(os.path.join(out_dir, 'success.png'), success, 'CoRL 2017, agent %s' % agent)
    with open(os.path.join(out_dir, 'results.json'), 'w') as f:
        json.dump({'success': success, 'km_between_infractions': kms, 'per_weather': per_weather}, f, indent=1)
    return success, kms, per_weather
