#pragma once
// The flags of the frame input and of the depth pipeline's settings
// (agex::DepthPipelineParams), shared by every depth app.

#include <agex/detection/depth_pipeline.h>
#include <agex/io/frame_io.h>

#include <boost/program_options/options_description.hpp>

#include <string>
#include <vector>

namespace agex
{
namespace apps
{
/** Flags for the frame input (--fx --fy --cx --cy --depth-scale --width --height). */
boost::program_options::options_description frameOptionsDescription (FrameOptions &options);

/** Flags for the pipeline stages; values land in params after notify(). */
boost::program_options::options_description pipelineOptionsDescription (DepthPipelineParams &params,
                                                                        std::vector<std::string> &storage);

/** The flag that sets a pipeline setting (its DepthPipelineParams key), e.g. "--mixed-window". */
std::string pipelineFlagName (const std::string &key);

/** Parses the "x,y,z" strings collected by pipelineOptionsDescription into params and
  * checks every setting with the library's ranges (DepthPipelineParams::validate).
  * \throws std::runtime_error or std::invalid_argument naming the flag */
void finishPipelineOptions (const std::vector<std::string> &storage, DepthPipelineParams &params);
}  // namespace apps
}  // namespace agex
