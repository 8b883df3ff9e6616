"""Loads a depth frame, finds heads, hands and feet, and plots them over the frame.

    PYTHONPATH=build/python python3 doc/examples/python/plot_detections.py data/frames/bonn_1_002.png out.png
"""

import sys

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt
import numpy as np

import agex

frame_path = sys.argv[1] if len(sys.argv) > 1 else agex.bundled_data_file("frames/bonn_1_002.png")
out_path = sys.argv[2] if len(sys.argv) > 2 else "detections.png"

frame = agex.load_frame(frame_path)  # or agex.Frame(depth_array, fx, fy, cx, cy)
detector = agex.BodyPartDetector()  # the bundled model
detections, seen = detector.detect(frame, return_intermediate=True)

fig, ax = plt.subplots(figsize=(8, 6))
ax.imshow(frame.depth, cmap="gray_r")  # metres, NaN (invalid) left blank
ax.imshow(np.ma.masked_less(seen["mesh_ids"], 0), cmap="tab10", alpha=0.3, vmin=0, vmax=9)
colours = {"head": "red", "hand": "lime", "foot": "blue"}
for d in detections:
    if d["confidence"] < 0.5:
        continue
    u, v = d["pixel"]
    ax.add_patch(plt.Circle((u, v), 12, fill=False, color=colours[d["class"]], linewidth=2))
    ax.annotate(f'{d["class"]} {d["confidence"]:.2f}', (u + 14, v), color=colours[d["class"]])
ax.set_title(f"{frame.path}: {len(detections)} detections, {seen['ms']['total']:.0f} ms")
ax.set_axis_off()
fig.savefig(out_path, bbox_inches="tight")
print(f"{out_path}: {sum(d['confidence'] >= 0.5 for d in detections)} detections at or above 0.5")
