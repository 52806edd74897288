#!/usr/bin/env python3
"""Writes docs/results.md, and the results table of README.md, from run outputs.

Requires: Python >= 3.8, standard library only; git on PATH (for the commit stamp); the release
binary of evorec (`cargo build --release -p evorec-sim`), and for the timing section the firmware
(`cd hil-stubs && cargo build --release`) and qemu-system-arm.

    scripts/results.py [--work DIR] [--sequences DIR] [--bags DIR] [--trials N] [--reuse]

Runs, into WORK (default target/results):
  evorec paper --out WORK/paper                     the paper's experiment (30 runs)
  evorec track SEQ --out WORK/track/NAME            every sequence directory under SEQUENCES
                                                    (default ../shared/data/sequences), if any
  evorec import BAG --rig NAME.rig.toml --out WORK/bags/NAME, then evorec track of it
    --out WORK/track/NAME-bag                       every ROS 2 bag NAME under BAGS (default
                                                    ../shared/data/bags) with NAME.rig.toml and
                                                    NAME.groundtruth.tum beside it (the ground
                                                    truth copied in; import == track BAG)
  evorec acquire --trials N --out WORK/acquire      acquisition statistics (N = 100)
  evorec timing --out WORK/timing                   M4 instructions per generation
then writes docs/results.md from those outputs, stamped with the commit they ran on, and replaces
the lines between the README's `<!-- results:paper:begin -->` and `<!-- results:paper:end -->`
markers with the paper table's published cells (and the entries worse than the paper's), and
those between `<!-- results:track:begin -->` and `<!-- results:track:end -->` with the recorded
sequences' errors. `--reuse` skips every step whose output exists
(a partial rerun). A step that fails stops the script, naming the step, and nothing is written.
EVOREC=path overrides the binary.
"""
import argparse
import datetime
import json
import os
import shutil
import subprocess
import sys
import textwrap

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BEGIN, END = '<!-- results:paper:begin -->', '<!-- results:paper:end -->'
TRACK_BEGIN, TRACK_END = '<!-- results:track:begin -->', '<!-- results:track:end -->'
COLUMNS = ['F̄', 'RMS x', 'RMS y', 'RMS z', 'RMS ε₁', 'RMS ε₂', 'RMS ε₃']
README_METHODS = {'1-step GA': 'GA', '1-step GA + FF': 'GA+FF'}


def die(msg):
    print(f'results.py: {msg}', file=sys.stderr)
    sys.exit(1)


def run_step(name, args, out, reuse):
    """Runs one evorec command unless --reuse and its output directory exists."""
    if reuse and os.path.isdir(out):
        print(f'== {name}: reusing {out}')
        return
    print(f'== {name}: {" ".join(args)}', flush=True)
    if subprocess.call(args) != 0:
        die(f'step "{name}" failed ({" ".join(args)}); nothing written')


def bags_with_truth(bags_dir):
    """(name, bag, rig file, ground truth) of every bag under `bags_dir` whose rig file and
    ground truth lie beside it as NAME.rig.toml and NAME.groundtruth.tum."""
    if not os.path.isdir(bags_dir):
        return []
    found = []
    for name in sorted(os.listdir(bags_dir)):
        bag = os.path.join(bags_dir, name)
        rig, truth = bag + '.rig.toml', bag + '.groundtruth.tum'
        if os.path.isdir(bag) and os.path.isfile(rig) and os.path.isfile(truth):
            found.append((name, bag, rig, truth))
    return found


def commit_stamp():
    def git(*a):
        return subprocess.run(['git', '-C', ROOT, *a], capture_output=True, text=True).stdout.strip()
    head = git('rev-parse', '--short=8', 'HEAD') or 'unknown'
    dirty = git('status', '--porcelain', '--untracked-files=no')
    return head + (' with uncommitted changes' if dirty else '')


def paper_sections(paper_dir):
    md = open(os.path.join(paper_dir, 'paper_table.md'), encoding='utf-8').read().strip()
    rows = [l for l in md.splitlines() if l.startswith('| ') and not l.startswith('| motion')]
    published = []
    for l in rows:
        cells = [c.strip() for c in l.strip('|').split('|')]
        method = README_METHODS.get(cells[1])
        if method is None or cells[3].endswith('(—)'):
            continue
        cells[1] = method
        published.append('| ' + ' | '.join(c.replace('**', '') for c in cells) + ' |')
    head = ['| motion | method | ω rad/s | F̄ | RMS x mm | RMS y mm | RMS z mm | RMS ε₁ | RMS ε₂ | RMS ε₃ |',
            '|---|---|---|---|---|---|---|---|---|---|']
    return md, '\n'.join(head + published + ['', worse_than_published(published)])


