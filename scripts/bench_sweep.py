#!/usr/bin/python3
"""The sweeps behind doc/*.csv: cloth_bench over method x substeps x iterations x ordering on the
four bench scenes, bullet_cloth_bench over its substep and iteration knobs on the same scenes, the
general case (`general`: corners held closer than the width, the T-shirt held at its shoulders;
GENERAL_SCENES, GENERAL_PBD_SERIES) and the stability matrix. Called by scripts/run_bench; one CSV row per run with every key=value field
the tool printed, plus the overrides that made the run.

    /usr/bin/python3 scripts/bench_sweep.py --bin-dir <devel/lib/pbd_cloth> --out doc [--quick]
"""
import argparse
import concurrent.futures
import csv
import os
import shlex
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Time limit of one run (s): 4 times what a healthy run of that many passes per step takes, at least
# 20 s. cloth_bench counts self-intersections at every metric sample, and on a cloth that has blown
# up (finite, but spread over kilometres) one count takes seconds: such a run is stopped and
# recorded as diverged (exit_status=timeout) instead of holding the sweep for minutes.
# Code paths compared by cloth_bench's flags (the scene YAML offers what a user decides).
COMMAND_LINE_SWITCHES = {'solver.simd=false': '--no-simd', 'solver.avx512=false': '--no-avx512'}


def run_timeout(run):
    if run.timeout:
        return run.timeout
    if run.scene in CLOTH_SCENES:
        steps = run.duration * 60.0
        return max(20.0, 4.0 * (1.0 + steps * run.fields.get('passes', 1) * 0.6e-3))
    return 120.0

# Columns first in every CSV, in this order; the tool's own keys follow.
LEAD_COLUMNS = ['sweep', 'scene', 'tool', 'curve', 'method', 'ordering', 'substeps', 'iterations',
                'passes', 'wall_ms_per_step', 'max_strain', 'mean_strain', 'finite', 'energy']


