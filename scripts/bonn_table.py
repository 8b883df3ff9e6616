#!/usr/bin/env python3
"""Tables of the agex_eval detect reports that scripts/evaluate_bonn.sh writes.

  scripts/bonn_table.py FOLD_DIR            one fold: AP, top recall, ms, candidate coverage
  scripts/bonn_table.py FOLD_DIR FOLD_DIR.. several folds: per figure the mean over folds and
                                            its range [min, max] (folds missing a report are named)
"""
import json
import os
import statistics
import sys

DETECTORS = [("agex", "AGEX only"), ("sw", "sliding window"), ("pcl_forest", "PCL's forest alone"),
             ("our_forest", "our forest alone"), ("fused", "fused"),
             ("box", "fused, crop box instead of person isolation")]
# Rows shown only where a fold has them (older fold folders lack the crop-box reports).
OPTIONAL = {"box"}
VIEWS = ["portrait", "full"]
PARTS = ["head", "hand", "foot"]


def load(fold, name, view):
    path = os.path.join(fold, f"ev_{name}_{view}.json")
    if name in OPTIONAL and not os.path.exists(path):
        return None
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        print(f"bonn_table: {path}: {e}", file=sys.stderr)
        return None


def figures(report):
    """The figures of one report: AP and top recall per class, ms per frame."""
    ap = report.get("ap", {})
    ap = ap.get("distance", ap)
    out = {f"ap_{p}": ap.get(p) for p in PARTS}
    out.update({f"top_{p}": report.get("top_recall", {}).get(p) for p in PARTS})
    out["ms"] = report.get("ms_per_frame_median")
    cov = report.get("candidate_coverage") or {}
    for kind in ("agex5", "modes", "union"):
        for p in PARTS:
            out[f"cov_{kind}_{p}"] = (cov.get(kind) or {}).get(p)
    return out


def cell(values, digits=3):
    values = [v for v in values if isinstance(v, (int, float))]
    if not values:
        return "-"
    fmt = f"{{:.{digits}f}}"
    if len(values) == 1:
        return fmt.format(values[0])
    return f"{fmt.format(statistics.mean(values))} [{fmt.format(min(values))}, {fmt.format(max(values))}]"


def main(folds):
    for view in VIEWS:
        print(f"\n{view} view, {len(folds)} fold(s): AP at 10 cm head / hand / foot; top recall head / hand / foot; ms per frame\n")
        print("| detector | AP head | AP hand | AP foot | top recall head | hand | foot | ms |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        fused = []
        for name, label in DETECTORS:
            rows = [figures(r) for r in (load(f, name, view) for f in folds) if r is not None]
            if name == "fused":
                fused = rows
            if not rows:
                if name not in OPTIONAL:
                    print(f"| {label} | (no reports) |")
                continue
            cells = [cell([r[f"ap_{p}"] for r in rows]) for p in PARTS]
            cells += [cell([r[f"top_{p}"] for r in rows]) for p in PARTS]
            cells.append(cell([r["ms"] for r in rows], 1))
            print(f"| {label} | " + " | ".join(cells) + " |")
        if fused:
            print(f"\ncandidate coverage (labelled tips within 10 cm of a candidate), {view} view, fused model\n")
            print("| candidates | head | hand | foot |")
            print("| --- | --- | --- | --- |")
            for kind, label in (("agex5", "AGEX_5"), ("modes", "forest modes"), ("union", "union (fused)")):
                print(f"| {label} | " + " | ".join(cell([r[f"cov_{kind}_{p}"] for r in fused]) for p in PARTS) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
