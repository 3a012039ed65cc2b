#!/usr/bin/python3
"""Charts and summary of the bench sweeps (scripts/run_bench). Reads doc/sweep_*.csv and
doc/microbench.csv, writes doc/*.png and doc/bench_summary.md, and prints the summary.

    /usr/bin/python3 scripts/plot_bench.py [--data doc] [--env doc/bench_env.txt]

/usr/bin/python3 with Debian's python3-matplotlib (Agg backend, no display needed).
"""
import argparse
import csv
import math
import os
import sys

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402  (after the backend choice)
from matplotlib.colors import LogNorm  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
G = 9.81
DIVERGED_STRAIN = 1e3     # links 1000 x rest length: blown up (a crumpled cloth reaches 300)
BOUNDED_ENERGY = 10.0     # stable: energy never above E0 + 10 M g L (test_stability_matrix.cpp)
TARGET = 0.01             # the tolerance of issue 6: max strain 1 %
# Issue 12's targets on config/swinging.yaml: final strain of the structural links, max and mean.
SWING_MAX_TARGET = 0.01
SWING_MEAN_TARGET = 0.001

# One style per curve of the charts, in legend order.
STYLES = [
    ('xpbd', dict(color='tab:blue', marker='o')),
    ('xpbd, no bending', dict(color='tab:cyan', marker='o')),
    ('xpbd + tethers', dict(color='navy', marker='*')),
    ('xpbd jacobi', dict(color='tab:purple', marker='v')),
    ('xpbd + levels', dict(color='darkgreen', marker='h')),
    ('xpbd + levels, interpolated', dict(color='tab:pink', marker='X')),
    # Fewer levels (2 at 50 x 50, 4 at 100 x 100; each chart has one of them).
    ('xpbd + 2 levels', dict(color='seagreen', marker='p')),
    ('xpbd + 4 levels', dict(color='seagreen', marker='p')),
    # The same build at solver.avx512=false: four links a register instead of eight.
    ('xpbd + levels, AVX2 only', dict(color='yellowgreen', marker='h')),
    ('xpbd + levels, chebyshev 0.9', dict(color='gold', marker='d')),
    ('xpbd + levels, chebyshev 0.95', dict(color='darkgoldenrod', marker='d')),
    ('xpbd, chebyshev 0.9', dict(color='tab:gray', marker='d')),
    ('pbd', dict(color='tab:green', marker='s')),
    ('verlet', dict(color='tab:olive', marker='D')),
    ('mass_spring', dict(color='tab:brown', marker='P')),
    ('bullet', dict(color='tab:red', marker='^')),
    ('bullet + bending links', dict(color='tab:orange', marker='^')),
]
STYLE = dict(STYLES)


def number(text, default=float('nan')):
    try:
        return float(text)
    except (TypeError, ValueError):
        return default


def load(path):
    if not os.path.exists(path):
        return []
    with open(path, newline='') as handle:
        rows = list(csv.DictReader(handle))
    for row in rows:
        for key in ('wall_ms_per_step', 'max_strain', 'mean_strain', 'energy', 'substeps',
                    'iterations', 'passes', 'mass_ratio', 'end_drop', 'max_penetration',
                    'spring_stiffness', 'final_structural_max_strain',
                    'final_structural_mean_strain', 'project_ms', 'predict_ms', 'update_ms',
                    'cpu_ms_per_step', 'last_second_median_structural_max_strain',
                    'median_structural_max_strain_last_1s',
                    'median_structural_mean_strain_last_1s'):
            row[key] = number(row.get(key))
        row['ok'] = row.get('exit_status') == '0' and row.get('finite') == '1'
    return rows


def converged_run(row):
    """Finite, exited normally, and not blown up (a diverged run can stay finite: Bullet clamps)."""
    return row['ok'] and row['max_strain'] < DIVERGED_STRAIN


def pareto(points):
    """Non-dominated (cost, error) points, by increasing cost."""
    front = []
    for cost, error, row in sorted(points, key=lambda p: (p[0], p[1])):
        if not front or error < front[-1][1]:
            front.append((cost, error, row))
    return front


def setting(row):
    if row['method'] == 'bullet':
        text = 'bullet.substeps=%d bullet.piterations=%d' % (row['substeps'], row['iterations'])
        if row.get('variant') == 'bending_links':
            text += ' bullet.bending=1'
        return text
    text = 'solver.method=%s solver.substeps=%d solver.iterations=%d' % (
        row['method'], row['substeps'], row['iterations'])
    if row.get('ordering') == 'jacobi':
        text += ' solver.ordering=jacobi'
    if row.get('variant') == 'no_bending':
        text += ' cloth.bend_compliance=-1'
    if row.get('variant') == 'tethers':
        text += ' cloth.tethers=true'
    if row['method'] == 'mass_spring':
        text += ' solver.spring_stiffness=%g solver.bend_spring_stiffness=0.01' % (
            row['spring_stiffness'])
    return text


def curves_of(rows):
    names = [name for name, _ in STYLES if any(r['curve'] == name for r in rows)]
    return names + sorted({r['curve'] for r in rows} - set(names))


# --- Speed against accuracy -----------------------------------------------------------------------

def pareto_panel(ax, rows, metric, ylabel, target=None):
    everything = []
    top = max([r[metric] for r in rows if converged_run(r) and r[metric] > 0] or [1.0]) * 3.0
    for name in curves_of(rows):
        style = STYLE.get(name, dict(color='gray', marker='.'))
        mine = [r for r in rows if r['curve'] == name]
        good = [(r['wall_ms_per_step'], r[metric], r) for r in mine
                if converged_run(r) and r[metric] > 0]
        bad = [r for r in mine if not converged_run(r)]
        everything += good
        frozen = sum(1 for r in bad if r.get('frozen'))
        label = '%s (%d runs%s%s)' % (name, len(mine),
                                      ', %d diverged' % (len(bad) - frozen) if len(bad) > frozen
                                      else '', ', %d frozen' % frozen if frozen else '')
        if good:
            ax.scatter([p[0] for p in good], [p[1] for p in good], s=12, alpha=0.3,
                       color=style['color'], marker=style['marker'], linewidths=0)
            front = pareto(good)
            ax.plot([p[0] for p in front], [p[1] for p in front], '-', color=style['color'],
                    marker=style['marker'], markersize=5, linewidth=1.4, label=label)
        if bad:
            # Runs stopped by the time limit have no time per step: not drawn, counted in the label.
            costs = [r['wall_ms_per_step'] for r in bad if r['wall_ms_per_step'] > 0]
            ax.scatter(costs, [top] * len(costs), marker='x', s=30, color=style['color'],
                       label=None if good else label)
    front = pareto(everything)
    if front:
        xs, ys = [], []
        for cost, error, _ in front:
            if xs:
                xs.append(cost)
                ys.append(ys[-1])
            xs.append(cost)
            ys.append(error)
        ax.plot(xs, ys, '-', color='black', linewidth=3, alpha=0.25, zorder=0,
                label='Pareto front, all runs')
    if target:
        ax.axhline(target, color='gray', linestyle=':', linewidth=1)
        ax.annotate('%g %%' % (100 * target), xy=(0.01, target), xycoords=('axes fraction', 'data'),
                    va='bottom', color='gray', fontsize=8)
    ax.set_xscale('log')
    ax.set_yscale('log')
    ax.set_xlabel('wall time per step (ms, one thread)')
    ax.set_ylabel(ylabel)
    ax.grid(True, which='major', alpha=0.3)
    ax.text(0.99, 0.99, 'x at the top: diverged (or frozen) runs, at their time per step',
            transform=ax.transAxes, ha='right',
            va='top', fontsize=7, color='gray')


def pareto_figure(rows, metrics, title, path):
    fig, axes = plt.subplots(1, len(metrics), figsize=(6.4 * len(metrics), 5.6))
    if len(metrics) == 1:
        axes = [axes]
    for ax, (metric, label, target) in zip(axes, metrics):
        pareto_panel(ax, rows, metric, label, target)
    axes[0].legend(fontsize=7, loc='lower left')
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# The general sweep (issue 50): one panel per scene, in the sweep's order, every series on every
# panel (Bullet included). (label, title) of the panels; scenes not listed come after, by label.
GENERAL_PANELS = [
    ('held_corners', 'held_corners.yaml: 50 x 50, one diagonal, 0.5 % closer'),
    ('held_50_2pct', 'bench/held_50_2pct: 50 x 50, one diagonal, 2 % closer'),
    ('held_50_both_05pct', 'bench/held_50_both_05pct: 50 x 50, both diagonals, 0.5 %'),
    ('held_50_both_2pct', 'bench/held_50_both_2pct: 50 x 50, both diagonals, 2 %'),
    ('held_100_05pct', 'bench/held_100_05pct: 100 x 100, one diagonal, 0.5 %'),
    ('held_100_2pct', 'bench/held_100_2pct: 100 x 100, one diagonal, 2 %'),
    ('tshirt_held', 'tshirt_held.yaml: T-shirt held at its shoulders'),
]
# Metrics of a general panel: (column, how it is drawn, legend suffix).
GENERAL_METRICS = [('final_structural_max_strain', '-', 'final max'),
                   ('median_structural_max_strain_last_1s', '--', 'median of the max, last 1 s'),
                   ('final_structural_mean_strain', ':', 'final mean')]


