// Fuzz target: agex::loadFrame on a .pcd file.
#define AGEX_FUZZ_FRAME_FILE "frame.pcd"
#include "fuzz_frame.inc"
