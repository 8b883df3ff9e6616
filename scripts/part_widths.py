#!/usr/bin/env python3
"""How wide hands, feet and heads are in the pipeline's meshes, and how near a mesh point the
spur erosion leaves each labelled tip (doc/synthetic.md "Clothes", doc/results.md "Synthetic
hands and feet are thinner than real ones").

  scripts/part_widths.py --bonn ../shared/data/bonn --sequences 7,8
  scripts/part_widths.py --dataset /tmp/synth   # an agex dataset (agex_synth, agex_convert)

Runs the bundled model twice per frame: as bundled, and with its spur erosion off (a copy of
the model with spur_iterations 0 in a temporary directory). Needs the agex Python module
(PYTHONPATH=build/python) and NumPy. Widths are measured on the meshes without the erosion,
across the part at 30% and 60% of the way from the base (wrist, ankle) to the tip (heads: half
way from the neck to the top). A tip's 3D point is the nearest valid depth within 5 pixels of
its labelled pixel, as a hand-clicked label gives it (both kinds of data alike). A part in
front of the body measures the body: read medians, not single cuts."""
import argparse, csv, json, os, shutil, subprocess, sys, tempfile

import numpy as np
import agex

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def labels_file(directory):
    path = os.path.join(directory, 'labels.csv')
    if not os.path.isfile(path):
        sys.exit(f'part_widths: {path}: missing (not a labelled dataset)')
    return open(path, newline='')


def frames(args):
    """(path, [(part, tip_u, tip_v, base_u, base_v)]) per frame with labels."""
    items = {}
    if args.bonn:
        seqs = set(args.sequences.split(',')) if args.sequences else None
        for r in csv.DictReader(labels_file(args.bonn)):
            if (seqs and r['sequence'] not in seqs) or r['keyframe'] != '1':
                continue
            path = os.path.join(args.bonn, 'depth', r['sequence'], r['frame'] + '.png')
            items.setdefault(path, []).append(r)
    else:
        for r in csv.DictReader(labels_file(args.dataset)):
            if r.get('visible', '1') != '1':
                continue
            items.setdefault(os.path.join(args.dataset, 'frames', r['frame'] + '.pcd'), []).append(r)
    for path in sorted(items)[:args.frames]:
        yield path, [(r['part'], float(r['tip_u']), float(r['tip_v']), float(r['base_u']), float(r['base_v']))
                     for r in items[path]]


def intrinsics(args, path):
    """A dataset's intrinsics (its PCD frames carry none)."""
    if args.dataset:
        try:
            k = json.load(open(os.path.join(args.dataset, 'dataset.json'))).get('intrinsics')
        except (OSError, ValueError, AttributeError) as e:
            sys.exit(f'part_widths: {os.path.join(args.dataset, "dataset.json")}: cannot read its intrinsics ({e})')
        if isinstance(k, dict) and all(isinstance(k.get(c), (int, float)) and k[c] > 0 for c in ('fx', 'fy', 'cx', 'cy')):
            return k
    sys.exit(f'part_widths: {path}: no intrinsics (and none in dataset.json)')


def tip_point(frame, u, v):
    P = frame.points
    u0, v0 = int(round(u)), int(round(v))
    for r in range(6):
        z = P[max(0, v0 - r):v0 + r + 1, max(0, u0 - r):u0 + r + 1, 2]
        if np.isfinite(z).any():
            d = float(np.nanmin(z))
            return np.array([(u - frame.cx) * d / frame.fx, (v - frame.cy) * d / frame.fy, d])
    return None


def width(mask, depth, fx, p, direction):
    """Metres across the mask through pixel p, perpendicular to direction."""
    H, W = mask.shape
    n = np.array([-direction[1], direction[0]])
    u0, v0 = int(round(p[0])), int(round(p[1]))
    if not (0 <= u0 < W and 0 <= v0 < H) or not mask[v0, u0]:
        return None
    run = 1
    for s in (1, -1):
        t = 1
        while t < 400:
            u, v = (int(round(c)) for c in p + s * t * n)
            if not (0 <= u < W and 0 <= v < H) or not mask[v, u]:
                break
            t += 1
        run += t - 1
    return run * float(depth[v0, u0]) / fx


