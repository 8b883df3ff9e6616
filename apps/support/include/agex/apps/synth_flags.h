#pragma once
// agex_synth's flags: the motion, the frames, the sensor, the scene and the output, checked
// before anything is read.

#include <agex/simulation/synthetic_scene.h>

#include <string>

namespace agex
{
namespace apps
{
struct SynthFlags
{
  SynthOptions options;  ///< --bvh-scale and --sensor parsed into it
  std::string sensor = "sr4000";
  std::string bvh_scale = "auto";
  std::string layout = "aimed";
  std::string resolution;  ///< WxH, empty: the sensor's own
  std::string config;      ///< a file of flag = value lines
  std::string output;
  int frames = 0;
  bool force = false;
};

/** \brief Parses agex_synth's command line into flags and checks them.
  * \return false when --help was given (the help is printed)
  * \throws std::runtime_error or boost::program_options::error naming the flag */
bool parseSynthFlags (int argc, char **argv, SynthFlags &flags);
}  // namespace apps
}  // namespace agex
