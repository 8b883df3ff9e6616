# agex_synth's settings (issue 32): each bad setting is refused by name before anything is
# rendered, and a config file is bounded and named in its errors.
# Sourced by run_bad_inputs.sh (check, capped, hash_inputs, $BIN, in/, out/).

S="$BIN/agex_synth --motion in/absent.bvh --frames 2 --sensor kinect"
printf 'layout = whole\nmax-pitch = 120\n' > in/synth_bad_pitch.cfg
printf 'layout = whole\nno-such-setting = 1\n' > in/synth_unknown.cfg
head -c 70000 /dev/zero | tr '\0' '#' > in/synth_huge.cfg
hash_inputs
check "agex_synth: an unknown layout" 1 "unknown --layout 'room'" $S --layout room --output out/synth_a
check "agex_synth: a pitch beyond 89 degrees" 1 "min-pitch and --max-pitch must satisfy" $S --layout whole --max-pitch 95 --output out/synth_b
check "agex_synth: a share above 1" 1 "close-range-share must be 0-1" $S --layout whole --close-range-share 2 --output out/synth_c
check "agex_synth: a resolution that is not WxH" 1 "resolution must be WxH" $S --resolution 640 --output out/synth_d
check "agex_synth: a resolution of another aspect ratio" 1 "does not keep the sensor's aspect ratio" $S --resolution 320x200 --output out/synth_e
check "agex_synth: a resolution for the bonn view" 1 "144x176 portrait view; no other frame size" $BIN/agex_synth --motion in/absent.bvh --frames 2 --sensor bonn --resolution 320x240 --output out/synth_f
check "agex_synth: a config file's bad value" 1 "min-pitch and --max-pitch must satisfy" $S --config in/synth_bad_pitch.cfg --output out/synth_g
check "agex_synth: a config file's unknown setting" 1 "synth_unknown.cfg: .*no-such-setting" $S --config in/synth_unknown.cfg --output out/synth_h
check "agex_synth: a config file of 70 KB" 1 "synth_huge.cfg: 70000 bytes, more than a config file" $S --config in/synth_huge.cfg --output out/synth_i
check "agex_synth: a missing config file" 1 "absent.cfg: cannot read it" $S --config in/absent.cfg --output out/synth_j
check "agex_synth: an even correlation window" 1 "kinect-window must be an odd 1-31 pixels" $S --kinect-window 4 --output out/synth_k
# --pose-report may replace only a PNG agex wrote: a user's picture (or a pose file) stays.
cp in/frame.png in/users_picture.png
hash_inputs
check "agex_synth --pose-report over a user's PNG" 1 "users_picture.png" $BIN/agex_synth --procedural-poses 5 --pose-report in/users_picture.png
