// Fuzz target: agex::readImglabDataset (dlib/imglab XML of the 2D landmark module). Any
// input must give a dataset or a std::runtime_error naming the file.
#include "fuzz_support.h"

#include <agex/landmarks/imglab_dataset.h>

#include <stdexcept>

extern "C" int
LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size)
{
  const std::string path = agex::fuzz::writeInput ("dataset.xml", data, size);
  try
  {
    const agex::ImglabDataset dataset = agex::readImglabDataset (path);
    // What was read must write back and read again to the same images and boxes.
    const std::string text = agex::imglabDatasetXml (dataset);
    const std::string again = agex::fuzz::writeInput ("dataset-again.xml",
                                                      reinterpret_cast<const std::uint8_t *> (text.data ()), text.size ());
    const agex::ImglabDataset reread = agex::readImglabDataset (again);
    if (reread.images.size () != dataset.images.size ())
      __builtin_trap ();
    for (std::size_t i = 0; i < dataset.images.size (); ++i)
      if (reread.images[i].boxes.size () != dataset.images[i].boxes.size ())
        __builtin_trap ();
  }
  catch (const std::runtime_error &)
  {
  }
  return 0;
}