def main():
    a = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    g = a.add_mutually_exclusive_group(required=True)
    g.add_argument('--bonn', help='../shared/data/bonn (8-bit PNG frames and labels.csv)')
    g.add_argument('--dataset', help='an agex dataset directory')
    a.add_argument('--sequences', help='Bonn sequences, e.g. 7,8 (default: all)')
    a.add_argument('--frames', type=int, default=60, help='frames at most (default 60)')
    a.add_argument('--model', default=os.path.join(ROOT, 'data/models/agex_bonn.yml'))
    args = a.parse_args()
    if not 1 <= args.frames <= 100000:
        sys.exit('part_widths: --frames must be 1-100000')
    if args.sequences is not None and not all(q in '12345678' and len(q) == 1 for q in args.sequences.split(',')):
        sys.exit(f'part_widths: --sequences lists Bonn sequences 1-8 (e.g. 7,8), not {args.sequences!r}')
    if not os.path.isfile(args.model):
        sys.exit(f'part_widths: {args.model}: no such model file')
    with tempfile.TemporaryDirectory() as tmp:
        off_model = os.path.join(tmp, 'no_spur.yml')
        made = subprocess.run([sys.executable, os.path.join(ROOT, 'scripts/set_model_pipeline.py'), args.model,
                               off_model, 'spur_iterations=0'], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if made.returncode != 0:
            sys.exit(f'part_widths: {args.model}: cannot turn its spur erosion off: {made.stderr.strip()}')
        # The copy finds the forest and the window model it names beside itself.
        for f in os.listdir(os.path.dirname(os.path.abspath(args.model))):
            if f.endswith('.agexforest'):
                shutil.copy(os.path.join(os.path.dirname(os.path.abspath(args.model)), f), tmp)
        window = agex.BodyPartDetector(model=args.model).window_model
        if window:
            relative = os.path.relpath(window, os.path.dirname(os.path.abspath(args.model)))
            if relative.startswith('..'):
                sys.exit(f'part_widths: {args.model} names its window model outside its folder ({window})')
            os.makedirs(os.path.dirname(os.path.join(tmp, relative)) or tmp, exist_ok=True)
            shutil.copy(window, os.path.join(tmp, relative))
        on, off = agex.BodyPartDetector(model=args.model), agex.BodyPartDetector(model=off_model)
        widths, near = {}, {}
        seen = 0
        for path, labels in frames(args):
            seen += 1
            frame = agex.load_frame(path)
            if not frame.has_intrinsics:
                k = intrinsics(args, path)
                frame = agex.Frame(frame.depth, k['fx'], k['fy'], k['cx'], k['cy'])
            meshes = [det.detect(frame, return_intermediate=True)[1]['mesh_ids'] >= 0 for det in (on, off)]
            clouds = [frame.points[m] for m in meshes]
            for part, tu, tv, bu, bv in labels:
                t = tip_point(frame, tu, tv)
                if t is not None:
                    near.setdefault(part, []).append(
                        [float(np.min(np.linalg.norm(c - t, axis=1))) if len(c) else np.inf for c in clouds])
                d = np.array([tu - bu, tv - bv])
                length = np.linalg.norm(d)
                if length < 2:
                    continue
                for f in ((0.5,) if part == 'head' else (0.3, 0.6)):
                    w = width(meshes[1], frame.points[..., 2], frame.fx, np.array([bu, bv]) + f * d, d / length)
                    if w is not None:
                        widths.setdefault(part, []).append(w)
        if seen == 0:
            sys.exit('part_widths: no labelled frames (keyframes of the sequences, or visible labels) to measure')
        for part in sorted(set(widths) | set(near)):
            w = np.array(widths.get(part, [np.nan])) * 100
            d = np.array(near.get(part, [[np.inf, np.inf]]))
            print(f'{part}: width {np.nanmedian(w):.1f} cm ({np.nanpercentile(w, 25):.1f}-{np.nanpercentile(w, 75):.1f}, '
                  f'{len(w)} cuts); tips with a mesh point within 5 cm: {np.mean(d[:, 0] < 0.05):.2f} as bundled, '
                  f'{np.mean(d[:, 1] < 0.05):.2f} without the spur erosion ({len(d)} tips)')


if __name__ == '__main__':
    main()
