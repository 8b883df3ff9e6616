// Fuzz target: agex::loadFrame on a raw .u16 file. The first two bytes choose the
// frame size the caller claims (--width/--height: 0..15 x 0..15, often wrong), the rest
// is the file. Any input must give a frame or an agex::FrameError.
#include "fuzz_support.h"

#include <agex/io/frame_io.h>

extern "C" int
LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size)
{
  if (size < 2)
    return 0;
  agex::FrameOptions options;
  options.width = data[0] % 16;
  options.height = data[1] % 16;
  const std::string path = agex::fuzz::writeInput ("frame.u16", data + 2, size - 2);
  try
  {
    const agex::Frame frame = agex::loadFrame (path, options);
    if (static_cast<int> (frame.cloud->width) != options.width ||
        static_cast<int> (frame.cloud->height) != options.height)
      __builtin_trap ();
  }
  catch (const agex::FrameError &)
  {
  }
  return 0;
}
