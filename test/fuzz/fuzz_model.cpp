// Fuzz target: agex::PatchClassifier::load (model files). Any input must give a usable
// classifier or an agex::ModelError; a loaded model must classify a patch.
#include "fuzz_support.h"

#include <agex/classification/patch_classifier.h>

#include <vector>

extern "C" int
LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size)
{
  const std::string path = agex::fuzz::writeInput ("model.yml", data, size);
  try
  {
    const agex::PatchClassifier model = agex::PatchClassifier::load (path);
    agex::DepthPatch patch;
    patch.size = model.patchGeometry ().size;
    patch.metres_per_cell = model.patchGeometry ().extent / patch.size;
    std::vector<float> margins (model.classes ()), confidences (model.classes ());
    model.classify (patch, margins.data (), confidences.data ());
  }
  catch (const agex::ModelError &)
  {
  }
  return 0;
}
