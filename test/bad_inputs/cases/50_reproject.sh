# agex_reproject (issue 33): each bad setting is refused by name before anything is read or
# written, the input dataset and unrelated directories are never written over, and frames
# without depth or labels give a defined result.
# Sourced by run_bad_inputs.sh (check, capped, hash_inputs, check_kept, $BIN, $C, in/, out/).

R=$BIN/agex_reproject
"$C" pcd --input in/all_nan_48x64.pcd --output in/ds_all_nan >/dev/null 2>&1
mkdir -p in/reproject_notes
echo "my notes" > in/reproject_notes/notes.txt
hash_inputs
check "agex_reproject: a distance beyond 20 m" 1 "--distance must be 0.3-20 metres, got 50" $R --dataset in/dataset --output out/rp_a --distance 50
check "agex_reproject: --distance and --distance-range together" 1 "give --distance or --distance-range, not both" $R --dataset in/dataset --output out/rp_b --distance 3 --distance-range 3:4
check "agex_reproject: a distance range that is not MIN:MAX" 1 "--distance-range must be MIN:MAX metres" $R --dataset in/dataset --output out/rp_c --distance-range 4-5
check "agex_reproject: a NaN tilt" 1 "--tilt-deg must be 0-80 degrees, got nan" $R --dataset in/dataset --output out/rp_d --tilt-deg nan
check "agex_reproject: no copies" 1 "--copies must be 1-1000, got 0" $R --dataset in/dataset --output out/rp_e --copies 0
check "agex_reproject: an unknown sensor" 1 "unknown --sensor 'nosuch'" $R --dataset in/dataset --output out/rp_f --sensor nosuch
check "agex_reproject: a resolution for the bonn view" 1 "bonn sensor's frames are its 144x176 portrait view" $R --dataset in/dataset --output out/rp_g --sensor bonn --resolution 320x240
check "agex_reproject: a source depth step of 1 m" 1 "--source-depth-step must be auto or 0-0.5 metres, got '1'" $R --dataset in/dataset --output out/rp_h --source-depth-step 1
check "agex_reproject: an unknown floor choice" 1 "--floor must be auto or none, got 'plane'" $R --dataset in/dataset --output out/rp_l --floor plane
check "agex_reproject: a missing dataset" 1 "in/nope: not a dataset directory" $R --dataset in/nope --output out/rp_i
check "agex_reproject: an unknown sequence" 1 "has no sequence 'zz'" $R --dataset in/dataset@zz --output out/rp_j
check "agex_reproject: output inside the input dataset" 1 "output would land inside the input dataset" $R --dataset in/dataset --output in/dataset/moved
check "agex_reproject --force onto a directory of other things" 1 "reproject_notes: is a directory without an agex dataset.json" $R --dataset in/dataset --output in/reproject_notes --force
check "agex_reproject: a distance, but no frame has labels or a person image" 1 "has a person depth .* nothing written" $R --dataset in/dataset --output out/rp_k --distance 3
[ ! -e out/rp_a ] && [ ! -e out/rp_k ] && [ -z "$(ls -a out | grep partial)" ] || { echo "FAILED: a refused agex_reproject left an output" >&2; failures=$((failures + 1)); }
check "agex_reproject: an all-NaN frame" 0 "1 kinect frames .640x480. from 1 frames" $R --dataset in/ds_all_nan --output out/rp_nan --sideways 0.5
check "agex_reproject: a frame without labels, moved sideways, up and tilted" 0 "1 kinect frames" $R --dataset in/dataset --output out/rp_wall --sideways 0.3 --tilt-deg 5 --vertical 0.2
