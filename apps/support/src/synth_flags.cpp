#include <agex/apps/synth_flags.h>

#include <agex/apps/command_line.h>

#include <boost/program_options.hpp>

#include <charconv>
#include <filesystem>
#include <fstream>
#include <iostream>
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

/** "WxH" into width and height, each 16-4096. */
void
parseResolution (const std::string &text, int &width, int &height)
{
  const auto x = text.find ('x');
  auto number = [&] (const std::string &part, int &value) {
    const auto result = std::from_chars (part.data (), part.data () + part.size (), value);
    return result.ec == std::errc () && result.ptr == part.data () + part.size () && value >= 16 && value <= 4096;
  };
  if (x == std::string::npos || !number (text.substr (0, x), width) || !number (text.substr (x + 1), height))
    throw std::runtime_error ("--resolution must be WxH with 16-4096 pixels a side (e.g. 320x240), got '" + text + "'");
}

/** A config file's flags; the file is read whole, at most 64 KiB, and named in every error. */
po::parsed_options
parseSynthConfigFile (const std::string &path, const po::options_description &options)
{
  constexpr std::uintmax_t kMaxConfigBytes = 64 * 1024;
  std::error_code error;
  const auto size = std::filesystem::file_size (path, error);
  if (error || !std::filesystem::is_regular_file (path))
    throw std::runtime_error ("--config " + path + ": cannot read it (not a regular file)");
  if (size > kMaxConfigBytes)
    throw std::runtime_error ("--config " + path + ": " + std::to_string (size) + " bytes, more than a config file of " +
                              std::to_string (kMaxConfigBytes) + " holds");
  std::ifstream in (path);
  if (!in)
    throw std::runtime_error ("--config " + path + ": cannot open it");
  try
  {
    return po::parse_config_file (in, options);
  }
  catch (const po::error &e)
  {
    throw std::runtime_error ("--config " + path + ": " + e.what ());
  }
}
}  // namespace

