#pragma once
// agex_detect's flags: inputs or a device, outputs, the shards of a batch run, the detector
// and the frame input, checked before anything is read.

#include <agex/apps/batch_runs.h>
#include <agex/apps/detector_flags.h>
#include <agex/io/frame_io.h>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
struct DetectFlags
{
  std::vector<std::string> inputs;  ///< frame files, directories of frames, agex datasets
  std::string json_path, overlay_path, parts_overlay_path;
  float min_confidence = 0.5f;  ///< detections drawn on the overlay and printed
  int jobs = 1;
  Shard shard;                           ///< --shard K/N
  std::vector<std::string> merge_parts;  ///< --merge: join these parts into json_path
  std::string device;                    ///< --device: a live source instead of inputs
  double fps = 30.0;                     ///< of --device replay:PATH
  DetectorChoice detector;
  FrameOptions frame_options;
};

/** \brief Parses agex_detect's command line into flags and checks them (--merge takes no
  * input; otherwise inputs or --device, not both, --jobs and --shard).
  * \return false when --help was given (the help is printed)
  * \throws std::runtime_error or boost::program_options::error naming the flag */
bool parseDetectFlags (int argc, char **argv, DetectFlags &flags);
}  // namespace apps
}  // namespace agex
