#include <agex/apps/synth_flags.h>

#include <agex/apps/command_line.h>

#include <boost/program_options.hpp>

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
namespace
{
double
parseBvhScale (const std::string &text)
{
  if (text == "auto")
    return 0.0;
  double value = 0.0;
  const auto result = std::from_chars (text.data (), text.data () + text.size (), value);
  if (result.ec != std::errc () || result.ptr != text.data () + text.size () || !std::isfinite (value) || value <= 0)
    throw std::runtime_error ("--bvh-scale must be 'auto' or a positive number of metres per BVH unit, got '" + text +
                              "'");
  return value;
}
}  // namespace

bool
parseSynthFlags (int argc, char **argv, SynthFlags &flags)
{
  SynthOptions &options = flags.options;
  po::options_description general (
      "agex_synth --motion FILE... --frames N --sensor sr4000|kinect|bonn --seed S --output DIR [options]\n"
      "Renders labelled depth frames of people posed by BVH motion capture and writes an agex dataset");
  general.add_options () ("help,h", "show this help")
    ("motion", po::value (&options.motion_files)->multitoken (), "BVH motion files (CMU skeletons)")
    ("frames", po::value (&flags.frames), "number of frames to render")
    ("sensor", po::value (&flags.sensor)->default_value (flags.sensor), "sensor model: sr4000 (144x176 time of flight), kinect (640x480) or bonn (kinect in the Bonn frames' 8-bit "
     "depth steps and 144x176 portrait view)")
    ("seed", po::value (&options.seed)->default_value (options.seed), "random seed; the same seed gives the same bytes")
    ("output", po::value (&flags.output), "dataset directory to write")
    ("force", po::bool_switch (&flags.force), "replace an existing output directory")
    ("bvh-scale", po::value (&flags.bvh_scale)->default_value (flags.bvh_scale),
     "metres per BVH unit, or auto (by rest-pose height: metres, CMU units x0.056444, cm, mm)")
    ("subjects", po::value (&options.subjects)->default_value (options.subjects), "body shapes drawn from the seed")
    ("people", po::value (&options.people)->default_value (options.people),
     "people per frame, 1-4; several stand at random distances and bearings in front of the camera, partly hiding "
     "each other")
    ("min-distance", po::value (&options.min_distance)->default_value (options.min_distance, "1.5; 0.8 with --people 2-4"),
     "camera to body (each person's), metres")
    ("max-distance", po::value (&options.max_distance)->default_value (options.max_distance, "3.5; 6 with --people 2-4"),
     "camera to body (each person's), metres")
    ("min-height", po::value (&options.min_height)->default_value (options.min_height, "0.8"), "camera above the floor, metres")
    ("max-height", po::value (&options.max_height)->default_value (options.max_height, "1.6"), "camera above the floor, metres")
    ("body-mesh", po::value (&options.body_mesh),
     "MakeHuman directory (base.obj, default.mhskel, default_weights.mhw, e.g. ../shared/data/makehuman): skinned mesh "
     "bodies instead of capsules")
    ("body-shapes", po::bool_switch (&options.body_shapes),
     "with --body-mesh: give each subject its own MakeHuman body shape (gender, age, muscle, weight, height; "
     "targets/macrodetails of the --body-mesh directory), 1.5-2.0 m tall, slim to heavy")
    ("colour", po::bool_switch (&options.colour),
     "also paint each frame in colour (random clothes, room and light; sr4000 and kinect): XYZRGBA frames for "
     "agex_annotate rgbd; the depth stays the same");

  if (!parseCommandLine (argc, argv, general, po::positional_options_description ()))
    return false;
  if (options.motion_files.empty ())
    throw std::runtime_error ("no --motion BVH files given (see --help)");
  if (flags.frames < 1)
    throw std::runtime_error ("--frames must be at least 1");
  if (flags.output.empty ())
    throw std::runtime_error ("no --output directory given");
  if (options.people < 1 || options.people > 4)
    throw std::runtime_error ("--people must be 1-4, got " + std::to_string (options.people));
  if (!parseSynthSensor (flags.sensor, options.sensor))
    throw std::runtime_error ("unknown --sensor '" + flags.sensor + "' (expected sr4000, kinect or bonn)");
  options.bvh_scale = parseBvhScale (flags.bvh_scale);
  return true;
}
}  // namespace apps
}  // namespace agex
