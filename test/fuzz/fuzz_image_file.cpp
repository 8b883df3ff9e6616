// Fuzz target: agex::readImageFile (io/image_header.h), the checked image read of the 2D
// module and of depth PNGs: the format by content, the size from the header, then OpenCV's
// decoder. Any input must give an image within kMaxFramePixels or an agex::FrameError.
#include "fuzz_support.h"

#include <agex/io/frame_io.h>
#include <agex/io/image_header.h>

#include <opencv2/imgcodecs.hpp>

extern "C" int
LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size)
{
  const std::string path = agex::fuzz::writeInput ("image", data, size);
  try
  {
    const cv::Mat image = agex::readImageFile (path, cv::IMREAD_UNCHANGED);
    if (image.empty () || image.total () > agex::kMaxFramePixels)
      __builtin_trap ();
  }
  catch (const agex::FrameError &)
  {
  }
  return 0;
}
