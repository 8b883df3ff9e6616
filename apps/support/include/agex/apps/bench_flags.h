#pragma once
// agex_bench's flags: frames or a dataset, the repeats, the detector, the frame input and the
// depth pipeline, checked before anything is read.

#include <agex/apps/detector_flags.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/io/frame_io.h>

#include <algorithm>
#include <string>
#include <thread>
#include <vector>

namespace agex
{
namespace apps
{
struct BenchFlags
{
  std::vector<std::string> inputs;  ///< frame files (none: the bundled frame)
  std::string dataset_spec;         ///< DIR[@SEQ,...]: time the detector on its frames instead
  std::string json_path;
  std::string compare_with;  ///< another build directory: alternate runs of both and compare
  int rounds = 5;            ///< alternating rounds of --compare-with
  bool keyframes_only = false, no_portrait = false;
  int k = 20, repeat = 30, passes = 3;
  long long memory_frames = 0;  ///< with dataset_spec: frames of the resident-memory run (0: none)
  int jobs = static_cast<int> (std::clamp (std::thread::hardware_concurrency (), 1u, 1024u));
  DetectorChoice detector;
  FrameOptions frame_options;
  DepthPipelineParams params;
};

/** \brief Parses agex_bench's command line into flags and checks them.
  * \return false when --help was given (the help is printed)
  * \throws std::runtime_error or boost::program_options::error naming the flag */
bool parseBenchFlags (int argc, char **argv, BenchFlags &flags);
}  // namespace apps
}  // namespace agex
