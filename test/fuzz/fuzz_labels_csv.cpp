// Fuzz target: agex::readLabelsCsv (a dataset's labels.csv). Any input must give labels
// or an agex::DatasetError.
#include "fuzz_support.h"

#include <agex/io/dataset.h>

extern "C" int
LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size)
{
  const std::string path = agex::fuzz::writeInput ("labels.csv", data, size);
  try
  {
    const std::vector<agex::PartLabel> labels = agex::readLabelsCsv (path);
    // What was read must write back and read again to the same labels.
    const std::string text = agex::formatLabelsCsv (labels);
    const std::string again = agex::fuzz::writeInput ("labels-again.csv",
                                                      reinterpret_cast<const std::uint8_t *> (text.data ()), text.size ());
    if (agex::readLabelsCsv (again).size () != labels.size ())
      __builtin_trap ();
  }
  catch (const agex::DatasetError &)
  {
  }
  return 0;
}
