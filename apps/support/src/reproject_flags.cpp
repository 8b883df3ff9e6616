#include <agex/apps/reproject_flags.h>

#include <agex/apps/command_line.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
namespace
{
/** The whole of text as a finite number, or false. */
bool
number (const std::string &text, double &value)
{
  const auto result = std::from_chars (text.data (), text.data () + text.size (), value);
  return result.ec == std::errc () && result.ptr == text.data () + text.size () && std::isfinite (value);
}

void
checkRange (double value, double lo, double hi, const char *flag, const char *unit)
{
  if (value >= lo && value <= hi)
    return;
  std::ostringstream message;
  message << "--" << flag << " must be " << lo << "-" << hi << " " << unit << ", got " << value;
  throw std::runtime_error (message.str ());
}

/** "WxH" into width and height, each 16-4096. */
void
parseResolution (const std::string &text, int &width, int &height)
{
  const auto x = text.find ('x');
  auto whole = [&] (const std::string &part, int &value) {
    const auto result = std::from_chars (part.data (), part.data () + part.size (), value);
    return result.ec == std::errc () && result.ptr == part.data () + part.size () && value >= 16 && value <= 4096;
  };
  if (x == std::string::npos || !whole (text.substr (0, x), width) || !whole (text.substr (x + 1), height))
    throw std::runtime_error ("--resolution must be WxH with 16-4096 pixels a side (e.g. 320x240), got '" + text + "'");
}
}  // namespace