bool
parseSynthFlags (int argc, char **argv, SynthFlags &flags)
{
  SynthOptions &options = flags.options;
  po::options_description general (
      "agex_synth --motion FILE... --frames N --sensor sr4000|kinect|kinect2|bonn --seed S --output DIR [options]\n"
      "Renders labelled depth frames of people posed by BVH motion capture and writes an agex dataset");
  general.add_options () ("help,h", "show this help")
    ("motion", po::value (&options.motion_files)->multitoken (), "BVH motion files (CMU skeletons)")
    ("frames", po::value (&flags.frames), "number of frames to render")
    ("sensor", po::value (&flags.sensor)->default_value (flags.sensor), "sensor model: sr4000 (144x176 time of flight), kinect (640x480 structured light), kinect2 (512x424 time "
     "of flight) or bonn (kinect in the Bonn frames' 8-bit depth steps and 144x176 portrait view)")
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
    ("min-height", po::value (&options.min_height)->default_value (options.min_height, "0.8; 0.6 with --layout whole"),
     "camera above the floor, metres")
    ("max-height", po::value (&options.max_height)->default_value (options.max_height, "1.6; 2.5 with --layout whole"),
     "camera above the floor, metres")
    ("layout", po::value (&flags.layout)->default_value (flags.layout),
     "aimed: the camera aimed at the people, level; whole: a camera of its own height, pitch and roll and 1 to "
     "--people people anywhere in its view (some cut by the borders, some close-range upper bodies without a room, "
     "some with the background removed)")
    ("min-pitch", po::value (&options.min_pitch_deg)->default_value (options.min_pitch_deg),
     "whole scenes: camera pitch, degrees, up positive")
    ("max-pitch", po::value (&options.max_pitch_deg)->default_value (options.max_pitch_deg), "whole scenes: camera pitch")
    ("max-roll", po::value (&options.max_roll_deg)->default_value (options.max_roll_deg),
     "whole scenes: camera roll within +-this, degrees")
    ("close-range-share", po::value (&options.close_range_share)->default_value (options.close_range_share),
     "whole scenes: share of frames showing one upper body at 0.7-1.6 m without a room")
    ("background-removed-share",
     po::value (&options.background_removed_share)->default_value (options.background_removed_share),
     "whole scenes: share of the other frames with every pixel off the people invalid")
    ("border-share", po::value (&options.border_share)->default_value (options.border_share),
     "whole scenes: how far beyond the image's edges a torso may stand, as a share of its width and height")
    ("resolution", po::value (&flags.resolution),
     "frame size WxH with the sensor's field of view, e.g. 320x240 for a kinect frame at half resolution")
    ("kinect-window", po::value (&options.kinect_window)->default_value (0),
     "kinect and bonn: the correlation window's side at 640x480, odd 1-31 pixels (thins far limbs, rounds "
     "silhouettes; doc/sensors.md); 0: the model's default, off")
    ("clutter", po::value (&options.clutter)->default_value (options.clutter), "desks, chairs, shelves and boxes (1 or 0)")
    ("config", po::value (&flags.config),
     "a file of flag = value lines (the flags above without their dashes); flags on the command line win")
    ("body-mesh", po::value (&options.body_mesh),
     "MakeHuman directory (base.obj, default.mhskel, default_weights.mhw, e.g. ../shared/data/makehuman): skinned mesh "
     "bodies instead of capsules")
    ("pose-dir", po::value (&options.pose_dirs)->composing (),
     "directory of BVH files (Character Creator CC_Base_* or CMU skeletons) for the pose bank; repeatable. With "
     "--pose-dir or --procedural-poses, frames draw their pose from one bank of the --motion files, these and the "
     "procedural poses")
    ("procedural-poses", po::value (&options.procedural_poses)->default_value (0),
     "procedural poses in the pose bank, 0-100000 (hands on hips, arms raised, pointing, seated, ...)")
    ("thin-poses", po::value (&options.thin_poses)->default_value (0.0),
     "keep only pose bank poses farther apart than this, metres 0-1 (largest joint distance; 0 keeps all)")
    ("pose-report", po::value (&flags.pose_report),
     "write a PNG of the pose bank's hand positions and print its sizes and spread; without --frames, only that")
    ("body-shapes", po::bool_switch (&options.body_shapes),
     "with --body-mesh: give each subject its own MakeHuman body shape (gender, age, muscle, weight, height; "
     "targets/macrodetails of the --body-mesh directory), 1.5-2.0 m tall, slim to heavy")
    ("clothes", po::bool_switch (&options.clothes),
     "with --body-mesh: dress each subject (sleeves and trousers 0.3-2.5 cm, shoes 0.8-2.5 cm, hands 0.2-1 cm, "
     "hair 0-3 cm thicker than the bare mesh), drawn from the seed")
    ("colour", po::bool_switch (&options.colour),
     "also paint each frame in colour (random clothes, room and light; sr4000 and kinect): XYZRGBA frames for "
     "agex_annotate rgbd; the depth stays the same");

  // The command line first, so that its flags win over the config file's.
  po::variables_map given;
  const int style = po::command_line_style::default_style & ~po::command_line_style::allow_guessing;
  po::store (po::command_line_parser (argc, argv).options (general).style (style).run (), given);
  if (given.count ("help"))
  {
    std::cout << general << "\n";
    return false;
  }
  if (given.count ("config"))
    po::store (parseSynthConfigFile (given["config"].as<std::string> (), general), given);
  po::notify (given);
  if (options.motion_files.empty () && options.pose_dirs.empty () && options.procedural_poses == 0)
    throw std::runtime_error ("no --motion BVH files, --pose-dir or --procedural-poses given (see --help)");
  if (options.procedural_poses < 0 || options.procedural_poses > 100000)
    throw std::runtime_error ("--procedural-poses must be 0-100000, got " + std::to_string (options.procedural_poses));
  if (!(options.thin_poses >= 0.0 && options.thin_poses <= 1.0))
    throw std::runtime_error ("--thin-poses must be 0-1 metres, got " + std::to_string (options.thin_poses));
  if (!flags.pose_report.empty () && options.pose_dirs.empty () && options.procedural_poses == 0)
    throw std::runtime_error ("--pose-report needs a pose bank (--pose-dir or --procedural-poses)");
  flags.report_only = !flags.pose_report.empty () && flags.frames == 0 && flags.output.empty ();
  if (flags.report_only)
    return true;
  if (flags.frames < 1)
    throw std::runtime_error ("--frames must be at least 1");
  if (flags.output.empty ())
    throw std::runtime_error ("no --output directory given");
  if (options.people < 1 || options.people > 4)
    throw std::runtime_error ("--people must be 1-4, got " + std::to_string (options.people));
  if (!parseSynthSensor (flags.sensor, options.sensor))
    throw std::runtime_error ("unknown --sensor '" + flags.sensor + "' (expected " + synthSensorNames () + ")");
  options.bvh_scale = parseBvhScale (flags.bvh_scale);
  if (!parseSynthLayout (flags.layout, options.layout))
    throw std::runtime_error ("unknown --layout '" + flags.layout + "' (expected aimed or whole)");
  if (options.kinect_window != 0 && (options.kinect_window < 1 || options.kinect_window > 31 || options.kinect_window % 2 == 0))
    throw std::runtime_error ("--kinect-window must be an odd 1-31 pixels (or 0: off), got " +
                              std::to_string (options.kinect_window));
  if (!flags.resolution.empty ())
    parseResolution (flags.resolution, options.width, options.height);
  auto share = [] (double value, const char *flag, double most) {
    if (!(value >= 0.0 && value <= most))
      throw std::runtime_error (std::string ("--") + flag + " must be 0-" + (most == 1.0 ? "1" : "0.5") + ", got " +
                                std::to_string (value));
  };
  share (options.close_range_share, "close-range-share", 1.0);
  share (options.background_removed_share, "background-removed-share", 1.0);
  share (options.border_share, "border-share", 0.5);
  if (!(options.min_pitch_deg >= -89.0 && options.max_pitch_deg <= 89.0 && options.min_pitch_deg <= options.max_pitch_deg))
    throw std::runtime_error ("--min-pitch and --max-pitch must satisfy -89 <= min <= max <= 89 degrees");
  if (!(options.max_roll_deg >= 0.0 && options.max_roll_deg <= 90.0))
    throw std::runtime_error ("--max-roll must be 0-90 degrees");
  if (!(options.min_distance >= 0.0 && options.max_distance <= 20.0 && options.min_height >= 0.0 &&
        options.max_height <= 10.0))
    throw std::runtime_error ("--min/max-distance must lie in 0-20 m and --min/max-height in 0-10 m");
  return true;
}
}  // namespace apps
}  // namespace agex
