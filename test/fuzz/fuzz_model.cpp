// Fuzz target: agex::PatchClassifier::load (model files). Any input must give a usable
// classifier or an agex::ModelError; a loaded model must classify a patch. And the nesting
// pre-scan must be a bound: on any input it lets through that OpenCV's YAML parser accepts,
// the parsed tree is never deeper than agex::yamlNestingBound says (else a deeper, crashing
// file could slip past it).
#include "fuzz_support.h"

#include <agex/classification/patch_classifier.h>

#include <opencv2/core.hpp>

#include <cstdio>
#include <cstdlib>
#include <utility>
#include <vector>

namespace
{
std::size_t
treeDepth (const cv::FileNode &root)
{
  std::size_t deepest = 0;
  std::vector<std::pair<cv::FileNode, std::size_t>> stack{{root, 1}};
  while (!stack.empty ())
  {
    const auto [node, depth] = stack.back ();
    stack.pop_back ();
    deepest = std::max (deepest, depth);
    if (node.isMap () || node.isSeq ())
      for (cv::FileNodeIterator it = node.begin (); it != node.end (); ++it)
        stack.push_back ({*it, depth + 1});
  }
  return deepest;
}

void
checkNestingBound (const std::string &yaml)
{
  const std::size_t bound = agex::yamlNestingBound (yaml);
  if (bound > agex::kMaxModelNesting || yaml.find ("!!binary") != std::string::npos)
    return;  // refused before parsing (PatchClassifier::load)
  try
  {
    cv::FileStorage fs (yaml, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened ())
      return;
    const std::size_t depth = treeDepth (fs.root ());
    if (depth > bound)
    {
      std::fprintf (stderr, "yamlNestingBound %zu, but OpenCV built a tree %zu deep\n", bound, depth);
      std::abort ();
    }
  }
  catch (const std::exception &)
  {
  }
}
}  // namespace

extern "C" int
LLVMFuzzerTestOneInput (const std::uint8_t *data, std::size_t size)
{
  checkNestingBound (std::string (reinterpret_cast<const char *> (data), size));
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