def splits(totals):
    """(substeps, iterations) pairs: every power-of-two split of each total number of passes (every
    divisor for totals that are not powers of two)."""
    pairs = []
    for total in totals:
        if total & (total - 1) == 0:
            substeps = total
            while substeps >= 1:
                pairs.append((substeps, total // substeps))
                substeps //= 2
        else:
            pairs += [(s, total // s) for s in range(total, 0, -1) if total % s == 0]
    return pairs


# Metric samples every 3rd step on the cloth scenes (both tools alike). Counting self-intersections
# at every step of a crumpled 50 x 50 cloth (the cheapest settings) takes up to 20 s a run; every
# 3rd step (50 ms) changes max_strain by under 2 % and keeps the whole sweep under 15 minutes.
CLOTH_SAMPLE_EVERY = 3
CLOTH_SCENES = ('hanging.yaml', 'drape.yaml', 'swinging.yaml', 'fabric_table.yaml',
                'towel_on_table.yaml')


class Run(object):
    """One command line and the fields that describe it in the CSV."""

    def __init__(self, sweep, scene, tool, curve, duration, sets, fields, positions=False):
        self.sweep = sweep
        self.scene = scene
        self.tool = tool
        self.curve = curve
        self.duration = duration
        self.sets = list(sets)
        self.fields = dict(fields)
        self.positions = positions
        self.sample_every = CLOTH_SAMPLE_EVERY if scene in CLOTH_SCENES else 0
        self.timeout = None  # s; None: run_timeout's rule
        # --csv: the per-step file cloth_bench writes (a temporary file), and where its columns
        # CONTROLLER_STEP_COLUMNS are kept (None: the file is not kept).
        self.csv_file = None
        self.steps_out = None

    def command(self, bin_dir, positions_file=None):
        cmd = [os.path.join(bin_dir, self.tool), '--config', os.path.join('config', self.scene),
               '--duration', repr(self.duration), '--quiet']
        for assignment in self.sets:
            # The comparison-only switches are cloth_bench's own flags, not scene keys.
            if assignment in COMMAND_LINE_SWITCHES:
                cmd.append(COMMAND_LINE_SWITCHES[assignment])
            else:
                cmd += ['--set', assignment]
        if self.sample_every and self.sweep != 'stability':
            cmd += ['--sample-every', str(self.sample_every)]
        if positions_file:
            cmd += ['--positions', positions_file]
        if self.csv_file:
            cmd += ['--csv', self.csv_file]
        return cmd


def pbd_run(sweep, scene, curve, method, substeps, iterations, duration, extra=(), **fields):
    sets = ['solver.method=%s' % method, 'solver.substeps=%d' % substeps,
            'solver.iterations=%d' % iterations] + list(extra)
    row = {'method': method, 'substeps': substeps, 'iterations': iterations,
           'passes': substeps * iterations, 'ordering': 'gauss_seidel'}
    row.update(fields)
    return Run(sweep, scene, 'cloth_bench', curve, duration, sets, row)


def bullet_run(sweep, scene, curve, substeps, iterations, duration, extra=(), **fields):
    sets = ['bullet.substeps=%d' % substeps, 'bullet.piterations=%d' % iterations] + list(extra)
    row = {'method': 'bullet', 'substeps': substeps, 'iterations': iterations,
           'passes': substeps * iterations, 'ordering': 'gauss_seidel'}
    row.update(fields)
    return Run(sweep, scene, 'bullet_cloth_bench', curve, duration, sets, row)


def substeps_only(counts):
    return [(s, 1) for s in counts]


def hanging_runs(quick):
    """config/hanging.yaml, 3 s: the Pareto chart and the Bullet comparison.

    Substeps with one pass each are the cheap way down in error (Small Steps), so every curve runs
    them from 1 up to the count that reaches or nears 1 % max strain; xpbd and Bullet also run every
    power-of-two split of 4, 16 and 64 passes (the substeps-against-iterations chart), the other
    curves a few iteration-heavy points to show where they lie.
    """
    duration = 1.0 if quick else 3.0
    scene = 'hanging.yaml'
    sweep = 'hanging'
    if quick:
        plan = {
            'xpbd': splits([1, 4, 16]), 'pbd': substeps_only([1, 4]),
            'verlet': substeps_only([1, 4]), 'xpbd, no bending': substeps_only([1, 4]),
            'xpbd + tethers': substeps_only([1, 4]), 'xpbd jacobi': substeps_only([1, 4]),
            'bullet': splits([1, 4, 16]), 'bullet + bending links': substeps_only([1, 4]),
        }
        spring_grid = [(1e3, [40, 80])]
    else:
        equal_cost = sorted(set(splits([1, 4, 16, 64]) + substeps_only([2, 8, 32])))
        plan = {
            'xpbd': equal_cost + substeps_only([128, 256]),
            'pbd': substeps_only([1, 2, 4, 8, 16, 32, 64, 128, 256]) + [(1, 4), (4, 4), (1, 16)],
            'verlet': substeps_only([1, 2, 4, 8, 16, 32, 64, 128, 256]) + [(4, 4)],
            # The constraint set of the Bullet cloth (structural + shear links, no bending hinges).
            'xpbd, no bending': substeps_only([1, 2, 4, 8, 16, 32, 64, 128, 256]) + [(4, 4),
                                                                                   (16, 4)],
            # Long-range attachments to the pins (Kim et al. 2012).
            'xpbd + tethers': substeps_only([1, 2, 4, 8]) + [(1, 4)],
            'xpbd jacobi': substeps_only([1, 4, 16, 64]) + [(1, 16), (4, 4), (16, 4)],
            'bullet': equal_cost + substeps_only([128, 256]),
            'bullet + bending links': substeps_only([1, 2, 4, 8, 16, 32, 64]) + [(4, 4), (16, 4)],
        }
        # Explicit springs: stable only above a substep count set by k (and by the bending
        # springs, kept at 0.01 here: the scene's 1/bend_compliance = 1 would need more than the
        # 1000 substeps the solver allows). The first count of each k is below the limit on
        # purpose: the chart marks it as diverged.
        spring_grid = [(1e3, [40, 80, 160]), (1e4, [80, 160, 320]), (1e5, [320, 640])]
    extra = {
        'xpbd, no bending': (['cloth.bend_compliance=-1.0'], {'variant': 'no_bending'}),
        'xpbd + tethers': (['cloth.tethers=true'], {'variant': 'tethers'}),
        'xpbd jacobi': (['solver.ordering=jacobi'], {'ordering': 'jacobi'}),
        'bullet + bending links': (['bullet.bending=1'], {'variant': 'bending_links'}),
    }
    # hanging.yaml has tethers on since 2026-11-27 (the default scene: doc/scenes.md "The default
    # scene"); every other curve measures the cloth without them, as the sweeps before did.
    no_tethers = ['cloth.tethers=false']
    runs = []
    for curve, pairs in plan.items():
        sets, fields = extra.get(curve, ([], {}))
        if curve != 'xpbd + tethers':
            sets = no_tethers + sets
        for s, i in pairs:
            if curve.startswith('bullet'):
                run = bullet_run(sweep, scene, curve, s, i, duration, sets)
            else:
                method = curve.split()[0].rstrip(',')
                run = pbd_run(sweep, scene, curve, method, s, i, duration, sets)
            run.fields.update(fields)
            runs.append(run)
    for k, counts in spring_grid:
        for s in counts:
            runs.append(pbd_run(sweep, scene, 'mass_spring', 'mass_spring', s, 1, duration,
                                no_tethers + ['solver.spring_stiffness=%g' % k,
                                              'solver.bend_spring_stiffness=0.01'],
                                spring_stiffness=k))
    return runs


# Curves of the swinging sweep beyond plain xpbd: (--set assignments, CSV fields). Solver options
# of issue 12 join here, so every method tried lands on the same Pareto chart.
SWINGING_VARIANTS = {
    # Long-range links in a hierarchy (solver.levels, coarse_levels.h): 5 levels are all a 50 x 50
    # grid has (lines 25, 13, 7, 4, 2).
    'xpbd + levels': (['solver.levels=5'], {'variant': 'levels'},
                      substeps_only([10, 20, 30, 36, 40, 50, 60, 80, 120])),
    # Fewer levels, less work a substep. (The top row between the pins is exactly taut here: the
    # degenerate case. solver.taut_chains, which held it straight, left the product on 2026-12-07,
    # doc/journal.md; the general case is the `general` sweep.)
    'xpbd + 2 levels': (['solver.levels=2'], {'variant': 'levels_2'},
                        substeps_only([34, 40, 60, 80, 120])),
    # The same levels without the AVX2 path (cloth_bench --no-simd, the portable loop every x86-64 and
    # other processors run): what SIMD buys, with bit-identical results.
    'xpbd + levels, portable loop': (['solver.levels=5', 'solver.simd=false'],
                                     {'variant': 'levels_portable'}, substeps_only([40, 60, 80])),
    # AVX2 at most (cloth_bench --no-avx512) on a processor with AVX-512: four links a register
    # instead of eight, what the wider registers buy (the same results, bit for bit).
    'xpbd + levels, AVX2 only': (['solver.levels=5', 'solver.avx512=false'],
                                 {'variant': 'levels_avx2'}, substeps_only([40, 60, 80])),
    # Two threads (solver.threads=2): row blocks of the stretch links side by side, prediction and
    # velocity update in halves; bit-identical to one thread.
    'xpbd + levels, 2 threads': (['solver.levels=5', 'solver.threads=2'],
                                 {'variant': 'levels_2_threads'}, substeps_only([40, 60, 80])),
    # One diagonal per cell (cloth.shear_diagonals=1, the grid's default link set): the peers'
    # figures on these links given since issue 12 (Bender's PBD 160 x 1, Bullet 16 x 10; doc/journal.md "Speed (issue 12)"
    # and doc/journal.md, "On equal links") compare with these, the two-diagonal ones above
    # with the issue's own.
    'xpbd + levels, one diagonal': (['solver.levels=5', 'cloth.shear_diagonals=1'],
                                    {'variant': 'levels_one_diagonal'},
                                    substeps_only([32, 36, 40, 50, 60, 80])),
    'xpbd, one diagonal': (['cloth.shear_diagonals=1'], {'variant': 'one_diagonal'},
                           substeps_only([80, 160, 320])),
    'bullet, one diagonal': (['cloth.shear_diagonals=1'], {'variant': 'bullet_one_diagonal'},
                             substeps_only([32, 128]) + [(16, 10)]),
}


def swinging_runs(quick):
    """config/swinging.yaml, 3 s (issue 12's benchmark): a flat cloth with both diagonals per cell
    swinging down from two pinned corners; the error is the final strain of the structural links.

    xpbd runs substeps with one pass each from 5 up to 320 and a few iteration-heavy points; Bullet
    runs its internal steps with one position pass and, as the figures of issue 12, 10 passes.
    """
    duration = 1.0 if quick else 3.0
    scene = 'swinging.yaml'
    sweep = 'swinging'
    if quick:
        plan = {'xpbd': substeps_only([5, 20]), 'bullet': substeps_only([5, 20]) + [(4, 10)],
                'xpbd + levels': substeps_only([5, 20])}
    else:
        plan = {
            'xpbd': substeps_only([5, 10, 20, 40, 60, 80, 120, 160, 320]) + [
                (10, 2), (20, 2), (10, 4), (40, 2), (20, 4)],
            'bullet': substeps_only([4, 8, 16, 32, 64, 128, 256]) + [(4, 10), (8, 10), (16, 10),
                                                                     (16, 4), (32, 4)],
        }
        for curve, (sets, fields, pairs) in SWINGING_VARIANTS.items():
            plan[curve] = pairs
    # Energy at t = 0 (no step): a run whose cloth never fell ends there. Bullet in single precision
    # at 256 internal steps does: h^2 g = 4e-8 m is below the float resolution at z = 1.5 m.
    runs = [pbd_run(sweep, scene, 'start', 'xpbd', 1, 1, 0.0, level='start')]
    for curve, pairs in plan.items():
        sets, fields, _ = SWINGING_VARIANTS.get(curve, ([], {}, None))
        for s, i in pairs:
            if curve.startswith('bullet'):
                run = bullet_run(sweep, scene, curve, s, i, duration, sets)
            else:
                run = pbd_run(sweep, scene, curve, 'xpbd', s, i, duration, sets)
            run.fields.update(fields)
            runs.append(run)
    return runs


def swinging100_runs(quick):
    """config/swinging.yaml at 100 x 100 (issue 12, target 2): the same 1 m cloth, 4x the
    particles; levels=6 are all a 100 x 100 grid has."""
    n = 20 if quick else 100
    duration = 1.0 if quick else 3.0
    grid = ['cloth.rows=%d' % n, 'cloth.cols=%d' % n, 'cloth.spacing=%r' % (1.0 / (n - 1)),
            'cloth.pinned=[0, %d]' % (n - 1)]
    levels = ['solver.levels=6']
    if quick:
        plan = [('xpbd + levels', levels, substeps_only([10])),
                ('bullet', [], substeps_only([5]))]
    else:
        # Neighbouring counts side by side: the strain at the last instant swings between them
        # (doc/journal.md, "Target 2, no longer on its edge"), and the chart shows it.
        plan = [('xpbd + levels', levels, substeps_only([40, 60, 80, 88, 96, 104, 112, 120, 124,
                                                          128, 140, 160])),
                ('xpbd + 4 levels', ['solver.levels=4'], substeps_only([80, 88, 96])),
                ('xpbd + levels, AVX2 only', levels + ['solver.avx512=false'],
                 substeps_only([96, 128])),
                ('xpbd + levels, 2 threads', levels + ['solver.threads=2'],
                 substeps_only([60, 80, 96, 120])),
                ('xpbd', [], substeps_only([80, 96, 104, 112, 120, 160, 320])),
                ('bullet', [], substeps_only([64, 128, 256]) + [(16, 10)])]
    runs = [pbd_run('swinging100', 'swinging.yaml', 'start', 'xpbd', 1, 1, 0.0, grid,
                    level='start')]
    for curve, sets, pairs in plan:
        for s, i in pairs:
            if curve == 'bullet':
                runs.append(bullet_run('swinging100', 'swinging.yaml', curve, s, i, duration, grid))
            else:
                runs.append(pbd_run('swinging100', 'swinging.yaml', curve, 'xpbd', s, i, duration,
                                    grid + sets))
    return runs


# The general case (issue 50): scenes where no row is exactly taut. Each is a panel of
# doc/general_pareto.png: (label, scene file under config/, what it is).
GENERAL_SCENES = [
    ('held_corners', 'held_corners.yaml', '50 x 50, one diagonal, corners 0.5 % closer'),
    ('held_50_2pct', 'bench/held_50_2pct.yaml', '50 x 50, one diagonal, corners 2 % closer'),
    ('held_50_both_05pct', 'bench/held_50_both_05pct.yaml',
     '50 x 50, both diagonals, corners 0.5 % closer'),
    ('held_50_both_2pct', 'bench/held_50_both_2pct.yaml',
     '50 x 50, both diagonals, corners 2 % closer'),
    ('held_100_05pct', 'bench/held_100_05pct.yaml', '100 x 100, one diagonal, corners 0.5 % closer'),
    ('held_100_2pct', 'bench/held_100_2pct.yaml', '100 x 100, one diagonal, corners 2 % closer'),
    ('tshirt_held', 'tshirt_held.yaml', 'T-shirt held at both shoulders (self-collision on)'),
]
# pbd_cloth's series on every general scene: curve name -> the --set overrides that make it (the
# substep count is added per run). Extend with a method's keys, e.g.
#   'xpbd + 2 Newton steps': ['solver.newton_steps=2'],
# and it runs at every count of GENERAL_SUBSTEPS on every scene, charted as a curve of its own.
# Fixed substeps: a scene's own target (config/held_corners.yaml recommends one) is turned off.
GENERAL_PBD_SERIES = {
    'xpbd': ['solver.target_max_strain=0'],
}
GENERAL_SUBSTEPS = [40, 80, 120, 180, 240]  # x 1 iteration
# Bullet on the same scene, the same links (each scene's own link set: one diagonal or both),
# its held particles moved as pins (bullet_cloth_bench): internal steps x position passes.
GENERAL_BULLET = [(16, 10), (64, 10)]


def general_runs(quick):
    """The general-case scenes (GENERAL_SCENES), 3 s: pbd_cloth's series (GENERAL_PBD_SERIES) at
    GENERAL_SUBSTEPS x 1 and Bullet at GENERAL_BULLET, recording the final and last-second-median
    structural strains (cloth_bench and bullet_cloth_bench print both)."""
    duration = 0.5 if quick else 3.0
    substeps = [10, 20] if quick else GENERAL_SUBSTEPS
    bullet = [(4, 2)] if quick else GENERAL_BULLET
    runs = []
    for label, scene, _ in GENERAL_SCENES:
        for curve, sets in GENERAL_PBD_SERIES.items():
            for s in substeps:
                run = pbd_run('general', scene, curve, 'xpbd', s, 1, duration, sets, label=label)
                runs.append(run)
        for s, i in bullet:
            runs.append(bullet_run('general', scene, 'bullet', s, i, duration, label=label))
    for run in runs:
        # The medians read every step whatever the sampling; the samples (max over the run, the
        # self-intersection count) every 3rd step, as on the other cloth scenes.
        run.sample_every = CLOTH_SAMPLE_EVERY
        # Bullet 64 x 10 at 100 x 100 and the shirt at 240 substeps take a minute or more.
        run.timeout = 900.0
    return runs


# Accuracy on demand (issue 51): the controller (solver.target_max_strain) against fixed substeps
# on a scripted manipulation with calm and violent phases, on the held corners, and on a cloth at
# rest. (label, scene under config/, duration s, fixed substep counts x 1, extra --set, what it is).
CONTROLLER_TARGET = 0.01
CONTROLLER_MAX_SUBSTEPS = 1000
CONTROLLER_SCENES = [
    ('manipulation', 'bench/manipulation.yaml', 10.0,
     [20, 40, 60, 80, 120, 160, 200, 240, 320, 400, 480, 560, 640, 800], [],
     'grasp, lift, shake, lay on the table, fold, let go, lie still (calm from 4.7 s of 10 s)'),
    ('held_corners', 'held_corners.yaml', 3.0,
     [20, 40, 60, 80, 120, 160, 200, 240, 320, 400, 480], [],
     '50 x 50 held by two corners 0.5 % closer than its width'),
    # The default cloth hanging from its pins, without its tethers (with them one substep meets
    # 1 %): meant as the calm case, but not at rest: it starts unstretched and stretches under
    # gravity (its strain climbs over the first second at fixed substeps). A scene truly at rest
    # is still to be made (a saved settled state, --load-state).
    ('calm', 'hanging.yaml', 3.0, [16, 24, 32, 48, 64, 80, 96, 128, 160, 200],
     ['cloth.tethers=false'],
     'config/hanging.yaml without tethers: hanging from its pins, settling'),
]
# The columns of cloth_bench --csv kept per step under <out>/controller/ (the charts' data).
CONTROLLER_STEP_COLUMNS = ['t', 'substeps_run', 'structural_max_strain', 'target_met']


def controller_runs(quick, out_dir):
    """Every scene of CONTROLLER_SCENES with the controller (target 1 % structural strain, at most
    CONTROLLER_MAX_SUBSTEPS substeps) and at each fixed substep count, every step sampled (--csv
    kept in <out>/controller/<label>_<curve>.csv)."""
    runs = []
    step_dir = os.path.join(out_dir, 'controller')
    os.makedirs(step_dir, exist_ok=True)
    for label, scene, duration, counts, extra, _ in CONTROLLER_SCENES:
        if quick:
            duration, counts = min(duration, 1.0), counts[:2]
        target = ['solver.target_max_strain=%g' % CONTROLLER_TARGET,
                  'solver.max_substeps=%d' % CONTROLLER_MAX_SUBSTEPS]
        plan = [('controller', None, extra + target)] + [
            ('fixed %d' % s, s, extra + ['solver.substeps=%d' % s, 'solver.target_max_strain=0'])
            for s in counts]
        for curve, substeps, sets in plan:
            run = Run('controller', scene, 'cloth_bench', curve, duration, sets,
                      {'method': 'xpbd', 'iterations': 1, 'ordering': 'gauss_seidel',
                       'label': label, 'target_max_strain': CONTROLLER_TARGET,
                       'controller': 1 if substeps is None else 0})
            if substeps is not None:
                run.fields.update(substeps=substeps, passes=substeps)
            run.sample_every = 1
            run.timeout = 900.0
            name = '%s_%s.csv' % (label, 'controller' if substeps is None else
                                  'fixed_%03d' % substeps)
            run.steps_out = os.path.join(step_dir, name)
            runs.append(run)
    return runs


def keep_step_columns(source, destination):
    """The CONTROLLER_STEP_COLUMNS of a cloth_bench --csv file, strains to 4 significant digits;
    returns the fraction of the steps (rows after t = 0) at or under CONTROLLER_TARGET."""
    with open(source, newline='') as handle:
        rows = list(csv.DictReader(handle))
    with open(destination, 'w', newline='') as handle:
        writer = csv.writer(handle)
        writer.writerow(CONTROLLER_STEP_COLUMNS)
        for row in rows:
            writer.writerow(['%.6g' % float(row['t']), row['substeps_run'],
                             '%.4g' % float(row['structural_max_strain']), row['target_met']])
    steps = rows[1:]
    under = [r for r in steps if float(r['structural_max_strain']) <= CONTROLLER_TARGET]
    return len(under) / float(len(steps)) if steps else float('nan'), \
        sum(int(r['substeps_run']) for r in steps)


def fabric_runs(quick):
    """config/fabric_table.yaml, 2 s (issue 12, target 3): fabric_simulator's settings, dt 3 ms
    and 12 substeps, with and without self-collision, one and two threads."""
    duration = 0.5 if quick else 2.0
    runs = []
    for self_collision in ('false', 'true'):
        for threads in (1, 2):
            curve = 'xpbd' + (' + self-collision' if self_collision == 'true' else '') + \
                (', 2 threads' if threads == 2 else '')
            runs.append(pbd_run('fabric', 'fabric_table.yaml', curve, 'xpbd', 12, 1, duration,
                                ['cloth.self_collision=%s' % self_collision,
                                 'solver.threads=%d' % threads]))
    # The same without the AVX2 paths (links and flat hinges): what SIMD buys on this scene.
    runs.append(pbd_run('fabric', 'fabric_table.yaml', 'xpbd, portable loop', 'xpbd', 12, 1,
                        duration, ['cloth.self_collision=false', 'solver.simd=false']))
    return runs


def towel_runs(quick):
    """config/towel_on_table.yaml, 6 s (issue 12, target 6): a towel drops 2 cm onto a table and
    lies still; with sleeping on, the steps it sleeps through are timed apart from the others."""
    duration = 2.0 if quick else 6.0
    return [pbd_run('towel', 'towel_on_table.yaml', 'xpbd, sleeping', 'xpbd', 10, 1, duration),
            pbd_run('towel', 'towel_on_table.yaml', 'xpbd, never sleeps', 'xpbd', 10, 1, duration,
                    ['solver.sleep_speed=0'])]


def drape_runs(quick):
    """config/drape.yaml, 3 s: contact and self-collision."""
    duration = 1.0 if quick else 3.0
    pairs = [(1, 1), (4, 1), (2, 2), (1, 4), (16, 1), (4, 4), (1, 16), (64, 1), (8, 8), (1, 64)]
    if quick:
        pairs = pairs[:4]
    runs = []
    for method in ('xpbd', 'pbd', 'verlet'):
        for s, i in pairs:
            runs.append(pbd_run('drape', 'drape.yaml', method, method, s, i, duration))
    for s, i in pairs:
        runs.append(bullet_run('drape', 'drape.yaml', 'bullet', s, i, duration))
    return runs


def chain_runs(quick):
    """config/chain_heavy.yaml, 10 s, end mass 1:1e3 and 1:1e5 (Small Steps figs. 3-4; the paper's
    figure compares 100 iterations with 100 substeps). 512 passes is the largest power of two the
    solver accepts (substeps and iterations are each at most 1000)."""
    duration = 3.0 if quick else 10.0
    totals = [4, 16, 64, 100, 256, 512] if not quick else [4, 16]
    runs = []
    for ratio in (1e3, 1e5):
        mass = 'cloth.point_masses=[[19, %r]]' % ratio
        for method in ('xpbd', 'pbd'):
            for s, i in splits(totals):
                run = pbd_run('chain', 'chain_heavy.yaml', method, method, s, i, duration, [mass],
                              mass_ratio=ratio)
                run.positions = True
                runs.append(run)
        for s, i in splits([t for t in totals if t <= 256]):
            run = bullet_run('chain', 'chain_heavy.yaml', 'bullet', s, i, duration, [mass],
                             mass_ratio=ratio)
            run.positions = True
            runs.append(run)
    return runs


def stability_runs(quick):
    """The heat map: method x stiffness x dt x mass ratio x iterations on the heavy chain (2 s),
    and ordering x dt x iterations on a 10 x 10 hanging cloth."""
    duration = 2.0
    stiffness = {
        'verlet': [('rigid', [])],
        'pbd': [('k=%g' % k, ['solver.stretch_stiffness=%g' % k]) for k in (1.0, 0.1, 0.01)],
        'xpbd': [('alpha=%g' % a, ['cloth.stretch_compliance=%g' % a]) for a in (0.0, 1e-6, 1e-4)],
        'mass_spring': [('k=%g' % k, ['solver.spring_stiffness=%g' % k])
                        for k in (1e4, 1e5, 1e6)],
        'bullet': [('kLST=1', [])],
    }
    substeps = [1, 4, 16, 64] if not quick else [1, 16]
    ratios = [1.0, 1e3, 1e5] if not quick else [1.0, 1e5]
    iterations = [1, 10]
    runs = []
    for ratio in ratios:
        mass = 'cloth.point_masses=[[19, %r]]' % ratio
        # Energy at t = 0 (no step): the reference of "energy bounded".
        start = pbd_run('stability', 'chain_heavy.yaml', 'start', 'xpbd', 1, 1, 0.0, [mass],
                        mass_ratio=ratio, level='start')
        runs.append(start)
        for method, levels in sorted(stiffness.items()):
            for level, sets in levels:
                for s in substeps:
                    for i in iterations:
                        if method == 'bullet':
                            run = bullet_run('stability', 'chain_heavy.yaml', method, s, i,
                                             duration, [mass] + sets)
                        else:
                            run = pbd_run('stability', 'chain_heavy.yaml', method, method, s, i,
                                          duration, [mass] + sets)
                        run.fields.update(mass_ratio=ratio, level=level, panel='chain')
                        runs.append(run)
    # Jacobi needs averaging (case 7): interior cloth particles have K >= 3 constraints.
    small = ['cloth.rows=10', 'cloth.cols=10', 'cloth.spacing=0.1111111111111111',
             'cloth.pinned=[0, 9]', 'cloth.tethers=false']
    start = pbd_run('stability', 'hanging.yaml', 'start', 'xpbd', 1, 1, 0.0, small,
                    level='start', panel='ordering')
    runs.append(start)
    orderings = [('gauss_seidel', ['solver.ordering=gauss_seidel']),
                 ('jacobi, averaged', ['solver.ordering=jacobi']),
                 ('jacobi, plain', ['solver.ordering=jacobi', 'solver.jacobi_averaging=false'])]
    for level, sets in orderings:
        for s in substeps:
            for i in iterations:
                run = pbd_run('stability', 'hanging.yaml', 'xpbd ' + level, 'xpbd', s, i,
                              duration, small + sets, level=level, panel='ordering')
                run.fields['ordering'] = sets[0].split('=')[1]
                runs.append(run)
    return runs


def parse_metrics(stdout):
    for line in reversed(stdout.strip().splitlines()):
        if 'wall_ms_per_step=' in line:
            fields = {}
            for token in line.split():
                key, _, value = token.partition('=')
                fields[key] = value
            return fields
    return {}


def tool_environment():
    """The environment of the runs: the repository on ROS_PACKAGE_PATH, so that the scenes'
    package://pbd_cloth/... files (the T-shirt's mesh) resolve without a sourced workspace (rospack
    stops at the repository's own package.xml)."""
    env = dict(os.environ)
    paths = [p for p in env.get('ROS_PACKAGE_PATH', '').split(':') if p]
    if REPO not in paths:
        env['ROS_PACKAGE_PATH'] = ':'.join([REPO] + paths)
    return env


def execute(run, bin_dir):
    """Runs one command from the repository root; returns the CSV row."""
    positions_file = None
    if run.steps_out:
        handle, run.csv_file = tempfile.mkstemp(prefix='pbd_bench_steps_', suffix='.csv')
        os.close(handle)
    if run.positions:
        handle, positions_file = tempfile.mkstemp(prefix='pbd_bench_', suffix='.csv')
        os.close(handle)
    cmd = run.command(bin_dir, positions_file)
    row = {'sweep': run.sweep, 'scene': run.scene, 'tool': run.tool, 'curve': run.curve,
           'duration': run.duration, 'sets': ' '.join(run.sets)}
    row.update(run.fields)
    begin = time.time()
    try:
        done = subprocess.run(cmd, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              universal_newlines=True, timeout=run_timeout(run),
                              env=tool_environment())
        metrics = parse_metrics(done.stdout)
        row['exit_status'] = done.returncode
        if done.returncode != 0 or not metrics:
            row['error'] = (done.stderr.strip().splitlines() or ['no output'])[-1]
        for key, value in metrics.items():
            # The run's own settings win over ours where both exist (e.g. method, substeps).
            row[key] = value
        if positions_file and metrics:
            row.update(chain_end(positions_file))
        if run.steps_out and metrics:
            under, total = keep_step_columns(run.csv_file, run.steps_out)
            row['steps_csv'] = os.path.relpath(run.steps_out, os.path.dirname(
                os.path.dirname(run.steps_out)))
            row['steps_under_target_fraction'] = '%.6g' % under
            row['total_substeps'] = total
            row['total_wall_s'] = '%.6g' % (float(metrics['wall_ms_per_step']) *
                                            float(metrics['steps']) / 1e3)
    except subprocess.TimeoutExpired:
        row['exit_status'] = 'timeout'
        row['finite'] = ''
        row['error'] = 'stopped after %.0f s: diverged (metrics of a blown-up cloth)' % (
            run_timeout(run))
    finally:
        if positions_file and os.path.exists(positions_file):
            os.remove(positions_file)
        if run.csv_file and os.path.exists(run.csv_file):
            os.remove(run.csv_file)
    row['run_seconds'] = '%.3f' % (time.time() - begin)
    # As typed from the repository root with the tools on PATH (rosrun pbd_cloth <tool> ...).
    shown = [os.path.basename(cmd[0])] + [a for a in cmd[1:]
                                          if a not in (positions_file, run.csv_file)]
    if positions_file or run.csv_file:
        shown.append('<file>')
    row['command'] = ' '.join(shlex.quote(a) for a in shown)
    return row


def chain_end(positions_file):
    """The case-5 metric: drop of the last particle below its rest position (1 - 19 * 0.01)."""
    last = None
    with open(positions_file) as handle:
        for line in handle:
            parts = line.strip().split(',')
            if len(parts) == 4:
                last = parts
    if last is None:
        return {}
    rest_z = 1.0 - 0.01 * int(last[0])
    return {'end_index': last[0], 'end_z': last[3], 'end_drop': '%.9g' % (rest_z - float(last[3]))}


def write_csv(path, rows):
    keys = []
    for row in rows:
        for key in row:
            if key not in keys:
                keys.append(key)
    ordered = [k for k in LEAD_COLUMNS if k in keys] + [k for k in keys if k not in LEAD_COLUMNS]
    with open(path, 'w', newline='') as handle:
        writer = csv.DictWriter(handle, fieldnames=ordered, extrasaction='ignore')
        writer.writeheader()
        for row in rows:
            writer.writerow(row)


def describe(row):
    text = '%-22s s=%-4s i=%-3s' % (row['curve'], row.get('substeps'), row.get('iterations'))
    if row.get('exit_status') not in (0, '0'):
        return text + '  FAILED (%s) %s' % (row.get('exit_status'), row.get('error', ''))
    return text + '  %9s ms/step  max_strain %-12s finite %s' % (
        row.get('wall_ms_per_step'), row.get('max_strain'), row.get('finite'))


def load_average():
    with open('/proc/loadavg') as handle:
        return handle.read().split()[0]


def median_row(rounds):
    """The row of the round with the median wall time (the runs are deterministic: only the time
    differs between rounds), with every round's time and the load average at its start."""
    timed = [r for r in rounds if number_or_none(r.get('wall_ms_per_step')) is not None]
    if not timed:
        return rounds[0]
    timed.sort(key=lambda r: float(r['wall_ms_per_step']))
    row = dict(timed[(len(timed) - 1) // 2])
    row['wall_ms_rounds'] = ';'.join(r['wall_ms_per_step'] for r in rounds
                                     if 'wall_ms_per_step' in r)
    row['load_rounds'] = ';'.join(r['load'] for r in rounds)
    row['rounds'] = len(rounds)
    return row


def number_or_none(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def sweep(name, runs, bin_dir, out_dir, workers, repeat=1):
    """Runs every command `repeat` times, in rounds (all runs once, then all again: load that
    drifts over minutes hits every setting alike), and keeps the median time of each."""
    path = os.path.join(out_dir, 'sweep_%s.csv' % name)
    print('== %s: %d runs%s -> %s%s' % (name, len(runs), ' x %d rounds' % repeat if repeat > 1
                                        else '', os.path.relpath(path, REPO),
                                        ' (%d in parallel)' % workers if workers > 1 else ''),
          flush=True)
    begin = time.time()
    started = time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime(begin))
    rounds = [[] for _ in runs]

    def timed_execute(run):
        load = load_average()
        row = execute(run, bin_dir)
        row['load'] = load
        return row
    for round_index in range(repeat):
        with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
            futures = {pool.submit(timed_execute, run): k for k, run in enumerate(runs)}
            for count, future in enumerate(concurrent.futures.as_completed(futures), 1):
                k = futures[future]
                rounds[k].append(future.result())
                print('[%s %d/%d %3d/%d %5.0f s] %s' % (
                    name, round_index + 1, repeat, count, len(runs), time.time() - begin,
                    describe(rounds[k][-1])), flush=True)
    rows = [median_row(r) if repeat > 1 else r[0] for r in rounds]
    for row in rows:
        row['sweep_date'] = started
    write_csv(path, rows)
    print('== %s: %.0f s' % (name, time.time() - begin), flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--bin-dir', required=True, help='directory of cloth_bench and '
                        'bullet_cloth_bench (<workspace>/devel/lib/pbd_cloth)')
    parser.add_argument('--out', default=os.path.join(REPO, 'doc'), help='CSV directory')
    parser.add_argument('--quick', action='store_true', help='small grids (a pipeline check)')
    parser.add_argument('--repeat', type=int, default=None,
                        help='rounds of the timed sweeps (median time kept); default 3 for '
                        'swinging, 1 for the others')
    parser.add_argument('--only', nargs='*', default=None,
                        help='sweeps to run: hanging swinging swinging100 fabric towel drape '
                        'chain general controller stability '
                        '(default: all)')
    args = parser.parse_args()
    bin_dir = os.path.abspath(args.bin_dir)
    for tool in ('cloth_bench', 'bullet_cloth_bench'):
        if not os.access(os.path.join(bin_dir, tool), os.X_OK):
            sys.exit('bench_sweep: %s not found in %s' % (tool, bin_dir))
    os.makedirs(args.out, exist_ok=True)
    # The swinging sweep is issue 12's benchmark: its times are the medians of 3 rounds.
    plan = [('hanging', hanging_runs, 1, 1), ('swinging', swinging_runs, 1, 3),
            ('swinging100', swinging100_runs, 1, 1), ('fabric', fabric_runs, 1, 3),
            ('towel', towel_runs, 1, 1),
            ('drape', drape_runs, 1, 1), ('chain', chain_runs, 1, 1),
            ('general', general_runs, 1, 1),
            ('controller', lambda quick: controller_runs(quick, args.out), 1, 1),
            # Only stability and error are read from this one, not time: both cores.
            ('stability', stability_runs, 2, 1)]
    for name, make, workers, repeat in plan:
        if args.only is None or name in args.only:
            rounds = 1 if args.quick or name == 'stability' else (args.repeat or repeat)
            sweep(name, make(args.quick), bin_dir, args.out, workers, rounds)


if __name__ == '__main__':
    main()