def worse_than_published(rows):
    """One sentence naming the GA+FF entries of `rows` (README table lines, `ours (published)`)
    that are worse than the paper's: lower F̄, higher RMS (as printed, so ties count as equal)."""
    worse = []
    for line in rows:
        cells = [c.strip() for c in line.strip('|').split('|')]
        if cells[1] != 'GA+FF':
            continue
        for name, cell in zip(COLUMNS, cells[3:]):
            ours, _, pub = cell.partition(' (')
            pub = pub.rstrip(')')
            if pub == '—':
                continue
            o, p = float(ours), float(pub)
            if (o < p) if name == 'F̄' else (o > p):
                worse.append(f'{name} in motion {cells[0]} at {cells[2]} rad/s ({ours} against {pub})')
    text = 'With feedforward every entry is at least as good as the published one'
    text += (' except ' + '; '.join(worse) + '.') if worse else '.'
    return textwrap.fill(text, width=100, break_long_words=False, break_on_hyphens=False)


def track_summaries(track_dir):
    """(name, summary.json) of every tracked sequence, by name; None when none was tracked."""
    if not os.path.isdir(track_dir):
        return None
    return [(name, json.load(open(os.path.join(track_dir, name, 'summary.json'), encoding='utf-8')))
            for name in sorted(os.listdir(track_dir))]


def track_table(track_dir, header, rows):
    """A markdown table of the tracked sequences: `header` (its two lines), then the lines
    `rows(name, summary)` gives for each sequence; a sentence when none was tracked."""
    runs = track_summaries(track_dir)
    if runs is None:
        return 'No sequences were tracked (none found).'
    return '\n'.join(header + [line for name, s in runs for line in rows(name, s)])


def track_section(track_dir):
    def rows(name, s):
        for key, label in (('all', 'all'), ('after_within', 'after acquisition')):
            r = s.get(key)
            if r:
                yield (f"| `{name}` | {label} | {r['frames']} | {r['rms_x_mm']:.2f} | {r['rms_y_mm']:.2f} | "
                       f"{r['rms_z_mm']:.2f} | {r['rms_rot_deg']:.2f} | {r['max_rot_deg']:.2f} |")
    return track_table(track_dir, ['| sequence | over | frames | RMS x mm | RMS y mm | RMS z mm | RMS rotation ° | max rotation ° |',
                                   '|---|---|---|---|---|---|---|---|'], rows)


def acquire_section(acq_dir):
    text = open(os.path.join(acq_dir, 'acquire.md'), encoding='utf-8').read().strip()
    # The report's own title is this section's heading.
    return '\n'.join(l for l in text.splitlines() if not l.startswith('# ')).strip()


def timing_section(timing_dir):
    t = json.load(open(os.path.join(timing_dir, 'timing.json'), encoding='utf-8'))
    ipg = t['instructions_per_generation']
    ff_t = t.get('ff_target', {}).get('deadline', {}).get('worst_instructions')
    rows = [('worst generation, `ff` (instructions)', f"{ipg['max']:,.0f}"),
            ('worst generation, `ff+target` (instructions)', f'{ff_t:,.0f}' if ff_t else '—'),
            ('budget (instructions)', f"{ipg['budget']:,.0f}"),
            ('flash (B)', f"{t['flash_bytes']:,}"),
            ('static RAM (B)', f"{t['static_ram_bytes']:,}"),
            ('stack, one generation (B)', f"{t['stack_bytes']:,}")]
    return '\n'.join(['| quantity | value |', '|---|---|'] + [f'| {a} | {b} |' for a, b in rows])


def replace_block(text, begin, end, table, stamp):
    """`text` with the lines between the markers `begin` and `end` replaced by `table`."""
    if begin not in text or end not in text:
        die(f'README.md has no {begin} … {end} block; nothing written')
    pre, rest = text.split(begin, 1)
    _, post = rest.split(end, 1)
    body = f'{begin}\n<!-- generated by scripts/results.py from the runs of commit {stamp}; do not edit -->\n{table}\n{end}'
    return pre + body + post


