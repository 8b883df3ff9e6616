#pragma once
// agex_reproject's flags: the input dataset, the moves, the target sensor and the output,
// checked before anything is read.

#include <agex/simulation/dataset_reprojection.h>

#include <string>

namespace agex
{
namespace apps
{
struct ReprojectFlags
{
  DatasetReprojectionOptions options;  ///< the moves, sensor and mesh settings parsed into it
  std::string dataset_spec;            ///< DIR[@SEQ,...]
  std::string output;
  bool force = false, keyframes_only = false;
  std::string sensor = "kinect";
  std::string resolution;                ///< WxH, empty: the sensor's own
  /** The source frames' fixed depth step: "auto" (depthQuantumOf the dataset) or metres. */
  std::string source_depth_step = "auto";
  bool source_depth_step_auto = true;
  /** "auto": each frame's floor found (agex::PersonSegmentation) and rendered as a plane;
    * "none": only what the frames show. */
  std::string floor = "auto";
};

/** \brief Parses agex_reproject's command line into flags and checks every value's range.
  * \return false when --help was given (the help is printed)
  * \throws std::runtime_error or boost::program_options::error naming the flag */
bool parseReprojectFlags (int argc, char **argv, ReprojectFlags &flags);
}  // namespace apps
}  // namespace agex
