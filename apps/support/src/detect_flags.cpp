#include <agex/apps/detect_flags.h>

#include <agex/apps/command_line.h>
#include <agex/apps/pipeline_flags.h>

#include <boost/program_options.hpp>

#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
bool
parseDetectFlags (int argc, char **argv, DetectFlags &flags)
{
  std::string shard;
  po::options_description general ("agex_detect INPUT... [options]\n"
                                    "Heads, hands and feet in depth frames (.pcd, .png, .u16, directories, datasets)");
  general.add_options () ("help,h", "show this help") ("input", po::value (&flags.inputs)->multitoken (), "inputs")
    ("json", po::value (&flags.json_path), "one frame: JSON document; several: JSON lines, one per frame (resumable)")
    ("overlay", po::value (&flags.overlay_path), "overlay PNG (one frame only)")
    ("parts-overlay", po::value (&flags.parts_overlay_path),
     "the forest's part map over the depth frame as PNG (one frame only; needs --forest)")
    ("min-confidence", po::value (&flags.min_confidence)->default_value (flags.min_confidence, "0.5")->notifier ([] (float v) {
       if (!(v >= 0.f && v <= 1.f))
         throw std::runtime_error ("--min-confidence must lie in [0, 1]");
     }),
     "detections drawn on the overlay and printed")
    ("jobs", po::value (&flags.jobs)->default_value (flags.jobs), "frames processed in parallel")
    ("shard", po::value (&shard), "K/N: only the K-th (0-based) of N equal parts of the frames, for job arrays")
    ("merge", po::value (&flags.merge_parts)->multitoken (), "join the --json parts of --shard runs into --json, in input order")
    ("device", po::value (&flags.device), "openni2, openni2:URI or replay:PATH: process a live source's frames as they arrive")
    ("fps", po::value (&flags.fps)->default_value (flags.fps), "frames per second of --device replay:PATH");
  po::options_description all;
  all.add (general).add (detectorOptionsDescription (flags.detector, kBundledModelFile))
     .add (frameOptionsDescription (flags.frame_options));
  po::positional_options_description positional;
  positional.add ("input", -1);

  if (!parseCommandLine (argc, argv, all, positional))
    return false;
  if (!flags.merge_parts.empty () && !flags.inputs.empty ())
    throw std::runtime_error ("--merge takes the parts, and no INPUT");
  if (!flags.merge_parts.empty ())
    return true;
  if (!flags.device.empty () && !flags.inputs.empty ())
    throw std::runtime_error ("--device is the input: give no INPUT with it");
  if (flags.inputs.empty () && flags.device.empty ())
    throw std::runtime_error ("no INPUT given (see --help)");
  if (flags.jobs < 1)
    throw std::runtime_error ("--jobs must be at least 1");
  flags.shard = shard.empty () ? Shard () : parseShard (shard);
  return true;
}
}  // namespace apps
}  // namespace agex
