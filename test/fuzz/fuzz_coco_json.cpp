// Fuzz target: agex::readCocoPeople (COCO person annotations of the 2D module), then every
// person's mask (agex::cocoPersonMask) on a 64x48 image. Any input must give people and
// masks or a std::runtime_error; numbers are range-checked into their types, never cast.
#include "fuzz_support.h"

#include <agex/landmarks/annotation_sources.h>

#include <stdexcept>

extern "C" int
LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size)
{
  const std::string path = agex::fuzz::writeInput ("coco.json", data, size);
  try
  {
    for (const agex::CocoImage &image : agex::readCocoPeople (path))
      for (const agex::CocoPerson &person : image.people)
      {
        try
        {
          const cv::Mat mask = agex::cocoPersonMask (person, cv::Size (64, 48), "fuzz");
          if (!mask.empty () && mask.size () != cv::Size (64, 48))
            __builtin_trap ();
        }
        catch (const std::runtime_error &)
        {
        }
      }
  }
  catch (const std::runtime_error &)
  {
  }
  return 0;
}
