"""The agex Python module as built: the same detections as agex_detect on the bundled frame
(through a Frame and through numpy arrays), the intermediate results, AGEX interest points as
agex_keypoints gives them, clear errors for bad arrays and the apps' messages for bad files,
and a thread pool that gives what a serial loop gives.

Run from ctest (PYTHONPATH = the build's python/ directory; AGEX_DETECT = agex_detect as
built; AGEX_SOURCE_DIR = the source tree; AGEX_SHARED_DATA_DIR = ../shared/data).
"""

import json
import os
import subprocess
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import agex

SOURCE = os.environ.get("AGEX_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
FRAME = os.path.join(SOURCE, "data", "frames", "bonn_1_002.png")
AGEX_DETECT = os.environ.get("AGEX_DETECT", "")
BIN_DIR = os.path.dirname(AGEX_DETECT)
SHARED = os.environ.get("AGEX_SHARED_DATA_DIR", os.path.join(SOURCE, "..", "shared", "data"))
KINECT = dict(fx=525.0, fy=525.0, cx=319.5, cy=239.5)
BONN_SCALE = 0.016  # metres per grey level of the 8-bit Bonn frames


def run_app(app, *args):
    exe = os.path.join(BIN_DIR, app)
    if not os.path.exists(exe):
        pytest.skip(f"{exe} is not built")
    # The sanitizer runtimes preloaded for the interpreter (python/CMakeLists.txt) are not the
    # apps' to load: an app built by clang carries its own, and refuses a second.
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    return subprocess.run([exe, *args], capture_output=True, text=True, env=env)


def app_document(app, *args, tmp_path):
    out = tmp_path / f"{app}.json"
    done = run_app(app, *args, "--json", str(out))
    assert done.returncode == 0, done.stderr
    return json.loads(out.read_text())


def app_error(app, *args):
    done = run_app(app, *args)
    assert done.returncode == 1
    prefix = f"{app}: error: "
    line = [l for l in done.stderr.splitlines() if l.startswith(prefix)][-1]
    return line[len(prefix):]


@pytest.fixture(scope="module")
def detector():
    return agex.BodyPartDetector()


@pytest.fixture(scope="module")
def grey():
    """The bundled frame's grey levels (uint8), recovered exactly from its depth."""
    depth = agex.load_frame(FRAME).depth
    levels = np.where(np.isnan(depth), 0, np.rint(depth / np.float32(BONN_SCALE)))
    assert levels.max() <= 255
    return levels.astype(np.uint8)


def test_same_detections_as_agex_detect(detector, tmp_path):
    expected = app_document("agex_detect", FRAME, tmp_path=tmp_path)["detections"]
    frame = agex.load_frame(FRAME)
    assert (frame.width, frame.height, frame.has_intrinsics) == (640, 480, True)
    found = detector.detect(frame)
    assert len(found) > 0
    assert found == expected  # every field, bit for bit (the JSON keeps each float exactly)
    assert set(found[0]) >= {"class", "confidence", "margin", "position", "orientation", "pixel", "rank", "mesh"}


def test_the_cascade_off_keeps_every_candidate_and_the_confident_detections(detector):
    frame = agex.load_frame(FRAME)
    with_cascade = detector.detect(frame)
    full = agex.BodyPartDetector(cascade_min_confidence=0.0).detect(frame)
    assert len(full) > len(with_cascade)
    confident = [d for d in full if d["confidence"] >= 0.5]
    assert len(confident) >= 3
    for d in confident:
        assert d in with_cascade


def test_the_tip_refinement_moves_hands_and_feet_only_and_keeps_their_confidences(detector):
    frame = agex.load_frame(FRAME)
    # The fused classifier's own confidences (on this frame the window's view leaves no hand or
    # foot at an ankle or wrist to move).
    before = agex.BodyPartDetector(window_weight=0).detect(frame)
    after = agex.BodyPartDetector(tip_radius=0.1, window_weight=0).detect(frame)
    # Each class keeps its most confident detection's confidence; heads stay where they were.
    for part in ("head", "hand", "foot"):
        assert max(d["confidence"] for d in after if d["class"] == part) == \
            max(d["confidence"] for d in before if d["class"] == part)
    assert [d for d in after if d["class"] == "head"] == [d for d in before if d["class"] == "head"]
    # Some hand or foot moves (on this frame, with the bundled model), each onto an AGEX point;
    # among them a part mode's (rank 0), which takes its pixel's mesh to find one.
    was = {(d["class"], d["confidence"]): d for d in before}
    moved = [(was[(d["class"], d["confidence"])], d) for d in after
             if (d["class"], d["confidence"]) in was and was[(d["class"], d["confidence"])]["pixel"] != d["pixel"]]
    assert moved
    assert all(d["class"] != "head" and d["rank"] > 0 for _, d in moved)
    assert any(old["rank"] == 0 for old, _ in moved)


def test_the_bundled_fused_model_blends_in_its_sliding_window_and_weight_zero_turns_it_off():
    frame = agex.load_frame(FRAME)
    bundled = agex.BodyPartDetector()
    assert bundled.window_model == agex.bundled_data_file("models/agex_bonn_sw.yml")
    blended = bundled.detect(frame)
    plain_detector = agex.BodyPartDetector(window_weight=0)
    assert plain_detector.window_model == ""
    plain = plain_detector.detect(frame)
    assert blended and plain
    # The same candidates, other confidences: the window's view moves each of them.
    assert sorted(d["confidence"] for d in blended) != sorted(d["confidence"] for d in plain)
    # Given explicitly with the bundled model's weight: the bundled detector exactly.
    explicit = agex.BodyPartDetector(window_model=agex.bundled_data_file("models/agex_bonn_sw.yml"),
                                     window_weight=0.3)
    assert explicit.detect(frame) == blended
    with pytest.raises(ValueError, match="window_weight"):
        agex.BodyPartDetector(window_weight=1.5)
    with pytest.raises(ValueError, match="window_model rescores a fused model"):
        agex.BodyPartDetector(model=agex.bundled_data_file("models/agex_bonn_agex.yml"),
                              window_model=agex.bundled_data_file("models/agex_bonn_sw.yml"))
    with pytest.raises(ValueError, match="a sliding-window model is needed here"):
        agex.BodyPartDetector(window_model=agex.bundled_data_file("models/agex_bonn_agex.yml"))
    with pytest.raises(ValueError, match="window_model"):
        agex.BodyPartDetector(window_model="x\0y")
    assert agex.BodyPartDetector().window_weight == pytest.approx(0.3)
    assert agex.BodyPartDetector(window_weight=0).window_weight == 0


def test_same_detections_from_a_numpy_array(detector, grey):
    expected = detector.detect(agex.load_frame(FRAME))
    # The frame's own grey levels back-projected as loadFrame does: the same detections exactly.
    assert detector.detect(grey, **KINECT, depth_scale=BONN_SCALE) == expected
    # Metres as float32 (the frame's own depth) or millimetres: positions to float rounding (the
    # back-projection starts from a float, not from a grey level), so the confident parts are
    # found at the same pixels; a doubtful candidate of the forest's modes may come or go.
    def confident(detections):
        return sorted((tuple(d["pixel"]), d["class"]) for d in detections if d["confidence"] >= 0.5)

    by_pixel = {tuple(d["pixel"]): d for d in expected}
    for depth in (agex.load_frame(FRAME).depth.copy(), (grey.astype(np.uint16) * 16)):  # metres; millimetres
        found = detector.detect(depth, **KINECT)
        assert confident(found) and confident(found) == confident(expected)
        assert len({tuple(d["pixel"]) for d in found} & set(by_pixel)) >= 0.8 * len(by_pixel)
        for d in found:
            if tuple(d["pixel"]) in by_pixel:
                np.testing.assert_allclose(d["position"], by_pixel[tuple(d["pixel"])]["position"], atol=1e-5)


def test_arrays_of_any_layout_give_the_same_result(detector, grey):
    expected = detector.detect(grey, **KINECT, depth_scale=BONN_SCALE)
    # Rows inside a wider array (read in place), Fortran order, a negative row step (copied).
    wide = np.zeros((480, 700), np.uint8)
    wide[:, :640] = grey
    assert detector.detect(wide[:, :640], **KINECT, depth_scale=BONN_SCALE) == expected
    assert detector.detect(np.asfortranarray(grey), **KINECT, depth_scale=BONN_SCALE) == expected
    assert detector.detect(grey[::-1][::-1], **KINECT, depth_scale=BONN_SCALE) == expected
    every_other = np.zeros((480, 1280), np.uint8)
    every_other[:, ::2] = grey
    assert detector.detect(every_other[:, ::2], **KINECT, depth_scale=BONN_SCALE) == expected
    # uint16 at an odd address (numpy allows unaligned arrays): copied, the same result.
    mm = grey.astype(np.uint16) * 16
    raw = np.zeros(mm.nbytes + 1, np.uint8)
    unaligned = raw[1:].view(np.uint16).reshape(mm.shape)
    unaligned[...] = mm
    assert not unaligned.flags.aligned
    assert detector.detect(unaligned, **KINECT) == detector.detect(mm, **KINECT)
    frame = agex.Frame(grey, **KINECT, depth_scale=BONN_SCALE)
    assert detector.detect(frame) == expected
    np.testing.assert_array_equal(frame.points[..., 2], frame.depth)
    assert not frame.depth.flags.writeable


@pytest.mark.parametrize(
    "depth, needle",
    [
        (np.zeros((48, 64), np.float64), "dtype float64"),
        (np.zeros((48, 64), np.int32), "dtype int32"),
        (np.zeros((48, 64), ">u2"), "native byte order"),
        (np.zeros(64, np.uint16), "2-D array"),
        (np.zeros((48, 64, 3), np.uint16), "depth[..., 0]"),
        (np.zeros((0, 0), np.uint16), "at least 2 rows"),
        (np.zeros((1, 64), np.uint16), "at least 2 rows"),
        ([[1, 2], [3, 4]], "numpy array"),
    ],
)
def test_bad_arrays_are_refused_clearly(detector, depth, needle):
    with pytest.raises(ValueError, match=None) as refused:
        detector.detect(depth, 100.0, 100.0, 1.0, 1.0)
    assert needle in str(refused.value)


def test_bad_intrinsics_and_settings_are_refused(detector):
    depth = np.full((48, 64), 1500, np.uint16)
    with pytest.raises(ValueError, match="fx, fy, cx and cy"):
        detector.detect(depth)
    with pytest.raises(ValueError, match="principal point"):
        detector.detect(depth, 100.0, 100.0, 500.0, 24.0)
    with pytest.raises(ValueError, match="fx must be a focal length of"):
        detector.detect(depth, 0.0, 100.0, 32.0, 24.0)
    with pytest.raises(ValueError, match="depth_scale"):
        detector.detect(np.zeros((48, 64), np.uint8), 100.0, 100.0, 32.0, 24.0)
    with pytest.raises(ValueError, match="carries its intrinsics"):
        detector.detect(agex.load_frame(FRAME), 525.0)
    with pytest.raises(ValueError, match="mode"):
        agex.BodyPartDetector(mode="sliding")
    with pytest.raises(ValueError, match="cascade_min_confidence"):
        agex.BodyPartDetector(cascade_min_confidence=1.0)
    with pytest.raises(ValueError, match="cascade_miss_rate"):
        agex.BodyPartDetector(cascade_miss_rate=float("nan"))
    with pytest.raises(ValueError, match="tip_radius"):
        agex.BodyPartDetector(tip_radius=0.6)
    with pytest.raises(ValueError, match="tip_min_confidence"):
        agex.BodyPartDetector(tip_min_confidence=float("nan"))
    # An empty, all-invalid frame: no detections, no error.
    assert detector.detect(np.zeros((48, 64), np.uint16), 100.0, 100.0, 32.0, 24.0) == []


def test_absurd_intrinsics_and_depths_are_refused_or_give_nothing(detector):
    # Focal lengths of 1e-8 px (a crash in the person segmentation once), 1e39 (no detections
    # without a word) and a principal point beyond a float are refused, naming the value.
    depth = np.full((480, 640), 1500, np.uint16)
    for f in (1e-8, 1e-6, 1e39):
        with pytest.raises(ValueError, match="fx must be a focal length of 0.001 to 1e"):
            detector.detect(depth, f, 525.0, 319.5, 239.5)
        with pytest.raises(ValueError, match="fy must be a focal length"):
            agex.Frame(depth, 525.0, f, 319.5, 239.5)
    with pytest.raises(ValueError, match="fx must be a focal length"):
        agex.load_frame(FRAME, fx=1e-6, fy=525.0, cx=319.5, cy=239.5)
    with pytest.raises(ValueError, match="depth_scale must be a positive number"):
        detector.detect(depth, **KINECT, depth_scale=1e39)
    # Depths of 3.4e38 m: a frame of nothing to find, not a crash.
    assert detector.detect(np.full((480, 640), 3.4e38, np.float32), **KINECT) == []
    assert agex.agex_keypoints(np.full((480, 640), 3.4e38, np.float32), **KINECT) == []


def test_a_masked_array_is_invalid_where_masked(detector, grey):
    everything = np.ma.masked_array(grey, mask=np.ones(grey.shape, bool))
    assert detector.detect(everything, **KINECT, depth_scale=BONN_SCALE) == []
    frame = agex.Frame(everything, **KINECT, depth_scale=BONN_SCALE)
    assert np.isnan(frame.depth).all()
    nothing = np.ma.masked_array(grey, mask=np.zeros(grey.shape, bool))
    assert detector.detect(nothing, **KINECT, depth_scale=BONN_SCALE) == detector.detect(
        grey, **KINECT, depth_scale=BONN_SCALE)
    half = np.ma.masked_array(grey, mask=np.zeros(grey.shape, bool))
    half[:, :320] = np.ma.masked
    assert np.isnan(agex.Frame(half, **KINECT, depth_scale=BONN_SCALE).depth[:, :320]).all()


def test_paths_with_a_nul_are_refused(tmp_path):
    with pytest.raises(ValueError, match="path contains a NUL"):
        agex.load_frame(FRAME + "\0junk.png")
    model = agex.bundled_data_file("models/agex_bonn.yml")
    with pytest.raises(ValueError, match="model: the path contains a NUL"):
        agex.BodyPartDetector(model=model + "\0evil")
    with pytest.raises(ValueError, match="forest: the path contains a NUL"):
        agex.BodyPartDetector(forest="forest.agexforest\0evil")
    with pytest.raises(ValueError, match="model: the path contains a NUL"):
        agex.agex_keypoints(agex.load_frame(FRAME), model=model + "\0evil")


def test_bad_setting_values_name_the_setting():
    frame = agex.load_frame(FRAME)
    looped = [0.0, 0.0]
    looped.append(looped)
    with pytest.raises(ValueError, match="crop_min: lists nested more than 64 deep"):
        agex.agex_keypoints(frame, use_crop_box=True, crop_min=looped)
    deep = [0.0]
    for _ in range(50000):
        deep = [deep]
    with pytest.raises(ValueError, match="crop_min: lists nested more than 64 deep"):
        agex.agex_keypoints(frame, use_crop_box=True, crop_min=deep)
    with pytest.raises(ValueError, match="k: 9223372036854775808 does not fit a 64-bit integer"):
        agex.agex_keypoints(frame, k=2**63)
    with pytest.raises(ValueError, match="naive: expected True or False, got 'yes'"):
        agex.agex_keypoints(frame, naive="yes")


def test_file_errors_carry_the_apps_messages(tmp_path):
    missing = str(tmp_path / "missing.png")
    with pytest.raises(agex.FrameError, match=f"{missing}: no such file"):
        agex.load_frame(missing)
    broken = tmp_path / "broken.png"
    broken.write_bytes(b"\x89PNG not really")
    with pytest.raises(agex.FrameError) as e:
        agex.load_frame(str(broken))
    assert str(e.value) == app_error("agex_detect", str(broken))
    model = tmp_path / "model.yml"
    model.write_text("%YAML:1.0\nnot: a model\n")
    with pytest.raises(agex.ModelError) as e:
        agex.BodyPartDetector(model=str(model))
    assert str(e.value) == app_error("agex_detect", FRAME, "--model", str(model))
    # Frames and models that cannot be read are runtime errors, as the apps' exit status 1.
    assert issubclass(agex.FrameError, RuntimeError) and issubclass(agex.ModelError, RuntimeError)


def test_intermediate_results(detector, grey):
    detections, seen = detector.detect(grey, **KINECT, depth_scale=BONN_SCALE, return_intermediate=True)
    assert detections
    assert seen["filtered_depth"].shape == (480, 640) and seen["filtered_depth"].dtype == np.float32
    assert seen["mesh_ids"].dtype == np.int32 and seen["part_labels"].dtype == np.int32
    meshes = seen["mesh_ids"]
    assert meshes.max() >= 0
    # Mesh pixels are kept pixels; removed pixels are on no mesh.
    assert np.isfinite(seen["filtered_depth"][meshes >= 0]).all()
    assert (meshes[np.isnan(seen["filtered_depth"])] == -1).all()
    # Every detection lies on a mesh pixel of its mesh.
    for d in detections:
        u, v = d["pixel"]
        assert meshes[v, u] == d["mesh"]
    # The bundled detector is fused: its forest labels the meshes' pixels and nothing else.
    assert (seen["part_labels"][meshes < 0] == -1).all()
    assert (seen["part_labels"][meshes >= 0] >= 0).mean() > 0.5
    assert seen["interest_points"] and {"position", "orientation", "pixel", "rank", "mesh"} <= set(seen["interest_points"][0])
    assert "total" in seen["ms"]
    # intermediate () is the last detect ()'s.
    again = detector.intermediate()
    np.testing.assert_array_equal(again["mesh_ids"], meshes)


def test_part_labels_with_a_forest(tmp_path):
    forest = os.path.join(SHARED, "pcl_people", "forest1", "tree_20.txt.bz2")
    if not os.path.exists(forest):
        pytest.skip(f"{forest} not found; PCL's people forest is needed for this test")
    detector = agex.BodyPartDetector(forest=forest, mode="forest")
    found, seen = detector.detect(agex.load_frame(FRAME), return_intermediate=True)
    expected = app_document("agex_detect", FRAME, "--forest", forest, "--detector-mode", "forest", tmp_path=tmp_path)
    assert found == expected["detections"]
    labels = seen["part_labels"]
    assert labels.shape == (480, 640)
    assert set(np.unique(labels)) <= {-1, 0, 1, 2, 3}
    assert (labels[seen["mesh_ids"] >= 0] >= 0).mean() > 0.5  # the person's pixels are labelled
    # PCL's forests read the whole segmented person (doc/forest.md, "Forest mode: labels to
    # parts"): pixels the cleaning removed from the meshes are labelled too, the room is not.
    rows, cols = np.nonzero(seen["mesh_ids"] >= 0)
    lrows, lcols = np.nonzero(labels >= 0)
    assert lrows.min() >= rows.min() - 40 and lrows.max() <= rows.max() + 40
    assert lcols.min() >= cols.min() - 40 and lcols.max() <= cols.max() + 40
    assert seen["part_modes"]


def test_agex_keypoints_as_the_app_gives_them(tmp_path):
    expected = app_document("agex_keypoints", FRAME, "--k", "7", tmp_path=tmp_path)["interest_points"]
    points = agex.agex_keypoints(agex.load_frame(FRAME), k=7)
    assert len(points) == len(expected) > 0
    for p, q in zip(points, expected):
        assert p["position"] == (q["x"], q["y"], q["z"])
        assert p["pixel"] == (q["u"], q["v"])
        assert (p["rank"], p["mesh"]) == (q["rank"], q["mesh"])
        assert list(p["orientation"]) == q["orientation"]
    with pytest.raises(ValueError, match="unknown setting 'kk'"):
        agex.agex_keypoints(agex.load_frame(FRAME), kk=3)
    with pytest.raises(ValueError, match="pipeline.k"):
        agex.agex_keypoints(agex.load_frame(FRAME), k=0)
    # A narrower crop box (a numpy array is a list; the box is off unless asked for): every
    # point inside it.
    crop = agex.agex_keypoints(agex.load_frame(FRAME), use_crop_box=True, crop_min=np.array([0.0, -1.5, 1.3]))
    assert crop and all(p["position"][0] >= 0.0 for p in crop)
    assert any(p["position"][0] < 0.0 for p in agex.agex_keypoints(agex.load_frame(FRAME)))


def test_a_working_density_gives_the_inputs_pixels_and_images(tmp_path):
    # agex_keypoints at a working spacing of 1 cm (every second pixel of the bundled 640x480
    # frame): the same points as the app, their pixels the input's (where the camera sees
    # them), and the images at the input's size, each working pixel filling its block.
    expected = app_document("agex_keypoints", FRAME, "--working-spacing", "0.01", tmp_path=tmp_path)
    assert expected["working_stride"] == 2
    points, seen = agex.agex_keypoints(agex.load_frame(FRAME), working_spacing=0.01, return_intermediate=True)
    assert len(points) == len(expected["interest_points"]) > 0
    for p, q in zip(points, expected["interest_points"]):
        assert p["pixel"] == (q["u"], q["v"])
        x, y, z = p["position"]
        assert abs(KINECT["fx"] * x / z + KINECT["cx"] - p["pixel"][0]) <= 1.0
        assert abs(KINECT["fy"] * y / z + KINECT["cy"] - p["pixel"][1]) <= 1.0
    meshes = seen["mesh_ids"]
    assert meshes.shape == (480, 640) and seen["filtered_depth"].shape == (480, 640)
    for p in points:
        u, v = p["pixel"]
        assert meshes[v, u] == p["mesh"]
    # Blocks of 2x2: each row pair and column pair repeats.
    np.testing.assert_array_equal(meshes[0::2, 0::2], meshes[1::2, 1::2])


def test_a_thread_pool_gives_what_a_serial_loop_gives(grey):
    # Eight different frames: the bundled one shifted and mirrored.
    frames = [np.roll(grey, shift, axis=1) for shift in (-60, -30, 0, 30, 60)]
    frames += [grey[:, ::-1].copy(), np.roll(grey[:, ::-1], 40, axis=1), np.roll(grey, 20, axis=0)]
    shared = agex.BodyPartDetector()
    serial = [shared.detect(f, **KINECT, depth_scale=BONN_SCALE) for f in frames]
    assert len({json.dumps(s) for s in serial}) == len(frames)  # the frames really differ
    with ThreadPoolExecutor(max_workers=4) as pool:
        # One detector shared by every thread (each call a C++ detector no other call uses) ...
        pooled = list(pool.map(lambda f: shared.detect(f, **KINECT, depth_scale=BONN_SCALE), frames))
        # ... and one per call.
        fresh = list(pool.map(lambda f: agex.BodyPartDetector().detect(f, **KINECT, depth_scale=BONN_SCALE), frames))
    assert pooled == serial
    assert fresh == serial


def write_pcd(path, points):
    """An organized ASCII PCD of an H x W x 3 array of points (NaN where none)."""
    h, w, _ = points.shape
    header = (f"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
              f"WIDTH {w}\nHEIGHT {h}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {w * h}\nDATA ascii\n")
    rows = "\n".join(" ".join("nan" if np.isnan(v) else repr(float(v)) for v in p) for p in points.reshape(-1, 3))
    path.write_text(header + rows + "\n")


def test_a_kept_detector_gives_what_a_new_one_gives(grey, tmp_path):
    # One detector over frames of different cameras: a PCD (no intrinsics: estimated) after an
    # array seen through another lens gets the estimate again, not the last frame's.
    pcd = tmp_path / "frame.pcd"
    write_pcd(pcd, np.asarray(agex.load_frame(FRAME).points))
    kept = agex.BodyPartDetector()
    # The last call's C++ detector stays with intermediate (): calls take turns between two, so
    # two array frames first leave both having seen the other lens.
    through_another_lens = kept.detect(grey, fx=400.0, fy=400.0, cx=319.5, cy=239.5, depth_scale=BONN_SCALE)
    assert kept.detect(grey, fx=400.0, fy=400.0, cx=319.5, cy=239.5, depth_scale=BONN_SCALE) == through_another_lens
    from_pcd = kept.detect(agex.load_frame(str(pcd)))
    again = kept.detect(grey, fx=400.0, fy=400.0, cx=319.5, cy=239.5, depth_scale=BONN_SCALE)
    assert from_pcd == agex.BodyPartDetector().detect(agex.load_frame(str(pcd)))
    assert again == through_another_lens
    assert from_pcd and from_pcd != through_another_lens


def test_bundled_data():
    assert os.path.isfile(agex.bundled_data_file("models/agex_bonn.yml"))
    assert agex.BodyPartDetector().model == agex.bundled_data_file("models/agex_bonn.yml")
    assert agex.__version__


def test_the_documented_script_runs(tmp_path, monkeypatch):
    """doc/examples/python/plot_detections.py (doc/python.md) against the module as built, with
    matplotlib replaced by a stand-in that records what is drawn (matplotlib is not needed to
    build or test agex)."""
    import runpy
    import sys
    import types

    drawn = []

    class Anything:
        def __init__(self, name):
            self.name = name

        def __getattr__(self, attribute):
            return Anything(f"{self.name}.{attribute}")

        def __call__(self, *args, **kwargs):
            drawn.append((self.name, args, kwargs))
            return (Anything("fig"), Anything("ax")) if self.name.endswith("subplots") else Anything(self.name)

    matplotlib = types.ModuleType("matplotlib")
    matplotlib.use = lambda backend: None
    pyplot = types.ModuleType("matplotlib.pyplot")
    pyplot.subplots = Anything("subplots")
    pyplot.Circle = Anything("Circle")
    matplotlib.pyplot = pyplot
    monkeypatch.setitem(sys.modules, "matplotlib", matplotlib)
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", pyplot)
    out = tmp_path / "detections.png"
    monkeypatch.setattr(sys, "argv", ["plot_detections.py", FRAME, str(out)])
    runpy.run_path(os.path.join(SOURCE, "doc", "examples", "python", "plot_detections.py"), run_name="__main__")
    confident = [d for d in agex.BodyPartDetector().detect(agex.load_frame(FRAME)) if d["confidence"] >= 0.5]
    assert sum(name == "Circle" for name, _, _ in drawn) == len(confident) > 0
    assert any(name == "fig.savefig" and args[0] == str(out) for name, args, _ in drawn)
