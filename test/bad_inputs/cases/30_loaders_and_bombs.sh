# Loaders and decompression bombs (issue 31): small files that claim far more than they hold,
# and numbers beyond their type. Each blow-up runs capped and must be refused within the cap.
# Sourced by run_bad_inputs.sh (check, capped, hash_inputs, $BIN, $D, $E, in/, out/).

# A forest of 20 copies of a 9 KB bzip2 file that holds a valid depth-24 tree (201 MB of text):
# 14 GB within the per-file limits; a forest may hold 2^25 nodes.
mkdir -p in/forest24
for i in $(seq 10 29); do cp in/depth24_zeros.txt.bz2 "in/forest24/tree_$i.txt.bz2"; done
# 10,000 nested empty folders.
mkdir -p in/deep_forest
python3 -c "
import os
fd = os.open('in/deep_forest', os.O_RDONLY)
for _ in range(10000):
    os.mkdir('d', dir_fd=fd)
    sub = os.open('d', os.O_RDONLY, dir_fd=fd)
    os.close(fd)
    fd = sub
"
# Image bombs, made small: a 1-bit TIFF directory claiming 32767x32767, a WebP VP8X canvas of
# 16384x16384, a JPEG whose first frame header (the one libjpeg decodes) claims 30000x30000 and
# whose second, after the scan, 16x16; a small JPEG, later made a 2.2 GB sparse file.
python3 - <<'EOF'
import struct
def tiff(w, h):
    entries = [(256, 4, w), (257, 4, h), (258, 3, 1), (259, 3, 1), (262, 3, 0), (273, 4, 122),
               (277, 3, 1), (278, 4, h), (279, 4, 16)]
    t = b'II*\0' + struct.pack('<I', 8) + struct.pack('<H', len(entries))
    for tag, typ, value in entries:
        t += struct.pack('<HHII', tag, typ, 1, value)
    return t + struct.pack('<I', 0) + bytes(16)
open('in/bomb.tif', 'wb').write(tiff(32767, 32767))
open('in/bomb.webp', 'wb').write(b'RIFF' + struct.pack('<I', 30) + b'WEBPVP8X' + struct.pack('<I', 10) + bytes(4) +
                                 b'\xff\x3f\0\xff\x3f\0' + b'VP8L' + struct.pack('<I', 5) + b'\x2f' + bytes(4))
def sof(w, h):
    return b'\xff\xc0' + struct.pack('>HBHHB', 11, 8, h, w, 1) + b'\x01\x11\x00'
dqt = b'\xff\xdb' + struct.pack('>H', 67) + b'\0' + bytes([1] * 64)
dht = b'\xff\xc4' + struct.pack('>H', 20) + b'\x00' + bytes([1] + [0] * 15) + b'\x00'
sos = b'\xff\xda' + struct.pack('>HB', 8, 1) + b'\x01\x00\x00\x3f\x00'
open('in/two_sof.jpg', 'wb').write(b'\xff\xd8' + dqt + sof(30000, 30000) + dht + sos + bytes(500) + sof(16, 16) + b'\xff\xd9')
open('in/small.jpg', 'wb').write(b'\xff\xd8' + dqt + sof(16, 16) + dht + sos + bytes(10) + b'\xff\xd9')
EOF
mkdir -p in/bomb_images in/bomb_masks
cp in/frame.png in/bomb_images/a.png
cp in/bomb.tif in/bomb_masks/a.png
for image in two_sof.jpg sparse.jpg bomb.webp; do
  printf '{"images": [{"id": 1, "file_name": "%s"}], "annotations": []}\n' "$image" > "in/coco_${image%.*}.json"
done
# COCO numbers: an RLE count plus 2^32, a polygon vertex at 3e9 (the frame is 640x480).
printf '%s\n' '{"images": [{"id": 1, "file_name": "frame.png", "width": 640, "height": 480}], "annotations": [' \
  '{"id": 7, "image_id": 1, "category_id": 1, "bbox": [0, 0, 2, 480], "segmentation": {"size": [480, 640], "counts": [0, 4294968256, 306240]}}]}' \
  > in/coco_rle_wrap.json
printf '%s\n' '{"images": [{"id": 1, "file_name": "frame.png", "width": 640, "height": 480}], "annotations": [' \
  '{"id": 7, "image_id": 1, "category_id": 1, "bbox": [10, 10, 100, 300], "segmentation": [[10, 10, 3000000000, 10, 100, 300]]}]}' \
  > in/coco_polygon_3e9.json
