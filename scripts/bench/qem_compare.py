#!/usr/bin/env python3
"""The quadric simplifier against meshoptimizer 1.3 at equal triangle counts (docs/simplify.md).

    npm ci --prefix scripts/bench/peers/npm             # once (install-deps.sh does it)
    scripts/bench/qem_compare.py BUILD_DIR WORK_DIR [MESH,MESH..] [FRACTION,FRACTION..]

Each shared scan is first rewritten by qem_tool unchanged (binary PLY: the input both
simplifiers and `scanlod compare` read); then qem_tool simplifies it to each fraction of its
triangles, and meshoptimizer's simplifyWithUpdate and simplify are asked for the count qem_tool
reached. Each result is measured against the input with `scanlod compare --samples 200000`
(symmetric, fractions of the diagonal). Prints one line per pair and the median ratios.
"""
import json, os, statistics, subprocess, sys

HERE = os.path.dirname(os.path.abspath(__file__))
MESHES = ['armadillo_86kf', 'bun_zipper', 'dragon_100kf', 'fandisk', 'igea', 'lucy_100kf',
          'nefertiti', 'rocker_arm', 'usnm_1145291']
FRACTIONS = [0.01, 0.02, 0.05, 0.1, 0.2, 0.5]


def compare(build, a, b):
    r = subprocess.run([f'{build}/cli/scanlod', 'compare', a, b, '--samples', '200000', '--json'],
                       capture_output=True, text=True, check=True)
    j = json.loads(r.stdout)
    return j['rms'], j['hausdorff'], j['b_triangles']


def main():
    build, work = sys.argv[1], sys.argv[2]
    meshes = sys.argv[3].split(',') if len(sys.argv) > 3 else MESHES
    fractions = [float(f) for f in sys.argv[4].split(',')] if len(sys.argv) > 4 else FRACTIONS
    data = os.environ.get('SCANLOD_SHARED_DATA', os.path.join(HERE, '../../../shared/data'))
    tool, driver = f'{build}/scripts/bench/qem_tool', os.path.join(HERE, 'peers/meshopt_js.mjs')
    os.makedirs(work, exist_ok=True)
    rows = []
    for mesh in meshes:
        source = f'{work}/{mesh}_in.ply'
        subprocess.run([tool, f'{data}/{mesh}.ply', source, '4000000000'], check=True, capture_output=True)
        for fraction in fractions:
            ours = f'{work}/{mesh}_{fraction}_qem.ply'
            line = subprocess.run([tool, source, ours, str(fraction)], check=True, capture_output=True,
                                  text=True).stdout.split()
            q = compare(build, source, ours)
            peers = []
            for mode in ('update', 'simplify'):
                prefix = f'{work}/{mesh}_{fraction}'
                out = f'{prefix}_{mode}_{q[2]}.ply'
                subprocess.run(['node', driver, source, '--targets', str(q[2]), '-o', prefix,
                                '--functions', mode, '--flags', 'none'], check=True, capture_output=True)
                peers.append(compare(build, source, out))
            rows.append((q, peers))
            print(f'{mesh:14s} {fraction:5.2f} {q[2]:7d} rms {q[0]:.3e} hd {q[1]:.3e} | update: rms x{q[0] / peers[0][0]:.3f} '
                  f'hd x{q[1] / peers[0][1]:.3f} ({peers[0][2]}) | simplify: rms x{q[0] / peers[1][0]:.3f} '
                  f'hd x{q[1] / peers[1][1]:.3f} | cpu {line[9]} s', flush=True)
    for k, name in enumerate(('simplifyWithUpdate', 'simplify')):
        rms = statistics.median(q[0] / p[k][0] for q, p in rows)
        hd = statistics.median(q[1] / p[k][1] for q, p in rows)
        print(f'median ours / {name}: rms {rms:.3f}, hausdorff {hd:.3f}')


if __name__ == '__main__':
    main()