bool
parseReprojectFlags (int argc, char **argv, ReprojectFlags &flags)
{
  DatasetReprojectionOptions &options = flags.options;
  double distance = 0.0;
  std::string distance_range;
  po::options_description general (
      "agex_reproject --dataset DIR[@SEQ,...] --output DIR [--distance D | --distance-range MIN:MAX] [options]\n"
      "Re-projects a dataset's real frames and labels to other distances, positions, tilts and sensors: each frame\n"
      "is meshed, moved, rendered by a sensor model and written with its moved labels as a new agex dataset");
  general.add_options () ("help,h", "show this help")
    ("dataset", po::value (&flags.dataset_spec), "input dataset (DIR, or DIR@1,2,... for some sequences)")
    ("output", po::value (&flags.output), "dataset directory to write")
    ("force", po::bool_switch (&flags.force), "replace an existing output (only an earlier agex dataset)")
    ("keyframes-only", po::bool_switch (&flags.keyframes_only), "only the frames with keyframe labels")
    ("distance", po::value (&distance), "move each frame so that the person's median depth is D metres (0.3-20)")
    ("distance-range", po::value (&distance_range),
     "MIN:MAX: each copy's person median depth drawn uniformly from MIN-MAX metres (0.3-20)")
    ("sideways", po::value (&options.sideways)->default_value (0.0), "each copy moves sideways by up to +-M metres (0-10)")
    ("vertical", po::value (&options.vertical)->default_value (0.0), "each copy moves up or down by up to +-M metres (0-10)")
    ("tilt-deg", po::value (&options.tilt_deg)->default_value (0.0),
     "the camera tilts (pitches) by up to +-T degrees about its x axis per copy (0-80)")
    ("copies", po::value (&options.copies)->default_value (1), "moved copies per frame (1-1000)")
    ("sensor", po::value (&flags.sensor)->default_value (flags.sensor),
     "target sensor model: kinect (640x480 structured light), sr4000 (144x176 time of flight), kinect2 (512x424 "
     "time of flight) or bonn (kinect in the Bonn frames' 144x176 portrait view)")
    ("resolution", po::value (&flags.resolution),
     "target frame size WxH with the sensor's field of view (same aspect ratio; not for bonn)")
    ("bonn-depth-levels", po::value (&options.bonn_depth_levels)->default_value (true),
     "bonn: store depth in the Bonn frames' 8-bit 1.6 cm levels, which end at 4.09 m (1), or keep the kinect's "
     "depth (0)")
    ("floor", po::value (&flags.floor)->default_value (flags.floor),
     "auto: find each frame's floor and render it as a plane, so that a scene moved away stands on a floor "
     "reaching to the camera, as a camera there would see it; none: only what the frames show")
    ("seed", po::value (&options.seed)->default_value (options.seed), "random seed; the same seed gives the same bytes")
    ("source-step-growth", po::value (&options.mesh.depth_step_growth)->default_value (options.mesh.depth_step_growth, "0.0029"),
     "the input frames' depth steps in metres per squared metre of depth (a Kinect v1's 0.0029; 0 for exact "
     "depth), 0-0.02: neighbours within 3 steps are one surface")
    ("source-depth-step", po::value (&flags.source_depth_step)->default_value (flags.source_depth_step),
     "the input frames' fixed depth step, metres (0-0.5), or auto: the dataset's depth scale when it is at most "
     "0.05 m (0.016 for Bonn's 8-bit frames), else 0");
  std::vector<std::string> given;
  if (!parseCommandLine (argc, argv, general, po::positional_options_description (), &given))
    return false;

  if (flags.dataset_spec.empty ())
    throw std::runtime_error ("no --dataset given (see --help)");
  if (flags.output.empty ())
    throw std::runtime_error ("no --output directory given");
  if (!parseSynthSensor (flags.sensor, options.sensor.sensor))
    throw std::runtime_error ("unknown --sensor '" + flags.sensor + "' (expected " + synthSensorNames () + ")");
  options.sensor = sensorModel (options.sensor.sensor);
  if (!flags.resolution.empty ())
  {
    if (options.sensor.sensor == SynthSensor::Bonn)
      throw std::runtime_error ("--resolution: the bonn sensor's frames are its 144x176 portrait view; no other size");
    int width = 0, height = 0;
    parseResolution (flags.resolution, width, height);
    if (std::abs (static_cast<double> (width) * options.sensor.height - static_cast<double> (height) * options.sensor.width) >
        0.01 * static_cast<double> (height) * options.sensor.width)
      throw std::runtime_error ("--resolution " + flags.resolution + " does not keep the sensor's aspect ratio (" +
                                std::to_string (options.sensor.width) + "x" + std::to_string (options.sensor.height) +
                                ")");
    options.sensor = scaledTo (options.sensor, width, height);
  }

  // Moves.
  const bool distance_flag = std::find (given.begin (), given.end (), "distance") != given.end ();
  if (distance_flag && !distance_range.empty ())
    throw std::runtime_error ("give --distance or --distance-range, not both");
  if (distance_flag)
  {
    checkRange (distance, 0.3, 20.0, "distance", "metres");
    options.min_distance = options.max_distance = distance;
  }
  else if (!distance_range.empty ())
  {
    const auto colon = distance_range.find (':');
    double lo = 0.0, hi = 0.0;
    if (colon == std::string::npos || !number (distance_range.substr (0, colon), lo) ||
        !number (distance_range.substr (colon + 1), hi) || !(lo >= 0.3 && hi <= 20.0 && lo <= hi))
      throw std::runtime_error ("--distance-range must be MIN:MAX metres with 0.3 <= MIN <= MAX <= 20, got '" +
                                distance_range + "'");
    options.min_distance = lo;
    options.max_distance = hi;
  }
  checkRange (options.sideways, 0.0, 10.0, "sideways", "metres");
  checkRange (options.vertical, 0.0, 10.0, "vertical", "metres");
  checkRange (options.tilt_deg, 0.0, 80.0, "tilt-deg", "degrees");
  if (options.copies < 1 || options.copies > 1000)
    throw std::runtime_error ("--copies must be 1-1000, got " + std::to_string (options.copies));

  // The source frames' surfaces.
  checkRange (options.mesh.depth_step_growth, 0.0, 0.02, "source-step-growth", "metres per squared metre");
  flags.source_depth_step_auto = flags.source_depth_step == "auto";
  if (!flags.source_depth_step_auto)
  {
    double step = 0.0;
    if (!number (flags.source_depth_step, step) || !(step >= 0.0 && step <= 0.5))
      throw std::runtime_error ("--source-depth-step must be auto or 0-0.5 metres, got '" + flags.source_depth_step +
                                "'");
    options.mesh.depth_quantum = step;
  }
  if (flags.floor != "auto" && flags.floor != "none")
    throw std::runtime_error ("--floor must be auto or none, got '" + flags.floor + "'");
  options.validate ();
  return true;
}
}  // namespace apps
}  // namespace agex