# imglab numbers: a part at 1e300 (infinite as a float), a box 4294967643 wide (347 as an int).
box="<box top='10' left='10' width='100' height='300'>"
printf "<dataset><images><image file='frame.png'>\n%s<part name='000' x='1e300' y='20'/></box></image></images></dataset>\n" "$box" > in/imglab_1e300.xml
printf "<dataset><images><image file='frame.png'>\n<box top='10' left='10' width='4294967643' height='300'/></image></images></dataset>\n" > in/imglab_wide.xml
hash_inputs

check "forest of 20 bzip2 depth-24 trees (9 KB each, 14 GB within the per-file limits)" 1 \
  "forest24/tree_12.txt.bz2: a depth-24 tree takes the forest of 20 files to 50331645 nodes" \
  capped 1000 20 $D in/frame.png --detector-mode forest --forest in/forest24 --json out/a.json
check "the same forest for agex_eval parts" 1 "forest24/tree_12.txt.bz2: a depth-24 tree takes the forest" \
  capped 1000 20 $E parts --dataset in/dataset --forest in/forest24 --json out/a.json
check "--forest: 10,000 nested empty folders" 1 "deep_forest: folders nested deeper than 16 levels" \
  capped 1000 20 $D in/frame.png --detector-mode forest --forest in/deep_forest --json out/a.json
check "TIFF bomb named .png (32767x32767 1-bit, 134 bytes)" 1 "bomb_masks/a.png: claims a 32767x32767" \
  capped 1000 20 $D in/bomb_masks/a.png --json out/a.json
if [ -x "$BIN/agex_landmarks_train" ]; then
  A=$BIN/agex_annotate
  check "TIFF bomb named .png as an agex_annotate masks mask" 1 "bomb_masks/a.png: claims a 32767x32767" \
    capped 1000 20 $A masks --images in/bomb_images --masks in/bomb_masks --out out/masks.xml
  check "JPEG with a second frame header (SOF) after its scan" 1 "two_sof.jpg: a JPEG with two frame headers \\(SOF\\) that disagree: 30000x30000, then 16x16" \
    capped 1000 20 $A coco --json in/coco_two_sof.json --images in --out out/coco.xml
  # Made after hash_inputs and removed after its case: every check re-hashes the inputs.
  cp in/small.jpg in/sparse.jpg && truncate -s 2200M in/sparse.jpg
  check "a 2.2 GB sparse .jpg" 1 "sparse.jpg: 2306867200 bytes, larger than the 268435456 bytes" \
    capped 1000 20 $A coco --json in/coco_sparse.json --images in --out out/coco.xml
  rm -f in/sparse.jpg
  check "WebP bomb (VP8X canvas 16384x16384)" 1 "bomb.webp: claims a 16384x16384" \
    capped 1000 20 $A coco --json in/coco_bomb.json --images in --out out/coco.xml
  check "COCO RLE count plus 2^32" 1 "coco_rle_wrap.json: frame.png.*RLE count 1 4294968256 is not a whole number in \\[0, 307200\\]" \
    $A coco --json in/coco_rle_wrap.json --images in --out out/coco.xml
  check "COCO polygon vertex at 3e9" 1 "polygon vertex coordinate 3000000000 is not a pixel coordinate" \
    $A coco --json in/coco_polygon_3e9.json --images in --out out/coco.xml
  check "imglab part at x='1e300', agex_landmarks_train" 1 "imglab_1e300.xml: line 2: attribute 'x' of <part> is 1e300, not a pixel coordinate" \
    $BIN/agex_landmarks_train --dataset in/imglab_1e300.xml --out out/shape.dat
  check "the same XML for agex_landmarks_eval" 1 "imglab_1e300.xml: line 2: attribute 'x' of <part> is 1e300" \
    $BIN/agex_landmarks_eval --dataset in/imglab_1e300.xml --model in/shape_predictor_5_landmarks.dat
  check "imglab box width='4294967643'" 1 "imglab_wide.xml: line 2: attribute 'width' of <box> is 4294967643, not a pixel size" \
    $BIN/agex_landmarks_train --dataset in/imglab_wide.xml --out out/shape.dat
fi