def general_figure(rows, path):
    labels = [label for label, _ in GENERAL_PANELS if any(r.get('label') == label for r in rows)]
    labels += sorted({r.get('label') for r in rows} - set(labels) - {None, ''})
    titles = dict(GENERAL_PANELS)
    columns = 4 if len(labels) > 4 else len(labels)
    lines = (len(labels) + columns - 1) // columns
    fig, axes = plt.subplots(lines, columns, figsize=(5.0 * columns, 4.4 * lines), squeeze=False)
    for ax in axes.flat[len(labels):]:
        ax.axis('off')
    for ax, label in zip(axes.flat, labels):
        mine = [r for r in rows if r.get('label') == label]
        for name in curves_of(mine):
            style = STYLE.get(name, dict(color='gray', marker='.'))
            runs = sorted([r for r in mine if r['curve'] == name and converged_run(r)],
                          key=lambda r: r['wall_ms_per_step'])
            failed = len([r for r in mine if r['curve'] == name and not converged_run(r)])
            for metric, line, suffix in GENERAL_METRICS:
                points = [(r['wall_ms_per_step'], r[metric]) for r in runs
                          if r[metric] > 0 and not math.isnan(r[metric])]
                if not points:
                    continue
                ax.plot([p[0] for p in points], [p[1] for p in points], line,
                        color=style['color'], marker=style['marker'], markersize=4,
                        linewidth=1.2, fillstyle='full' if line == '-' else 'none',
                        label='%s, %s%s' % (name, suffix, ' (%d failed)' % failed if failed
                                            else ''))
            for r in runs:
                if r['method'] == 'bullet' or r is runs[-1]:
                    ax.annotate('%dx%d' % (r['substeps'], r['iterations']),
                                (r['wall_ms_per_step'], r['final_structural_max_strain']),
                                fontsize=6, color=style['color'], xytext=(3, 3),
                                textcoords='offset points')
        ax.axhline(SWING_MAX_TARGET, color='gray', linestyle='-', linewidth=0.8)
        ax.axhline(SWING_MEAN_TARGET, color='gray', linestyle=':', linewidth=0.8)
        ax.set_xscale('log')
        ax.set_yscale('log')
        ax.set_title(titles.get(label, label), fontsize=8.5)
        ax.set_xlabel('wall ms per step (one thread)', fontsize=8)
        ax.set_ylabel('structural strain', fontsize=8)
        ax.grid(True, which='both', alpha=0.25)
        ax.tick_params(labelsize=7)
    axes.flat[0].legend(fontsize=6, loc='lower left')
    fig.suptitle('The general case (issue 50): corners held by grippers closer than the width, '
                 'and the T-shirt held at its shoulders; 3 s at 60 Hz. Targets: 1 % max (solid '
                 'grey), 0.1 % mean (dotted grey); pbd_cloth and Bullet on the same links, the '
                 'held particles moved alike', fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.96))
    fig.savefig(path, dpi=100)
    plt.close(fig)


def general_summary(add, general):
    """Every run of the general sweep, per scene, with its ratio to Bullet 16 x 10 on that scene."""
    add('')
    add('## The general case (sweep_general.csv, doc/general_pareto.png)')
    add('')
    add('Corners held by two grippers closer than the cloth\'s width (config/held_corners.yaml and '
        'config/bench/held_*.yaml) and the T-shirt held at its shoulders (config/tshirt_held.yaml), '
        '3 s. Strains of the structural links (every edge of the shirt): final, and the median over '
        'every step of the last second. Targets: max <= 1 % and mean <= 0.1 %, both readings. '
        'Ratio: wall ms per step over Bullet 16 x 10\'s on the same scene in the same run.')
    titles = dict(GENERAL_PANELS)
    labels = [label for label, _ in GENERAL_PANELS if any(r.get('label') == label
                                                          for r in general)]
    labels += sorted({r.get('label') for r in general} - set(labels) - {None, ''})
    for label in labels:
        mine = [r for r in general if r.get('label') == label]
        peer = next((r for r in mine if r['method'] == 'bullet' and r['substeps'] == 16 and
                     r['iterations'] == 10 and r['ok']), None)
        add('')
        add('### %s' % titles.get(label, label))
        add('')
        add('| curve | setting | wall ms/step | final max | final mean | median max, last 1 s | '
            'median mean, last 1 s | meets both | / Bullet 16x10 |')
        add('|---|---|---|---|---|---|---|---|---|')
        for r in sorted(mine, key=lambda r: (r['curve'] != 'bullet', r['curve'],
                                              r['wall_ms_per_step'])):
            if not r['ok']:
                add('| %s | %dx%d | failed (%s) | | | | | | |' % (
                    r['curve'], r['substeps'], r['iterations'], r.get('error') or
                    r.get('exit_status')))
                continue
            meets = (r['final_structural_max_strain'] <= SWING_MAX_TARGET and
                     r['final_structural_mean_strain'] <= SWING_MEAN_TARGET and
                     r['median_structural_max_strain_last_1s'] <= SWING_MAX_TARGET and
                     r['median_structural_mean_strain_last_1s'] <= SWING_MEAN_TARGET)
            ratio = ('%.2f' % (r['wall_ms_per_step'] / peer['wall_ms_per_step'])
                     if peer else '-')
            add('| %s | %dx%d | %.3g | %.3g | %.3g | %.3g | %.3g | %s | %s |' % (
                r['curve'], r['substeps'], r['iterations'], r['wall_ms_per_step'],
                r['final_structural_max_strain'], r['final_structural_mean_strain'],
                r['median_structural_max_strain_last_1s'],
                r['median_structural_mean_strain_last_1s'], 'yes' if meets else 'no', ratio))


# --- Accuracy on demand (issue 51): the controller against fixed substeps -------------------------

CONTROLLER_PANELS = [
    ('manipulation', 'bench/manipulation.yaml: grasp, lift, shake, lay, fold, let go (4.7 s), '
     'lie still'),
    ('held_corners', 'held_corners.yaml: 50 x 50 held by two corners 0.5 % closer'),
    ('calm', 'hanging.yaml, no tethers: hangs from its pins, settling (not at rest: it starts unstretched)'),
]


def controller_load(data_dir):
    """sweep_controller.csv's rows (numbers parsed), each with its per-step file's columns."""
    rows = load(os.path.join(data_dir, 'sweep_controller.csv'))
    for row in rows:
        for key in ('target_max_strain', 'worst_structural_max_strain', 'target_met_fraction',
                    'mean_substeps', 'total_substeps', 'total_wall_s', 'steps',
                    'steps_under_target_fraction', 'controller_fraction',
                    'controller_ms_per_step', 'redone_steps', 'budget_exhausted_steps',
                    'worst_target_ratio_within_budget'):
            row[key] = number(row.get(key))
        row['is_controller'] = row.get('controller') == '1'
        steps = {'t': [], 'substeps_run': [], 'structural_max_strain': []}
        path = os.path.join(data_dir, row.get('steps_csv') or '-')
        if os.path.exists(path):
            with open(path, newline='') as handle:
                for step in list(csv.DictReader(handle))[1:]:  # the rows after t = 0
                    for key in steps:
                        steps[key].append(number(step[key]))
        row['per_step'] = steps
    return rows


def controller_labels(rows):
    labels = [label for label, _ in CONTROLLER_PANELS if any(r.get('label') == label
                                                             for r in rows)]
    return labels + sorted({r.get('label') for r in rows} - set(labels) - {None, ''})


def controller_verdict(mine):
    """(controller row, fixed rows by substeps, the cheapest fixed row meeting the target at
    every step or None)."""
    control = next((r for r in mine if r['is_controller'] and r['ok']), None)
    fixed = sorted([r for r in mine if not r['is_controller'] and r['ok']],
                   key=lambda r: r['substeps'])
    meeting = [r for r in fixed if r['worst_structural_max_strain'] <= r['target_max_strain']]
    return control, fixed, (meeting[0] if meeting else None)


