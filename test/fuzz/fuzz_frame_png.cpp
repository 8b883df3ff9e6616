// Fuzz target: agex::loadFrame on a .png file. Any input must give a frame or an
// agex::FrameError, nothing else (no crash, no other exception, no leak).
#include "fuzz_support.h"

#include <agex/common/frame_io.h>

extern "C" int
LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size)
{
  const std::string path = agex::fuzz::writeInput ("frame.png", data, size);
  try
  {
    const agex::Frame frame = agex::loadFrame (path);
    if (!frame.cloud || !frame.cloud->isOrganized () || frame.cloud->size () != std::size_t (frame.cloud->width) * frame.cloud->height)
      __builtin_trap ();  // loadFrame promises an organized cloud
  }
  catch (const agex::FrameError &)
  {
  }
  return 0;
}
