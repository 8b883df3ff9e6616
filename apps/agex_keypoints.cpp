// agex_keypoints: AGEX interest points of one depth frame.
// Runs the depth pipeline (denoise, mixed pixels, crop, floor, meshes, AGEX) and
// writes the points as JSON and an overlay PNG.

#include <agex/apps/command_line.h>
#include <agex/apps/frame_jobs.h>
#include <agex/apps/output_guard.h>
#include <agex/apps/pipeline_flags.h>
#include <agex/apps/output.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/io/atomic_file.h>
#include <agex/io/frame_io.h>

#include <boost/program_options.hpp>

#include <iostream>

namespace po = boost::program_options;

int
main (int argc, char **argv)
{
  agex::FrameOptions frame_options;
  agex::DepthPipelineParams params;
  std::vector<std::string> vector_flags;
  std::string input, json_path, overlay_path;

  po::options_description general ("agex_keypoints INPUT [options]\n"
                                    "AGEX interest points of a depth frame (.pcd, .png or .u16)");
  general.add_options () ("help,h", "show this help") ("input", po::value (&input), "frame file")
    ("json", po::value (&json_path), "write the points as JSON here")
    ("overlay", po::value (&overlay_path), "write an overlay PNG here");
  po::options_description all;
  all.add (general).add (agex::apps::frameOptionsDescription (frame_options))
     .add (agex::apps::pipelineOptionsDescription (params, vector_flags));
  po::positional_options_description positional;
  positional.add ("input", 1);

  try
  {
    if (!agex::apps::parseCommandLine (argc, argv, all, positional))
      return 0;
    if (input.empty ())
      throw std::runtime_error ("no INPUT frame given (see --help)");
    agex::apps::finishPipelineOptions (vector_flags, params);
    agex::InputFiles read;  // the frame, and the dataset it belongs to, if any
    agex::apps::collectFrameJobs ({input}, read, "agex_keypoints");
    if (!json_path.empty ())
      agex::apps::checkOutputPath (json_path, agex::apps::OutputKind::JsonDocument, read);
    if (!overlay_path.empty ())
      agex::apps::checkOutputPath (overlay_path, agex::apps::OutputKind::Png, read);

    const agex::Frame frame = agex::loadFrame (input, frame_options);
    const agex::DepthPipelineResult result = agex::runDepthPipeline (frame.cloud, params);

    const nlohmann::json doc = agex::apps::keypointsJson (input, *frame.cloud, result);
    {
      const agex::apps::OutputSetClaim claim ({json_path, overlay_path});  // written as one set
      if (!json_path.empty ())
        agex::apps::writeJson (json_path, doc);
      if (!overlay_path.empty ())
        agex::apps::writePng (overlay_path,
                              // on the working frame, whose pixels the meshes and points are
                              agex::apps::renderOverlay (result.frame ? *result.frame : *frame.cloud, result.meshes,
                                                         result.interest_points));
    }

    // The summary goes to standard error: without --json, standard output is the JSON alone.
    std::cerr << input << ": " << result.meshes.size () << " meshes, " << result.interest_points.size ()
              << " interest points, " << result.ms.back ().second << " ms\n";
    if (json_path.empty ())
      std::cout << doc.dump (2) << "\n";
    return 0;
  }
  catch (const std::exception &e)
  {
    std::cerr << "agex_keypoints: error: " << e.what () << "\n";
    return 1;
  }
}