def track_readme_table(track_dir):
    """The README's compact table of the recorded sequences: over all frames and after
    acquisition."""
    xyz = lambda r: f"{r['rms_x_mm']:.2f} / {r['rms_y_mm']:.2f} / {r['rms_z_mm']:.2f}" if r else '—'
    rot = lambda r: f"{r['rms_rot_deg']:.2f}" if r else '—'

    def rows(name, s):
        a, w = s.get('all'), s.get('after_within')
        yield f'| `{name}` | {xyz(a)} | {rot(a)} | {xyz(w)} | {rot(w)} |'
    return track_table(track_dir, ['| sequence | RMS x / y / z mm, all frames | rotation ° | after acquisition: x / y / z mm | rotation ° |',
                                   '|---|---|---|---|---|'], rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--work', default=os.path.join(ROOT, 'target', 'results'))
    ap.add_argument('--sequences', default=os.path.join(ROOT, '..', 'shared', 'data', 'sequences'))
    ap.add_argument('--bags', default=os.path.join(ROOT, '..', 'shared', 'data', 'bags'))
    ap.add_argument('--trials', type=int, default=100)
    ap.add_argument('--reuse', action='store_true')
    a = ap.parse_args()
    evorec = os.environ.get('EVOREC', os.path.join(ROOT, 'target', 'release', 'evorec'))
    if not os.access(evorec, os.X_OK):
        die(f'no evorec binary at {evorec} (cargo build --release -p evorec-sim)')
    w = a.work
    stamp = commit_stamp()  # before the runs: the tree they ran on
    run_step('paper', [evorec, '-q', 'paper', '--out', f'{w}/paper'], f'{w}/paper', a.reuse)
    if os.path.isdir(a.sequences):
        for name in sorted(os.listdir(a.sequences)):
            seq = os.path.join(a.sequences, name)
            if os.path.isfile(os.path.join(seq, 'sequence.toml')):
                run_step(f'track {name}', [evorec, '-q', 'track', seq, '--out', f'{w}/track/{name}'],
                         f'{w}/track/{name}', a.reuse)
    for name, bag, rig, truth in bags_with_truth(a.bags):
        seq = f'{w}/bags/{name}'
        if not a.reuse and os.path.isdir(seq):
            shutil.rmtree(seq)  # import writes only into a new or empty directory
        run_step(f'import {name}', [evorec, '-q', 'import', bag, '--rig', rig, '--out', seq], seq, a.reuse)
        shutil.copyfile(truth, os.path.join(seq, 'groundtruth.tum'))
        run_step(f'track {name}', [evorec, '-q', 'track', seq, '--out', f'{w}/track/{name}-bag'],
                 f'{w}/track/{name}-bag', a.reuse)
    run_step('acquire', [evorec, '-q', 'acquire', '--trials', str(a.trials), '--out', f'{w}/acquire'],
             f'{w}/acquire', a.reuse)
    run_step('timing', [evorec, '-q', 'timing', '--out', f'{w}/timing'], f'{w}/timing', a.reuse)

    paper_md, readme_table = paper_sections(f'{w}/paper')
    date = datetime.date.today().isoformat()
    doc = f"""# Results

Generated by `scripts/results.py` on {date} from the runs of commit {stamp}; every number below is
read from those runs' output files. Do not edit by hand: rerun the script.

## The paper's experiment

`evorec paper --out DIR` (GA seed 1, 72 s per run; DIR/paper_table.md):

{paper_md}

## Recorded sequences

`evorec track SEQ --out DIR` with default options (DIR/summary.json; "after acquisition" counts
from the first frame within 10 mm and 5° of the truth). `NAME-bag` is a ROS 2 bag, imported
(`evorec import`) with its ground truth copied in:

{track_section(f'{w}/track')}

## Acquisition

`evorec acquire --trials {a.trials} --out DIR` (DIR/acquire.md):

{acquire_section(f'{w}/acquire')}

## Board timing (Cortex-M4, QEMU instruction counts)

`evorec timing --out DIR` (DIR/timing.json; method in [timing.md](timing.md)):

{timing_section(f'{w}/timing')}
"""
    readme_path = os.path.join(ROOT, 'README.md')
    readme = open(readme_path, encoding='utf-8').read()
    readme = replace_block(readme, BEGIN, END, readme_table, stamp)
    readme = replace_block(readme, TRACK_BEGIN, TRACK_END, track_readme_table(f'{w}/track'), stamp)
    out = os.path.join(ROOT, 'docs', 'results.md')
    for path, text in ((out, doc), (readme_path, readme)):
        tmp = path + '.tmp'
        with open(tmp, 'w', encoding='utf-8') as f:
            f.write(text)
        os.replace(tmp, path)
    print(f'wrote {out} and the results tables of {readme_path}')


if __name__ == '__main__':
    main()
