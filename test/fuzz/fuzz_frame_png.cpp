// Fuzz target: agex::loadFrame on a .png file.
#define AGEX_FUZZ_FRAME_FILE "frame.png"
#include "fuzz_frame.inc"
