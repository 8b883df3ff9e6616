#pragma once
// agex_convert's flags: the mode, inputs and output, the Bonn conversion's settings and the
// frame input's, checked before anything is read.

#include <agex/io/bonn.h>
#include <agex/io/frame_io.h>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
struct ConvertFlags
{
  std::string mode;  ///< bonn, u16 or pcd
  std::vector<std::string> inputs;
  std::string output;
  bool force = false;
  std::string view = "portrait", sequences, sensor = "kinect";
  int label_radius = 6;
  float depth_band = 0.05f;
  FrameOptions frame_options;
};

/** \brief Parses agex_convert's command line into flags and checks the flags every mode
  * needs. \return false when --help was given (the help is printed)
  * \throws std::runtime_error or boost::program_options::error naming the flag */
bool parseConvertFlags (int argc, char **argv, ConvertFlags &flags);

/** \brief The Bonn conversion the flags ask for (--view, --sequences, --label-radius,
  * --label-depth-band, the frame options). \throws std::runtime_error on a bad --view */
BonnConversionParams bonnConversionParams (const ConvertFlags &flags);
}  // namespace apps
}  // namespace agex