def controller_figure(rows, path):
    labels = controller_labels(rows)
    titles = dict(CONTROLLER_PANELS)
    fig, axes = plt.subplots(len(labels), 3, figsize=(17.0, 4.3 * len(labels)), squeeze=False)
    for line, label in zip(axes, labels):
        mine = [r for r in rows if r.get('label') == label]
        control, fixed, cheapest = controller_verdict(mine)
        target = mine[0]['target_max_strain']
        # A few fixed settings on the time charts: the cheapest meeting the target at every
        # step, the smallest count, and the one halfway between.
        shown = []
        if fixed:
            shown = [fixed[0], fixed[len(fixed) // 2]]
            if cheapest is not None:
                shown.append(cheapest)
            shown = sorted({id(r): r for r in shown}.values(), key=lambda r: r['substeps'])
        colors = ['tab:gray', 'tab:olive', 'tab:green', 'tab:purple']
        ax_strain, ax_substeps, ax_cost = line
        for k, r in enumerate(shown):
            steps = r['per_step']
            name = '%s%s' % (r['curve'], ' (cheapest meeting it at every step)'
                             if r is cheapest else '')
            ax_strain.plot(steps['t'], steps['structural_max_strain'], color=colors[k % 4],
                           linewidth=0.8, label=name)
            ax_substeps.plot(steps['t'], steps['substeps_run'], color=colors[k % 4],
                             linewidth=0.8, label=name)
        if control is not None:
            steps = control['per_step']
            ax_strain.plot(steps['t'], steps['structural_max_strain'], color='tab:red',
                           linewidth=1.0, label='controller (target %g)' % target)
            ax_substeps.plot(steps['t'], steps['substeps_run'], color='tab:red', linewidth=1.0,
                             label='controller: substeps run (redos counted)')
        ax_strain.axhline(target, color='black', linewidth=0.8, label='target')
        ax_strain.axhline(1.5 * target, color='black', linestyle='--', linewidth=0.8,
                          label='1.5 x target')
        ax_strain.set_yscale('log')
        ax_strain.set_xlabel('simulated time (s)', fontsize=8)
        ax_strain.set_ylabel('structural max strain of the step', fontsize=8)
        ax_strain.set_title('%s\n(a) error over time' % titles.get(label, label), fontsize=8.5)
        ax_strain.legend(fontsize=6, loc='upper right')
        ax_substeps.set_yscale('log')
        ax_substeps.set_xlabel('simulated time (s)', fontsize=8)
        ax_substeps.set_ylabel('substeps run in the step', fontsize=8)
        ax_substeps.set_title('(b) substeps over time', fontsize=8.5)
        ax_substeps.legend(fontsize=6, loc='upper right')
        # (c) total cost: every fixed setting and the controller, substeps and wall time.
        for r in fixed:
            meets = r['worst_structural_max_strain'] <= target
            ax_cost.plot(r['total_substeps'], r['total_wall_s'], 'o',
                         color='tab:green' if meets else 'tab:gray', markersize=5)
            ax_cost.annotate('%d' % r['substeps'], (r['total_substeps'], r['total_wall_s']),
                             fontsize=6, xytext=(3, -8), textcoords='offset points')
        if cheapest is not None:
            ax_cost.plot(cheapest['total_substeps'], cheapest['total_wall_s'], 'o',
                         markersize=13, markerfacecolor='none', markeredgecolor='tab:green',
                         label='cheapest fixed meeting the target at every step (%d x 1)' %
                         cheapest['substeps'])
        if control is not None:
            ax_cost.plot(control['total_substeps'], control['total_wall_s'], '*', color='tab:red',
                         markersize=13, label='controller (met %.1f %% of steps, worst %.2f x '
                         'target within the budget)' % (
                             100 * control['target_met_fraction'],
                             control['worst_target_ratio_within_budget']))
        ax_cost.plot([], [], 'o', color='tab:green', label='fixed N x 1: meets at every step')
        ax_cost.plot([], [], 'o', color='tab:gray', label='fixed N x 1: misses at some step')
        ax_cost.set_xscale('log')
        ax_cost.set_yscale('log')
        ax_cost.set_xlabel('total substeps of the run', fontsize=8)
        ax_cost.set_ylabel('total wall time of the steps (s)', fontsize=8)
        ax_cost.set_title('(c) total cost', fontsize=8.5)
        ax_cost.legend(fontsize=6, loc='upper left')
        for ax in line:
            ax.grid(True, which='both', alpha=0.25)
            ax.tick_params(labelsize=7)
    fig.suptitle('Accuracy on demand (issue 51): the controller (solver.target_max_strain = 1 %%, '
                 'max_substeps %s) against fixed substeps x 1, xpbd, one thread' % (
                     next((r['sets'].split('max_substeps=')[1].split()[0] for r in rows
                           if 'max_substeps=' in r.get('sets', '')), '?')), fontsize=9.5)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(path, dpi=90)
    plt.close(fig)


def controller_summary(add, rows):
    """Issue 51's targets per scene: the controller's met fraction, its worst step over the
    target, and its cost over the cheapest fixed setting meeting the target at every step."""
    add('')
    add('## Accuracy on demand (sweep_controller.csv, doc/controller.png)')
    add('')
    add('The controller (`solver.target_max_strain`, `solver.max_substeps` as in the command) '
        'against fixed substeps x 1 on the same scene; the error is the structural max strain of '
        'every step (cloth_bench `worst_structural_max_strain`). Cheapest fixed: the fewest '
        'substeps of the sweep whose worst step meets the target, chosen in hindsight. Cost: '
        'total substeps of the run (redone attempts counted) and total wall time of the step '
        'calls. Issue 51\'s targets: met in >= 99 % of the steps, no step over 1.5 x the target, '
        'cost <= 1.25 x the cheapest fixed (<= 0.6 x over a run calm for at least half its time), '
        'controller\'s own work <= 5 % of the step.')
    add('')
    add('| scene | controller: met | worst / target (within the budget; steps out of it) | mean substeps | redone steps | total '
        'substeps | wall s | cheapest fixed meeting at every step | its substeps | its wall s | '
        'cost ratio (substeps) | cost ratio (wall) | controller\'s own work / step | '
        'cheapest fixed meeting it in as many steps as the controller: its substeps, ratio '
        '(substeps) |')
    add('|---|---|---|---|---|---|---|---|---|---|---|---|---|---|')
    titles = dict(CONTROLLER_PANELS)
    for label in controller_labels(rows):
        mine = [r for r in rows if r.get('label') == label]
        control, fixed, cheapest = controller_verdict(mine)
        if control is None:
            add('| %s | failed | | | | | | | | | | | | |' % label)
            continue
        target = control['target_max_strain']
        if cheapest is not None:
            theirs = '%d x 1 (worst %.3g)' % (cheapest['substeps'],
                                              cheapest['worst_structural_max_strain'])
            ratio_substeps = '%.2f' % (control['total_substeps'] / cheapest['total_substeps'])
            ratio_wall = '%.2f' % (control['total_wall_s'] / cheapest['total_wall_s'])
            their_substeps = '%d' % cheapest['total_substeps']
            their_wall = '%.3g' % cheapest['total_wall_s']
        else:
            best_fixed = min(fixed, key=lambda r: r['worst_structural_max_strain'], default=None)
            theirs = 'none of the sweep (best: %s, worst %.3g)' % (
                best_fixed['curve'], best_fixed['worst_structural_max_strain']) if best_fixed \
                else 'none'
            ratio_substeps = ratio_wall = their_substeps = their_wall = '-'
        # Not the issue's yardstick (every step), but a fixed setting as good as the controller
        # by the issue's own first measure: the cheapest meeting the target in at least the
        # fraction of the steps the controller met it in.
        as_often = [r for r in fixed if r['steps_under_target_fraction'] >=
                    control['target_met_fraction'] - 1e-9]
        as_often = ('%d x 1: %d, %.2f' % (as_often[0]['substeps'], as_often[0]['total_substeps'],
                                          control['total_substeps'] /
                                          as_often[0]['total_substeps'])
                    if as_often else 'none of the sweep')
        add('| %s | %.1f %% | %.2f (%.2f; %d) | %.1f | %d | %d | %.3g | %s | %s | %s | %s | %s | '
            '%.2f %% | %s |' % (
            titles.get(label, label), 100 * control['target_met_fraction'],
            control['worst_structural_max_strain'] / target,
            control['worst_target_ratio_within_budget'],
            int(number(control.get('budget_exhausted_steps'), 0)), control['mean_substeps'],
            control['redone_steps'], control['total_substeps'], control['total_wall_s'], theirs,
            their_substeps, their_wall, ratio_substeps, ratio_wall,
            100 * control['controller_fraction'], as_often))
    add('')
    add('Every run (`controller/<scene>_<run>.csv` holds each step\'s t, substeps_run, '
        'structural_max_strain, target_met):')
    add('')
    add('| scene | run | worst structural max strain | steps meeting the target | total substeps '
        '| wall s | finite |')
    add('|---|---|---|---|---|---|---|')
    for label in controller_labels(rows):
        for r in sorted([r for r in rows if r.get('label') == label],
                        key=lambda r: (not r['is_controller'], r['substeps'])):
            add('| %s | %s | %.3g | %.1f %% | %s | %.3g | %s |' % (
                label, r['curve'], r['worst_structural_max_strain'],
                100 * r['steps_under_target_fraction'],
                '%d' % r['total_substeps'] if not math.isnan(r['total_substeps']) else '-',
                r['total_wall_s'], r.get('finite')))


def chain_figure(rows, path):
    ratios = sorted({r['mass_ratio'] for r in rows})
    fig, axes = plt.subplots(1, len(ratios), figsize=(6.4 * len(ratios), 5.4))
    if len(ratios) == 1:
        axes = [axes]
    for ax, ratio in zip(axes, ratios):
        mine = [dict(r, end_drop_abs=abs(r['end_drop'])) for r in rows if r['mass_ratio'] == ratio]
        pareto_panel(ax, mine, 'end_drop_abs', 'drop of the end mass below rest (m)')
        ax.set_title('end mass 1:%g' % ratio, fontsize=10)
    axes[0].legend(fontsize=7, loc='lower left')
    fig.suptitle('config/chain_heavy.yaml (REFERENCE_CASES case 5), 10 s at 60 Hz: cost against '
                 'the error of the heavy end', fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def substeps_panel(ax, rows, metric, totals, title, ylabel):
    colors = plt.cm.viridis([k / max(1, len(totals) - 1) for k in range(len(totals))])
    for color, total in zip(colors, totals):
        mine = sorted([r for r in rows if r['passes'] == total and converged_run(r)
                       and abs(r[metric]) > 0], key=lambda r: r['substeps'])
        if not mine:
            continue
        ax.plot([r['substeps'] for r in mine], [abs(r[metric]) for r in mine], '-o',
                color=color, markersize=4, label='%d passes per step' % total)
    ax.set_xscale('log', base=2)
    ax.set_yscale('log')
    ax.set_xlabel('substeps (iterations = passes / substeps)')
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)


def substeps_figure(hanging, chain, path):
    panels = []
    for ratio in sorted({r['mass_ratio'] for r in chain}):
        mine = [r for r in chain if r['mass_ratio'] == ratio and r['curve'] == 'xpbd']
        totals = sorted({int(r['passes']) for r in mine})
        panels.append((mine, 'end_drop', totals,
                       'chain, end mass 1:%g, xpbd' % ratio, 'drop of the end mass (m)'))
    for curve in ('xpbd', 'bullet'):
        mine = [r for r in hanging if r['curve'] == curve]
        totals = [t for t in (4, 16, 64) if any(r['passes'] == t for r in mine)]
        panels.append((mine, 'max_strain', totals, 'hanging cloth, %s' % curve, 'max strain'))
    panels = [p for p in panels if p[0]]
    if not panels:
        return
    fig, axes = plt.subplots(1, len(panels), figsize=(4.6 * len(panels), 4.4))
    if len(panels) == 1:
        axes = [axes]
    for ax, (mine, metric, totals, title, ylabel) in zip(axes, panels):
        substeps_panel(ax, mine, metric, totals, title, ylabel)
    fig.suptitle('Substeps against iterations at equal cost (layout of Small Steps figs. 3-4): '
                 'error at a fixed number of constraint passes per step', fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --- Stability matrix -----------------------------------------------------------------------------

def stability_verdicts(rows):
    """Adds 'stable' to every run: finite, exited normally, energy bounded by E0 + 10 M g L."""
    starts = {}
    for r in rows:
        if r.get('level') == 'start':
            starts[(r.get('panel') or 'chain', r['mass_ratio'] if r.get('panel') != 'ordering'
                    else 'cloth')] = r['energy']
    for r in rows:
        if r.get('level') == 'start':
            continue
        panel = r.get('panel') or 'chain'
        if panel == 'ordering':
            e0 = starts.get(('ordering', 'cloth'), float('nan'))
            scale = 0.5 * G * 1.0  # the 10 x 10 cloth: 0.5 kg, 1 m
        else:
            e0 = starts.get(('chain', r['mass_ratio']), float('nan'))
            scale = (19.0 + r['mass_ratio']) * G * 0.19
        gain = (r['energy'] - e0) / scale
        r['energy_gain'] = gain
        r['stable'] = r['ok'] and math.isfinite(gain) and gain < BOUNDED_ENERGY
    return [r for r in rows if r.get('level') != 'start']


def heat_panel(ax, fig, rows, row_keys, col_keys, row_label, col_label, title, analytic=None):
    import numpy as np
    values = np.full((len(row_keys), len(col_keys)), np.nan)
    unstable = np.zeros((len(row_keys), len(col_keys)), dtype=bool)
    missing = np.ones((len(row_keys), len(col_keys)), dtype=bool)
    for r in rows:
        rk, ck = row_label(r), col_label(r)
        if rk not in row_keys or ck not in col_keys:
            continue
        a, b = row_keys.index(rk), col_keys.index(ck)
        missing[a, b] = False
        if r['stable']:
            values[a, b] = max(r['max_strain'], 1e-9)
        else:
            unstable[a, b] = True
    finite = values[np.isfinite(values)]
    norm = LogNorm(vmin=max(1e-6, finite.min()) if finite.size else 1e-6,
                   vmax=max(finite.max(), 1e-5) if finite.size else 1.0)
    image = ax.imshow(np.ma.masked_invalid(values), cmap='viridis', norm=norm, aspect='auto')
    for a in range(len(row_keys)):
        for b in range(len(col_keys)):
            if unstable[a, b]:
                ax.add_patch(plt.Rectangle((b - 0.5, a - 0.5), 1, 1, color='black'))
                ax.text(b, a, 'unstable', ha='center', va='center', color='white', fontsize=5.5)
            elif missing[a, b]:
                ax.text(b, a, '-', ha='center', va='center', color='gray', fontsize=6)
            elif np.isfinite(values[a, b]):
                ax.text(b, a, '%.0e' % values[a, b], ha='center', va='center', fontsize=5.5,
                        color='white' if norm(values[a, b]) < 0.5 else 'black')
            if analytic and analytic(row_keys[a], col_keys[b]):
                ax.add_patch(plt.Rectangle((b - 0.46, a - 0.46), 0.92, 0.92, fill=False,
                                           edgecolor='red', linewidth=1.2))
    ax.set_xticks(range(len(col_keys)))
    ax.set_xticklabels(['\n'.join(str(x) for x in k) for k in col_keys], fontsize=6.5)
    ax.set_yticks(range(len(row_keys)))
    ax.set_yticklabels([' '.join(str(x) for x in k) for k in row_keys], fontsize=6.5)
    ax.set_title(title, fontsize=9)
    fig.colorbar(image, ax=ax, fraction=0.03, pad=0.01).set_label(
        'max strain over the run (stable runs)', fontsize=7)


def stability_figure(rows, path):
    chain = [r for r in rows if (r.get('panel') or 'chain') == 'chain']
    ordering = [r for r in rows if r.get('panel') == 'ordering']
    order = ['verlet', 'pbd', 'xpbd', 'mass_spring', 'bullet']
    levels = {}
    for r in chain:
        levels.setdefault(r['method'], [])
        if r['level'] not in levels[r['method']]:
            levels[r['method']].append(r['level'])
    row_keys = [(m, lv, 'it=%d' % it) for m in order if m in levels for lv in levels[m]
                for it in sorted({int(r['iterations']) for r in chain})]
    col_keys = [('1:%g' % ratio, 'dt=1/%d' % (60 * s))
                for ratio in sorted({r['mass_ratio'] for r in chain})
                for s in sorted({int(r['substeps']) for r in chain})]

    def analytic_unstable(row_key, col_key):
        # Case 8: explicit springs diverge when w_max dt >= 2, w_max^2 = 4 k / (1 kg) on the chain.
        if row_key[0] != 'mass_spring':
            return False
        k = float(row_key[1].split('=')[1])
        dt = 1.0 / float(col_key[1].split('/')[1])
        return 2.0 * math.sqrt(k) * dt >= 2.0

    fig, axes = plt.subplots(1, 2, figsize=(15, 9), gridspec_kw={'width_ratios': [3, 1.1]})
    heat_panel(ax=axes[0], fig=fig, rows=chain, row_keys=row_keys, col_keys=col_keys,
               row_label=lambda r: (r['method'], r['level'], 'it=%d' % r['iterations']),
               col_label=lambda r: ('1:%g' % r['mass_ratio'], 'dt=1/%d' % (60 * r['substeps'])),
               title='heavy chain (config/chain_heavy.yaml, hanging at rest, 2 s): method x '
                     'stiffness x iterations (rows), end mass ratio x substep dt (columns)\n'
                     'red frame: unstable by the analytic limit w_max dt >= 2 (case 8)',
               analytic=analytic_unstable)
    if ordering:
        o_rows = [('xpbd', lv, 'it=%d' % it) for lv in ('gauss_seidel', 'jacobi, averaged',
                                                          'jacobi, plain')
                  for it in sorted({int(r['iterations']) for r in ordering})]
        o_cols = [('dt=1/%d' % (60 * s),) for s in sorted({int(r['substeps']) for r in ordering})]
        heat_panel(ax=axes[1], fig=fig, rows=ordering, row_keys=o_rows, col_keys=o_cols,
                   row_label=lambda r: ('xpbd', r['level'], 'it=%d' % r['iterations']),
                   col_label=lambda r: ('dt=1/%d' % (60 * r['substeps']),),
                   title='ordering, 10 x 10 hanging cloth (2 s):\nplain Jacobi diverges '
                         '(K >= 3 constraints, case 7)')
    else:
        axes[1].axis('off')
    fig.suptitle('Stability matrix: stable = finite and energy below E0 + 10 M g L; colour = '
                 'max strain of the stable runs (log)', fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --- Summary --------------------------------------------------------------------------------------

def cheapest(rows, curve, metric, target):
    meeting = [r for r in rows if r['curve'] == curve and converged_run(r) and r[metric] <= target]
    return min(meeting, key=lambda r: r['wall_ms_per_step']) if meeting else None


def best(rows, curve, metric):
    mine = [r for r in rows if r['curve'] == curve and converged_run(r)]
    return min(mine, key=lambda r: (r[metric], r['wall_ms_per_step'])) if mine else None


def fmt_ms(value):
    return '%.3g ms' % value


def read_microbench(path):
    if not os.path.exists(path):
        return []
    with open(path, newline='') as handle:
        lines = handle.read().splitlines()
    # Google Benchmark writes its context before the CSV header.
    start = next((k for k, line in enumerate(lines) if line.startswith('name,')), None)
    if start is None:
        return []
    return list(csv.DictReader(lines[start:]))


def swinging_verdicts(rows):
    """Drops the t = 0 row and marks runs whose cloth never fell (energy within 1 % of the start's:
    Bullet in single precision with tiny internal steps) as failed, like diverged ones."""
    start = [r for r in rows if r.get('level') == 'start']
    runs = [r for r in rows if r.get('level') != 'start']
    if start and math.isfinite(start[0]['energy']):
        e0 = start[0]['energy']
        for r in runs:
            if r['ok'] and math.isfinite(r['energy']) and abs(r['energy'] - e0) < 0.01 * abs(e0):
                r['ok'] = False
                r['frozen'] = True
    return runs


def verdict(row):
    if row.get('frozen'):
        return 'frozen'
    return 'ok' if converged_run(row) else 'diverged'


def swinging_summary(add, swinging, name='swinging', size=50):
    """Issue 12's benchmark: which settings reach 1 % max / 0.1 % mean structural strain."""
    add('')
    add('## Swinging cloth (config/swinging.yaml%s): cost of 1 %% max / 0.1 %% mean '
        'strain' % ('' if size == 50 else ' at %d x %d' % (size, size)))
    add('')
    add('%d x %d, 1 m, structural links and both diagonals per cell, zero compliance, no bending, '
        'no tethers; starts flat and swings down from two pinned corners for 3 s at 60 Hz. Error: '
        'strain of the structural links in the final state (`final_structural_max_strain`, '
        '`final_structural_mean_strain`), Bullet on the same links. N x M = substeps x '
        'iterations (Bullet: internal steps x position iterations).' % (size, size))
    add('')
    add('| curve | cheapest with max <= 1 % | cheapest with mean <= 0.1 % | cheapest with both | '
        'best max strain (ms) |')
    add('|---|---|---|---|---|')
    mx, mn = 'final_structural_max_strain', 'final_structural_mean_strain'

    def cell(run):
        if not run:
            return 'not reached'
        return '%s (%dx%d; %.3g / %.3g)' % (fmt_ms(run['wall_ms_per_step']), run['substeps'],
                                            run['iterations'], run[mx], run[mn])
    for curve in curves_of(swinging):
        mine = [r for r in swinging if r['curve'] == curve and converged_run(r)]
        both = [r for r in mine if r[mx] <= SWING_MAX_TARGET and r[mn] <= SWING_MEAN_TARGET]
        top = min(mine, key=lambda r: r[mx]) if mine else None
        add('| %s | %s | %s | %s | %s |' % (
            curve, cell(cheapest(swinging, curve, mx, SWING_MAX_TARGET)),
            cell(cheapest(swinging, curve, mn, SWING_MEAN_TARGET)),
            cell(min(both, key=lambda r: r['wall_ms_per_step']) if both else None),
            '%.3g (%.3g ms)' % (top[mx], top['wall_ms_per_step']) if top else '-'))
    add('')
    add('(cell: wall ms per step (setting; final max / mean structural strain).)')
    loads = [float(x) for r in swinging for x in (r.get('load_rounds') or r.get('load') or '')
             .split(';') if x]
    rounds = {r.get('rounds') for r in swinging if r.get('rounds')}
    if loads:
        add('')
        add('Wall times: the median of %s rounds of each run (`wall_ms_rounds` in the CSV); the '
            '1-minute load average at the start of the runs was %.2f to %.2f on this 2-core '
            'machine (other builds), so compare times within this run, not across runs.' % (
                '/'.join(sorted(rounds)) or '1', min(loads), max(loads)))
    add('')
    add('Every run (the command of each is in doc/sweep_%s.csv):' % name)
    add('')
    add('| curve | N x M | wall ms/step | cpu ms/step | project ms | final max strain | '
        'final mean strain | max strain over the run, all links | verdict | --set |')
    add('|---|---|---|---|---|---|---|---|---|---|')
    for curve in curves_of(swinging):
        for r in sorted([r for r in swinging if r['curve'] == curve],
                        key=lambda r: r['wall_ms_per_step']):
            add('| %s | %dx%d | %.3g | %s | %s | %.3g | %.3g | %.3g | %s | `%s` |' % (
                curve, r['substeps'], r['iterations'], r['wall_ms_per_step'],
                '%.3g' % r['cpu_ms_per_step'] if math.isfinite(r['cpu_ms_per_step']) else '-',
                '%.3g' % r['project_ms'] if math.isfinite(r['project_ms']) else '-',
                r[mx], r[mn], r['max_strain'], verdict(r), r.get('sets', '')))
    add('')
    add('verdict: ok; diverged (non-finite, or links over %g x rest length at some sample); frozen '
        '(the cloth never fell: energy within 1 %% of the start, Bullet\'s single precision).'
        % DIVERGED_STRAIN)


def micro_ns(micro, name):
    for row in micro:
        if row['name'].replace('/manual_time', '') == name and row.get('ns_per_item'):
            return number(row['ns_per_item'])
    return None


def micro_label(micro, name):
    """The path a benchmark ran, from its label: 'projectStretchLinks, AVX-512' -> 'AVX-512'."""
    for row in micro:
        if row['name'].replace('/manual_time', '') == name and row.get('label'):
            return row['label'].split(', ')[-1]
    return None


# The machine the issue's milliseconds were measured on: there Bullet 16 x 10 stepped the 50 x 50
# swinging cloth (both diagonals) in 22.2 ms, and in 16.6 ms on one diagonal per cell (measured
# since). The same machine kind has run it in 8-12 ms on other days (a shared virtual machine), so
# a target in ms says little without the peer's time in the same run.
ISSUE_BULLET_MS = {'bullet': 22.2, 'bullet, one diagonal': 16.6}

# Issue 12's targets 1 and 2: ms per step, the fallback the acceptance allows, the grid's side.
SWING_TARGETS = ((1, 1.6, 5.0, 50), (2, 6.5, 20.0, 100))
# The curves a target's setting is chosen from, cheapest first.
SWING_TARGET_CURVES = ('xpbd', 'xpbd + levels', 'xpbd + 2 levels', 'xpbd + 4 levels')


def target_met(ms, goal, fallback):
    return 'yes' if ms <= goal else ('fallback (<= %g ms)' % fallback if ms <= fallback
                                     else 'no')


def bullet_factors(swinging):
    """How much faster this machine ran than the issue's: (curve, Bullet 16 x 10's ms here, the
    issue's ms over that), both diagonals first (the issue's own link set), then one diagonal."""
    factors = []
    for curve, issue_ms in ISSUE_BULLET_MS.items():
        run = next((r for r in swinging if r['curve'] == curve and r['substeps'] == 16 and
                    r['iterations'] == 10), None)
        if run:
            factors.append((curve, run['wall_ms_per_step'], issue_ms / run['wall_ms_per_step']))
    return factors


def machine_yardstick(swinging, swinging100, cheapest_both):
    """Targets 1 and 2 scaled to the issue's machine by Bullet 16 x 10's time in this run."""
    factors = bullet_factors(swinging)
    if not factors:
        return None
    factor = factors[0][2]  # the issue's own link set (both diagonals)
    scaled, verdicts = [], []
    for (number_, goal, fallback, _), rows in zip(SWING_TARGETS, (swinging, swinging100)):
        run = cheapest_both(rows, SWING_TARGET_CURVES) if rows else None
        if run:
            ms = run['wall_ms_per_step'] * factor
            scaled.append('target %d %.3g ms' % (number_, ms))
            verdicts.append('target %d %s' % (number_, target_met(ms, goal, fallback)))
    return ('| 1-2 | targets 1 and 2 on the issue\'s machine, where Bullet 16 x 10 took %s | '
            'Bullet 16 x 10 in this run: %s; this machine ran x%.2f faster, and scaled by that: '
            '%s | %s |' % (
                ' and '.join('%g ms (%s)' % (ms, c) for c, ms in ISSUE_BULLET_MS.items()),
                ', '.join('%s (%s: x%.2f)' % (fmt_ms(ms), c, f) for c, ms, f in factors),
                factor, ', '.join(scaled), ', '.join(verdicts)))


# Issue 12's targets 1-3 by the setting scripts/issue_yardstick times for each: (number, the
# setting's name in issue_yardstick.csv, goal ms, fallback ms or None, strains checked).
YARDSTICK_TARGETS = (
    (1, 'today: target 1, levels 36x1, both diagonals', 1.6, 5.0, True),
    (1, 'today: target 1, 2 levels 34x1, both diagonals', 1.6, 5.0, True),
    (1, 'today: target 1, levels 40x1, one diagonal', 1.6, 5.0, True),
    (2, 'today: target 2, 100x100 xpbd 104x1, both diagonals', 6.5, 20.0, True),
    (2, 'today: target 2, 100x100 levels 96x1, both diagonals', 6.5, 20.0, True),
    (3, 'today: target 3, fabric_table', 1.5, None, False),
    (3, 'today: target 3, fabric_table + self-collision', 3.0, None, False),
)


def issue_yardstick_row(data_dir):
    """Targets 1-3 on the issue's machine, scaled by the issue's own program (pbd_cloth at the
    commit the issue was filed on) timed in the same rounds (scripts/issue_yardstick), or None."""
    path = os.path.join(data_dir, 'issue_yardstick.csv')
    if not os.path.exists(path):
        return None
    with open(path, newline='') as handle:
        rows = {r['setting']: r for r in csv.DictReader(handle)}
    day = [rows.get('issue day: xpbd %dx1, one diagonal' % n) for n in (80, 20)]
    if not all(day):
        return None
    factor = number(day[0]['x_faster_than_issue'])  # the issue's 80 x 1: its larger figure
    scaled, verdicts = [], []
    for number_, name, goal, fallback, strains in YARDSTICK_TARGETS:
        run = rows.get(name)
        if not run:
            continue
        ms = number(run['median_wall_ms_per_step']) * factor
        label = name.split(': ', 1)[1]
        reached = (not strains or
                   (number(run['final_structural_max_strain']) <= SWING_MAX_TARGET and
                    number(run['final_structural_mean_strain']) <= SWING_MEAN_TARGET))
        scaled.append('%s: %s (%s here)' % (label, fmt_ms(ms),
                                            fmt_ms(number(run['median_wall_ms_per_step']))))
        if not reached:
            verdicts.append('%s: strain not reached' % label)
        elif fallback is None:
            verdicts.append('%s: %s' % (label, 'yes' if ms <= goal else 'no'))
        else:
            verdicts.append('%s: %s' % (label, target_met(ms, goal, fallback)))
    bullet = ['%s %s (issue %s ms: x%.2f)' % (r['setting'], fmt_ms(number(r['median_wall_ms_per_step'])),
                                             r['issue_ms'], number(r['x_faster_than_issue']))
              for r in rows.values() if r['program'] == 'bullet']
    return ('| 1-3 | on the issue\'s machine by the issue\'s own program: pbd_cloth %s (the commit '
            'the issue was filed on), plain xpbd on the swinging cloth, 80 x 1 and 20 x 1: 6.2 '
            'and 1.6 ms there | %s and %s here (x%.2f and x%.2f, medians of the same rounds as '
            'the settings: doc/issue_yardstick.csv); scaled by x%.2f: %s. Bullet in the same '
            'rounds: %s | %s |' % (
                day[0]['program'].split()[-1], fmt_ms(number(day[0]['median_wall_ms_per_step'])),
                fmt_ms(number(day[1]['median_wall_ms_per_step'])), factor,
                number(day[1]['x_faster_than_issue']), factor, '; '.join(scaled),
                '; '.join(bullet), '; '.join(verdicts)))


def issue12_summary(add, data_dir, swinging, swinging100, fabric, towel, micro):
    """Issue 12's targets, each with what this run measured (all from the CSVs of doc/)."""
    add('')
    add('## Speed targets: what this run measured')
    add('')
    add('| # | target | measured (this run) | met |')
    add('|---|---|---|---|')
    mx, mn = 'final_structural_max_strain', 'final_structural_mean_strain'

    def cheapest_both(rows, curves):
        curves = (curves,) if isinstance(curves, str) else curves
        both = [r for r in rows if r['curve'] in curves and converged_run(r) and
                r[mx] <= SWING_MAX_TARGET and r[mn] <= SWING_MEAN_TARGET]
        return min(both, key=lambda r: r['wall_ms_per_step']) if both else None

    for (number_, goal, fallback, size), rows in zip(SWING_TARGETS, (swinging, swinging100)):
        run = cheapest_both(rows, SWING_TARGET_CURVES) if rows else None
        if run:
            ms = run['wall_ms_per_step']
            met = target_met(ms, goal, fallback)
            # The steady reading beside the final instant (cloth_bench's median over the last
            # second; runs before it have none).
            median = run.get('last_second_median_structural_max_strain')
            steady = ('; median over the last second %.3g' % median
                      if median is not None and not math.isnan(median) else '')
            add('| %d | %d x %d swinging, 1 %% / 0.1 %%, one thread: <= %g ms (at least <= %g) | '
                '%s, %s %dx%d (%.3g / %.3g%s) | %s |' % (
                    number_, size, size, goal, fallback, fmt_ms(ms), run['curve'], run['substeps'],
                    run['iterations'], run[mx], run[mn], steady, met))
        else:
            add('| %d | %d x %d swinging | not reached in this run | no |' % (number_, size, size))
        if number_ == 1:
            # The same target on one diagonal per cell, the link set of the peers' figures given
            # since (Bender's PBD 160 x 1: 23.8 ms, Bullet 16 x 10: 16.6 ms; doc/journal.md "Speed (issue 12)" and
            # doc/journal.md, "On equal links").
            one = cheapest_both(rows, 'xpbd + levels, one diagonal') if rows else None
            if one:
                add('| 1 | the same on one diagonal per cell (the link set of the peers\' figures '
                    'given since) | %s, xpbd + levels %dx%d (%.3g / %.3g) | (comparison) |' % (
                        fmt_ms(one['wall_ms_per_step']), one['substeps'], one['iterations'],
                        one[mx], one[mn]))
    yardstick = machine_yardstick(swinging, swinging100, cheapest_both)
    if yardstick:
        add(yardstick)
    own = issue_yardstick_row(data_dir)
    if own:
        add(own)
    if fabric:
        # The target names no thread count (targets 1 and 2 say one thread): both are shown.
        for curve, goal in (('xpbd', 1.5), ('xpbd, 2 threads', 1.5),
                            ('xpbd + self-collision', 3.0),
                            ('xpbd + self-collision, 2 threads', 3.0)):
            run = next((r for r in fabric if r['curve'] == curve), None)
            if run:
                add('| 3 | fabric_table.yaml (dt 3 ms, 12 substeps) %s: <= %g ms | %s (cpu %s) '
                    '| %s |' % (curve, goal, fmt_ms(run['wall_ms_per_step']),
                                fmt_ms(run['cpu_ms_per_step']),
                                'yes' if run['wall_ms_per_step'] <= goal else 'no'))
        # One thread, scaled to the issue's machine as targets 1 and 2 are: by Bullet's time on
        # both diagonals (the verdict), and on one (shown beside it).
        factors = bullet_factors(swinging) if swinging else []
        runs = [(next((r for r in fabric if r['curve'] == curve), None), goal)
                for curve, goal in (('xpbd', 1.5), ('xpbd + self-collision', 3.0))]
        if factors and all(run for run, _ in runs):
            scaled = [[run['wall_ms_per_step'] * f for run, _ in runs] for _, _, f in factors]
            add('| 3 | fabric_table.yaml on the issue\'s machine, one thread, scaled by Bullet 16 x 10 '
                'as targets 1 and 2 (x%.2f%s): <= 1.5 ms, <= 3 ms with self-collision | %s and %s%s '
                '| %s |' % (
                    factors[0][2],
                    '; x%.2f on one diagonal' % factors[1][2] if len(factors) > 1 else '',
                    fmt_ms(scaled[0][0]), fmt_ms(scaled[0][1]),
                    ' (on one diagonal\'s scale %s and %s)' % (fmt_ms(scaled[1][0]),
                                                              fmt_ms(scaled[1][1]))
                    if len(scaled) > 1 else '',
                    ', '.join('yes' if ms <= goal else 'no'
                              for ms, (_, goal) in zip(scaled[0], runs))))
    pairs = [(swinging, 'xpbd + levels', 'xpbd + levels, 2 threads', '50 x 50 swinging'),
             (swinging100, 'xpbd + levels', 'xpbd + levels, 2 threads', '100 x 100 swinging'),
             (fabric, 'xpbd', 'xpbd, 2 threads', 'fabric_table'),
             (fabric, 'xpbd + self-collision', 'xpbd + self-collision, 2 threads',
              'fabric_table + self-collision')]
    for rows, one, two, label in pairs:
        if not rows:
            continue
        for a in sorted([r for r in rows if r['curve'] == one], key=lambda r: r['substeps']):
            b = next((r for r in rows if r['curve'] == two and r['substeps'] == a['substeps']
                      and r['iterations'] == a['iterations']), None)
            if b:
                same = a[mx] == b[mx] and a[mn] == b[mn] if mx in a and mx in b else None
                add('| 4 | threads: 2 measurably faster, same result (%s %dx%d) | 1 thread %s, '
                    '2 threads %s: x%.2f; final strains %s | %s |' % (
                        label, a['substeps'], a['iterations'], fmt_ms(a['wall_ms_per_step']),
                        fmt_ms(b['wall_ms_per_step']),
                        a['wall_ms_per_step'] / b['wall_ms_per_step'],
                        'identical' if same else 'differ',
                        'yes' if b['wall_ms_per_step'] < 0.9 * a['wall_ms_per_step'] and same
                        else 'no'))
    simd, portable, bare = (micro_ns(micro, 'BM_StretchLinks/simd:1'),
                            micro_ns(micro, 'BM_StretchLinks/simd:0'),
                            micro_ns(micro, 'BM_StretchBareLoop'))
    avx2 = micro_ns(micro, 'BM_StretchLinks/simd:2')  # AVX2 at most (solver.avx512: false)
    if simd and bare:
        widest = micro_label(micro, 'BM_StretchLinks/simd:1') or 'SIMD'
        add('| 5 | stretch projection within 1.5x of a bare loop (Google Benchmark pair) | '
            '%s %.3g ns%s, portable %.3g ns, bare loop %.3g ns per link: x%.2f and x%.2f | %s |'
            % (widest, simd, ', AVX2 %.3g ns' % avx2 if avx2 and avx2 != simd else '',
               portable or float('nan'), bare, simd / bare,
               (portable or float('nan')) / bare, 'yes' if simd <= 1.5 * bare and
               (portable is None or portable <= 1.5 * bare) else 'no'))
    if towel:
        run = next((r for r in towel if r['curve'] == 'xpbd, sleeping'), None)
        if run and number(run.get('asleep_ms_per_step'), 0.0) > 0:
            asleep, awake = number(run['asleep_ms_per_step']), number(run['awake_ms_per_step'])
            add('| 6 | towel at rest <= 10 %% of its moving cost | asleep %.3g ms, awake %.3g ms '
                'per step (%d steps asleep): %.2g %% | %s |' % (
                    asleep, awake, int(number(run['asleep_steps'], 0)), 100.0 * asleep / awake,
                    'yes' if asleep <= 0.1 * awake else 'no'))
    growth = {}
    for name, csv_name in (('same size', 'self_collision_scaling.csv'),
                           ('same density', 'self_collision_scaling_density.csv')):
        path = os.path.join(data_dir, csv_name)
        if os.path.exists(path):
            with open(path, newline='') as handle:
                rows = list(csv.DictReader(handle))
            growth[name] = [number(r.get('broad_plus_contact_on_per_doubling'))
                            for r in rows if r.get('broad_plus_contact_on_per_doubling')]
    growth = {name: g for name, g in growth.items() if g}
    if growth:
        add('| 7 | self-collision broad phase + contacts <= x2.3 per doubling, 32 x 32 to 128 x '
            '128 | %s (doc/self_collision_scaling.csv, _density.csv) | %s |' % (
                '; '.join('%s: %s' % (name, ', '.join('x%.2f' % x for x in g))
                          for name, g in growth.items()),
                ', '.join('%s %s' % (name, 'yes' if max(g) <= 2.3 else 'no')
                          for name, g in growth.items())))


def extra_summaries(add, swinging100, fabric, towel):
    if swinging100:
        swinging_summary(add, swinging100, 'swinging100', 100)
    for rows, title in ((fabric, 'fabric_simulator\'s settings (config/fabric_table.yaml, dt 3 ms, '
                                 '12 substeps, 2 s)'),
                        (towel, 'A towel at rest (config/towel_on_table.yaml, 6 s)')):
        if not rows:
            continue
        add('')
        add('## %s' % title)
        add('')
        add('| curve | wall ms/step | cpu ms/step | asleep steps | asleep ms/step | awake ms/step | '
            'max penetration (m) | self-intersections | --set |')
        add('|---|---|---|---|---|---|---|---|---|')
        for r in rows:
            add('| %s | %.3g | %.3g | %s | %s | %s | %.3g | %s | `%s` |' % (
                r['curve'], r['wall_ms_per_step'], r['cpu_ms_per_step'],
                r.get('asleep_steps', ''), r.get('asleep_ms_per_step', ''),
                r.get('awake_ms_per_step', ''), number(r.get('max_penetration'), 0.0),
                r.get('max_self_intersections', ''), r.get('sets', '')))


def summary(data_dir, hanging, drape, chain, stability, env_text, swinging=(), swinging100=(),
            fabric=(), towel=(), general=(), controller=()):
    out = []
    add = out.append
    add('# Bench summary')
    add('')
    add('Generated by `scripts/run_bench` (sweeps: `scripts/bench_sweep.py`; charts and this file: '
        '`scripts/plot_bench.py`). Every figure below comes from the CSVs listed here, each row of '
        'which holds the exact command line that produced it. The machine and load below are '
        'those of the last run; a run with `--only` rewrites only its own CSVs, so compare the '
        'times of the CSVs written by one run.')
    add('')
    for name in ('hanging', 'swinging', 'swinging100', 'general', 'controller', 'fabric', 'towel',
                 'drape', 'chain', 'stability'):
        path = os.path.join(data_dir, 'sweep_%s.csv' % name)
        if os.path.exists(path):
            with open(path, newline='') as handle:
                dates = {r.get('sweep_date') for r in csv.DictReader(handle)} - {None, ''}
            add('- `sweep_%s.csv`: %s' % (name, 'swept %s' % ', '.join(sorted(dates)) if dates
                                           else 'no sweep date recorded (a run before they were)'))
    if env_text:
        add('')
        add('```')
        add(env_text.strip())
        add('```')
    add('')
    add('Wall time per step is the mean over the run of the step calls only (metrics excluded), '
        'one thread. max_strain is the largest |l - l0| / l0 over the stretch links at any step '
        'of the run (transients included), mean_strain that of the final state; Bullet is '
        'measured on the same links with the same code (`pbd_cloth::computeStrain`).')

    if hanging:
        add('')
        add('## Hanging cloth (config/hanging.yaml, 50 x 50, 3 s): our cost against Bullet\'s')
        add('')
        add('Cheapest run of each curve whose max strain is at most the target '
            '(wall ms per step, and its setting). Ratio = ours / Bullet (below 1: we are cheaper).')
        add('')
        targets = [1.0, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01]
        ours = ['xpbd', 'xpbd, no bending', 'xpbd + tethers']
        peers = ['bullet', 'bullet + bending links']
        present = [c for c in ours + peers if any(r['curve'] == c for r in hanging)]
        add('| max strain <= | ' + ' | '.join(present) + ' | xpbd / bullet | '
            'xpbd no bending / bullet |')
        add('|---|' + '---|' * (len(present) + 2))
        for target in targets:
            cells, costs = [], {}
            for curve in present:
                run = cheapest(hanging, curve, 'max_strain', target)
                costs[curve] = run['wall_ms_per_step'] if run else None
                cells.append('%s (%dx%d)' % (fmt_ms(run['wall_ms_per_step']), run['substeps'],
                                             run['iterations']) if run else 'not reached')

            def ratio(a, b):
                if costs.get(a) and costs.get(b):
                    return '%.2f' % (costs[a] / costs[b])
                return '-'
            add('| %g | %s | %s | %s |' % (target, ' | '.join(cells), ratio('xpbd', 'bullet'),
                                           ratio('xpbd, no bending', 'bullet')))
        add('')
        add('(N x M = substeps x iterations; for Bullet internal steps x position iterations.)')
        add('')
        add('Best max strain each curve reaches in the sweep:')
        add('')
        add('| curve | best max strain | mean strain | wall ms per step | setting |')
        add('|---|---|---|---|---|')
        for curve in curves_of(hanging):
            run = best(hanging, curve, 'max_strain')
            if run:
                add('| %s | %.3g | %.3g | %.3g | `%s` |' % (
                    curve, run['max_strain'], run['mean_strain'], run['wall_ms_per_step'],
                    setting(run)))
        # At equal max strain: Bullet's best against the cheapest xpbd that matches it.
        bullet_best = best(hanging, 'bullet', 'max_strain')
        if bullet_best:
            add('')
            for curve in ('xpbd', 'xpbd, no bending', 'xpbd + tethers'):
                match = cheapest(hanging, curve, 'max_strain', bullet_best['max_strain'])
                if match:
                    add('- At Bullet\'s best max strain (%.3g, %.3g ms): %s reaches %.3g at '
                        '%.3g ms, cost ratio ours / Bullet = **%.2f**.' % (
                            bullet_best['max_strain'], bullet_best['wall_ms_per_step'], curve,
                            match['max_strain'], match['wall_ms_per_step'],
                            match['wall_ms_per_step'] / bullet_best['wall_ms_per_step']))
                else:
                    ours_best = best(hanging, curve, 'max_strain')
                    if ours_best:
                        add('- %s does not reach Bullet\'s best max strain %.3g in the sweep; '
                            'its best is %.3g at %.3g ms.' % (curve, bullet_best['max_strain'],
                                                             ours_best['max_strain'],
                                                             ours_best['wall_ms_per_step']))
        diverged = [r for r in hanging if not converged_run(r)]
        if diverged:
            add('')
            add('Diverged runs (non-finite or links over %g x rest length): %s.' % (
                DIVERGED_STRAIN, ', '.join('%s %dx%d' % (r['curve'], r['substeps'],
                                                         r['iterations']) for r in diverged)))

        add('')
        add('## Cheapest setting per method for max strain <= 1 % on hanging.yaml')
        add('')
        add('| curve | cheapest run meeting 1 % | max strain | mean strain | wall ms per step | '
            'cloth_bench --set ... |')
        add('|---|---|---|---|---|---|')
        for curve in curves_of(hanging):
            run = cheapest(hanging, curve, 'max_strain', TARGET)
            if run:
                add('| %s | %dx%d | %.3g | %.3g | %.3g | `%s` |' % (
                    curve, run['substeps'], run['iterations'], run['max_strain'],
                    run['mean_strain'], run['wall_ms_per_step'], setting(run)))
            else:
                near = best(hanging, curve, 'max_strain')
                add('| %s | not reached in the sweep | best %s | | %s | `%s` |' % (
                    curve, '%.3g' % near['max_strain'] if near else '-',
                    '%.3g' % near['wall_ms_per_step'] if near else '-',
                    setting(near) if near else ''))
        add('')
        add('Mean strain <= 1 %:')
        add('')
        add('| curve | cheapest run | mean strain | max strain | wall ms per step |')
        add('|---|---|---|---|---|')
        for curve in curves_of(hanging):
            run = cheapest(hanging, curve, 'mean_strain', TARGET)
            if run:
                add('| %s | %dx%d | %.3g | %.3g | %.3g |' % (
                    curve, run['substeps'], run['iterations'], run['mean_strain'],
                    run['max_strain'], run['wall_ms_per_step']))
            else:
                add('| %s | not reached | | | |' % curve)

    micro = read_microbench(os.path.join(data_dir, 'microbench.csv'))
    issue12_summary(add, data_dir, swinging, swinging100, fabric, towel, micro)
    if swinging:
        swinging_summary(add, swinging)
    extra_summaries(add, swinging100, fabric, towel)
    if general:
        general_summary(add, general)
    if controller:
        controller_summary(add, controller)

    if drape:
        add('')
        add('## Drape (config/drape.yaml, 32 x 32 on a ball and table, 3 s)')
        add('')
        add('| curve | cheapest run with max strain <= 10 % | max penetration (m) | '
            'self-intersections at the end | wall ms per step |')
        add('|---|---|---|---|---|')
        for curve in curves_of(drape):
            run = cheapest(drape, curve, 'max_strain', 0.1)
            if run:
                add('| %s | %dx%d (max strain %.3g) | %.3g | %s | %.3g |' % (
                    curve, run['substeps'], run['iterations'], run['max_strain'],
                    run['max_penetration'], run.get('self_intersections'),
                    run['wall_ms_per_step']))
            else:
                near = best(drape, curve, 'max_strain')
                add('| %s | not reached (best %s) | | | |' % (
                    curve, '%.3g' % near['max_strain'] if near else '-'))
        if any(r['curve'] == 'bullet' for r in drape):
            add('')
            add('Bullet runs the drape without cloth self-collision (it needs clusters for that), '
                'so its self-intersection count is not comparable.')

    if chain:
        add('')
        add('## Heavy chain (config/chain_heavy.yaml, 10 s): substeps against iterations')
        add('')
        add('Drop of the end mass below its rest position, equal number of passes per step '
            '(REFERENCE_CASES case 5; Small Steps reports ~322 m with 100 iterations against '
            '~3.2 m with 100 substeps at 1:1e5 over its own run length).')
        add('')
        add('| curve | end mass | passes | all substeps | all iterations | ratio |')
        add('|---|---|---|---|---|---|')
        for curve in ('xpbd', 'pbd', 'bullet'):
            for ratio in sorted({r['mass_ratio'] for r in chain}):
                mine = [r for r in chain if r['curve'] == curve and r['mass_ratio'] == ratio
                        and r['ok']]
                for total in sorted({r['passes'] for r in mine}):
                    subs = [r for r in mine if r['passes'] == total and r['iterations'] == 1]
                    its = [r for r in mine if r['passes'] == total and r['substeps'] == 1]
                    if total < 16 or not subs or not its:
                        continue
                    a, b = abs(subs[0]['end_drop']), abs(its[0]['end_drop'])
                    add('| %s | 1:%g | %d | %.3g m | %.3g m | %s |' % (
                        curve, ratio, total, a, b, '%.0fx' % (b / a) if a > 0 else '-'))

    if stability:
        add('')
        add('## Stability matrix (doc/stability_matrix.png)')
        add('')
        add('| method | runs | unstable | unstable cells |')
        add('|---|---|---|---|')
        for method in ('verlet', 'pbd', 'xpbd', 'mass_spring', 'bullet'):
            mine = [r for r in stability if r['method'] == method
                    and (r.get('panel') or 'chain') == 'chain']
            bad = [r for r in mine if not r['stable']]
            cells = ', '.join(sorted({'%s ratio 1:%g dt 1/%d' % (r['level'], r['mass_ratio'],
                                                                 60 * r['substeps'])
                                      for r in bad}))
            add('| %s | %d | %d | %s |' % (method, len(mine), len(bad), cells or '-'))
        springs = [r for r in stability if r['method'] == 'mass_spring']
        agree = sum(1 for r in springs if r['stable'] == (
            2.0 * math.sqrt(float(r['level'].split('=')[1])) / (60 * r['substeps']) < 2.0))
        if springs:
            add('')
            add('mass_spring: %d of %d runs agree with the analytic limit w_max dt < 2 '
                '(w_max^2 = 4 k / m on the chain).' % (agree, len(springs)))
        ordering = [r for r in stability if r.get('panel') == 'ordering']
        for level in ('gauss_seidel', 'jacobi, averaged', 'jacobi, plain'):
            mine = [r for r in ordering if r['level'] == level]
            if mine:
                add('- 10 x 10 cloth, xpbd %s: %d of %d runs stable.' % (
                    level, sum(1 for r in mine if r['stable']), len(mine)))

    micro = read_microbench(os.path.join(data_dir, 'microbench.csv'))
    if micro:
        add('')
        add('## Microbenchmarks (test/bench/microbench.cpp, doc/microbench.csv)')
        add('')
        add('| benchmark | time per iteration | count | ns per item | item |')
        add('|---|---|---|---|---|')
        for row in micro:
            per = row.get('ns_per_item') or ''
            add('| %s | %.4g %s | %s | %s | %s |' % (
                row['name'].replace('/manual_time', ''), number(row.get('real_time')),
                row.get('time_unit', ''), '%.0f' % number(row.get('count')),
                '%.3g' % number(per) if per else '', row.get('label', '')))
    return '\n'.join(out) + '\n'


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--data', default=os.path.join(REPO, 'doc'))
    parser.add_argument('--env', default=None, help='text file about the run (machine, load)')
    args = parser.parse_args()
    data = args.data
    hanging = load(os.path.join(data, 'sweep_hanging.csv'))
    drape = load(os.path.join(data, 'sweep_drape.csv'))
    swinging = swinging_verdicts(load(os.path.join(data, 'sweep_swinging.csv')))
    swinging100 = swinging_verdicts(load(os.path.join(data, 'sweep_swinging100.csv')))
    fabric = load(os.path.join(data, 'sweep_fabric.csv'))
    towel = load(os.path.join(data, 'sweep_towel.csv'))
    chain = load(os.path.join(data, 'sweep_chain.csv'))
    stability = load(os.path.join(data, 'sweep_stability.csv'))
    general = load(os.path.join(data, 'sweep_general.csv'))
    controller = controller_load(data)
    if not (hanging or swinging or swinging100 or fabric or towel or drape or chain or stability
            or general or controller):
        sys.exit('plot_bench: no sweep_*.csv in %s (run scripts/run_bench first)' % data)
    written = []
    if hanging:
        path = os.path.join(data, 'pareto_hanging.png')
        pareto_figure(hanging, [('max_strain', 'max strain over the run', TARGET),
                                ('mean_strain', 'mean strain at the end', TARGET)],
                      'config/hanging.yaml (50 x 50, 1 m, two pinned corners, 3 s at 60 Hz): '
                      'cost against stretch error, pbd_cloth and Bullet on the same links', path)
        written.append(path)
    swing_metrics = [('final_structural_max_strain', 'max strain of the structural links at the end',
                      SWING_MAX_TARGET),
                     ('final_structural_mean_strain',
                      'mean strain of the structural links at the end', SWING_MEAN_TARGET)]
    for rows, name, title in (
            (swinging, 'swinging', 'config/swinging.yaml (issue 12: 50 x 50, both diagonals, no '
             'bending, swings from two pinned corners, 3 s at 60 Hz): pbd_cloth and Bullet on '
             'the same links'),
            (swinging100, 'swinging100', 'config/swinging.yaml at 100 x 100 (issue 12, target '
             '2): pbd_cloth and Bullet on the same links')):
        if rows:
            path = os.path.join(data, 'pareto_%s.png' % name)
            metrics = list(swing_metrics)
            # The steady reading beside the final instant (cloth_bench since commit 6fc225b):
            # a third panel where the run has it.
            steady = 'last_second_median_structural_max_strain'
            if any(not math.isnan(r.get(steady, float('nan'))) for r in rows):
                metrics.append((steady, 'median over the last second of the structural max '
                                'strain', SWING_MAX_TARGET))
            pareto_figure(rows, metrics, title, path)
            written.append(path)
    if general:
        path = os.path.join(data, 'general_pareto.png')
        general_figure(general, path)
        written.append(path)
    if controller:
        path = os.path.join(data, 'controller.png')
        controller_figure(controller, path)
        written.append(path)
    if drape:
        path = os.path.join(data, 'pareto_drape.png')
        pareto_figure(drape, [('max_strain', 'max strain over the run', TARGET),
                              ('mean_strain', 'mean strain at the end', TARGET),
                              ('max_penetration', 'max penetration over the run (m)', None)],
                      'config/drape.yaml (32 x 32 on a ball and a table, 3 s at 60 Hz)', path)
        written.append(path)
    if chain:
        path = os.path.join(data, 'pareto_chain.png')
        chain_figure(chain, path)
        written.append(path)
    if hanging or chain:
        path = os.path.join(data, 'substeps_vs_iterations.png')
        substeps_figure(hanging, chain, path)
        written.append(path)
    verdicts = stability_verdicts(stability) if stability else []
    if verdicts:
        path = os.path.join(data, 'stability_matrix.png')
        stability_figure(verdicts, path)
        written.append(path)
    env_text = ''
    if args.env and os.path.exists(args.env):
        with open(args.env) as handle:
            env_text = handle.read()
    text = summary(data, hanging, drape, chain, verdicts, env_text, swinging, swinging100, fabric,
                   towel, general, controller)
    path = os.path.join(data, 'bench_summary.md')
    with open(path, 'w') as handle:
        handle.write(text)
    written.append(path)
    print(text)
    for path in written:
        print('plot_bench: wrote %s' % os.path.relpath(path, REPO))


if __name__ == '__main__':
    main()
