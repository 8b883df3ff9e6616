#!/usr/bin/env python3
"""Which labelled persons the detector loses, on an agex dataset with person images
(agex_synth --people N): per person with a visible tip at 0.8-4 m, whether any candidate of
the detector lies on its pixels (else person isolation lost it, or the cleaning stages removed
what it kept), whether any candidate lies within 10 cm of a visible tip, and whether a
detection of the tip's class with confidence >= 0.5 does.

  agex_detect DATASET --json DETECTIONS.jsonl [--model ...]
  scripts/person_losses.py DATASET DETECTIONS.jsonl

Needs NumPy and OpenCV's Python module (Debian: python3-numpy python3-opencv).
"""
import collections
import csv
import json
import sys

try:
    import cv2
    import numpy as np
except ImportError as e:
    sys.exit(f"person_losses.py: needs python3-numpy and python3-opencv ({e})")

RADIUS = 0.1


def main(dataset, detections_path):
    labels = collections.defaultdict(list)
    with open(f"{dataset}/labels.csv") as f:
        for row in csv.DictReader(f):
            labels[row["frame"]].append(row)
    persons = []
    with open(detections_path) as f:
        for line in f:
            doc = json.loads(line)
            frame = doc["frame"].split("/")[-1]
            image = cv2.imread(f"{dataset}/persons/{frame}.png", cv2.IMREAD_UNCHANGED)
            if image is None:
                sys.exit(f"person_losses.py: {dataset}/persons/{frame}.png: missing or unreadable")
            detections = doc["detections"]
            by_person = collections.defaultdict(list)
            for row in labels[frame]:
                by_person[int(row["person"])].append(row)
            for person, rows in by_person.items():
                mask = image == person
                tips = [(r["part"], np.array([float(r["tip_x"]), float(r["tip_y"]), float(r["tip_z"])]))
                        for r in rows if r["visible"] == "1"]
                if not tips:
                    continue
                distance = float(np.median([t[2] for _, t in tips]))
                on_mask = sum(1 for d in detections
                              if 0 <= d["pixel"][1] < mask.shape[0] and 0 <= d["pixel"][0] < mask.shape[1]
                              and mask[d["pixel"][1], d["pixel"][0]])
                near = lambda d, t: np.linalg.norm(np.array(d["position"]) - t) < RADIUS
                covered = any(near(d, t) for _, t in tips for d in detections)
                found = any(near(d, t) and d["class"] == part and d["confidence"] >= 0.5
                            for part, t in tips for d in detections)
                persons.append(dict(frame=frame, person=person, pixels=int(mask.sum()), distance=distance,
                                    on_mask=on_mask, covered=covered, found=found))
    near = [p for p in persons if 0.8 <= p["distance"] < 4.0]
    lost = [p for p in near if p["on_mask"] == 0]
    print(f"persons with a visible tip at 0.8-4 m: {len(near)}")
    print(f"  no candidate on their pixels (isolation or the cleaning lost them): {len(lost)}")
    print(f"  candidates on them, none within {RADIUS} m of a tip: "
          f"{sum(p['on_mask'] > 0 and not p['covered'] for p in near)}")
    print(f"  a candidate within {RADIUS} m of a tip: {sum(p['covered'] for p in near)}")
    print(f"  found (person recall): {sum(p['found'] for p in near)}")
    for p in sorted(lost, key=lambda p: -p["pixels"]):
        print(f"  lost: frame {p['frame']} person {p['person']}, {p['pixels']} pixels, {p['distance']:.2f} m")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
