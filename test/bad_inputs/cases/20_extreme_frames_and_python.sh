# Sourced by run_bad_inputs.sh (its check, capped, hash_inputs, $D $K, in/ and out/): frames
# whose metric extent is absurd, intrinsics outside the sane range, a forest whose reference
# focal length no camera could be evaluated at. The Python module's cases are pytest's
# (test/python/test_agex.py).

# 16x12 points 1e8 m apart at 2 m depth: once a crash in the person segmentation's bins. It is
# a frame of nothing to find: exit 0, no interest points, no detections.
{
  printf '# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n'
  printf 'WIDTH 16\nHEIGHT 12\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 192\nDATA ascii\n'
  for v in $(seq -6 5); do for u in $(seq -8 7); do echo "${u}e8 ${v}e8 2"; done; done
} > in/tiny_1e8_apart.pcd
# The bundled fused model's forest with its reference focal length (the f32 at byte 36) set to
# 1 px, the checksum (the last 4 bytes, CRC-32) made good again.
python3 - in/agex_bonn_forest.agexforest in/focal_1.agexforest <<'PY'
import struct, sys, zlib
data = bytearray(open(sys.argv[1], "rb").read())
data[36:40] = struct.pack("<f", 1.0)
data[-4:] = struct.pack("<I", zlib.crc32(bytes(data[:-4])) & 0xFFFFFFFF)
open(sys.argv[2], "wb").write(bytes(data))
PY
hash_inputs

check "points 1e8 m apart (16x12 PCD)" 0 "" capped 2000 60 $K in/tiny_1e8_apart.pcd --json out/tiny_points.json
grep -q '"interest_points":\[\]' <(tr -d ' \n' < out/tiny_points.json) ||
  { echo "FAILED: points 1e8 m apart: interest points not empty" >&2; failures=$((failures + 1)); }
check "points 1e8 m apart, detector" 0 "" capped 2000 60 $D in/tiny_1e8_apart.pcd --json out/tiny_detections.json
grep -q '"detections":\[\]' <(tr -d ' \n' < out/tiny_detections.json) ||
  { echo "FAILED: points 1e8 m apart: detections not empty" >&2; failures=$((failures + 1)); }
check "a focal length of 1e-6 px" 1 "--fx must be a focal length of 0.001 to 1e\+06 pixels; got 1e-06" \
  $K in/frame.png --fx 1e-6 --fy 1e-6
check "a focal length finite only as a double" 1 "--fx must be a focal length of 0.001 to 1e\+06 pixels; got 1e\+39" \
  $D in/frame.png --fx 1e39
check "a principal point beyond a float" 1 "--cy must be a number of pixels finite as a float" \
  $D in/frame.png --cy 1e39
check "a forest made for a 1 px camera" 1 "focal_1.agexforest: the reference focal length 1 px lies outside 10 to" \
  $D in/frame.png --detector-mode forest --forest in/focal_1.agexforest --json out/a.json
