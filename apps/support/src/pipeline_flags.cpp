#include <agex/apps/pipeline_flags.h>

#include <boost/program_options.hpp>

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
namespace
{
Eigen::Vector3f
parseVector (const std::string &flag, const std::string &text)
{
  std::stringstream in (text);
  Eigen::Vector3f v;
  char c1 = 0, c2 = 0;
  if (!(in >> v.x () >> c1 >> v.y () >> c2 >> v.z ()) || c1 != ',' || c2 != ',' || !(in >> std::ws).eof () ||
      !v.allFinite ())
    throw std::runtime_error ("--" + flag + ": expected three numbers as x,y,z, got '" + text + "'");
  return v;
}

/** A float flag whose default prints as written (0.05, not 0.0500000007). */
po::typed_value<float> *
floatValue (float *target)
{
  std::ostringstream text;
  text << *target;
  return po::value (target)->default_value (*target, text.str ());
}

std::string
formatVector (const Eigen::Vector3f &v)
{
  std::ostringstream out;
  out << v.x () << "," << v.y () << "," << v.z ();
  return out.str ();
}
}  // namespace

po::options_description
frameOptionsDescription (FrameOptions &options)
{
  // Checked as they are parsed (agex::intrinsicProblem, as frames and Python are): a NaN or
  // 1e-6 px focal length would give empty frames, not an error.
  // An intrinsic given on the command line is meant for the frames at hand, whatever their
  // size; the defaults are the Kinect's at 640x480 and are refused for frames of another size.
  const auto intrinsic = [&options] (double CameraIntrinsics::*field, const char *name, bool focal_length) {
    return [&options, field, name, focal_length] (double v) {
      const std::string problem =
          intrinsicProblem (focal_length ? IntrinsicKind::kFocalLength : IntrinsicKind::kPrincipalPoint, v);
      if (!problem.empty ())
        throw std::runtime_error (std::string ("--") + name + " " + problem);
      options.intrinsics.*field = v;
      options.intrinsics_width = options.intrinsics_height = 0;
    };
  };
  const auto number = [] (double v) {
    std::ostringstream text;
    text << v;
    return text.str ();
  };
  const CameraIntrinsics defaults = options.intrinsics;
  po::options_description desc ("Frame input (depth images; defaults: Kinect at 640x480, see ../shared/README.md)");
  desc.add_options ()
    ("fx", po::value<double> ()->value_name ("PX")->notifier (intrinsic (&CameraIntrinsics::fx, "fx", true)),
     ("focal length x, pixels (default " + number (defaults.fx) + ")").c_str ())
    ("fy", po::value<double> ()->value_name ("PX")->notifier (intrinsic (&CameraIntrinsics::fy, "fy", true)),
     ("focal length y, pixels (default " + number (defaults.fy) + ")").c_str ())
    ("cx", po::value<double> ()->value_name ("PX")->notifier (intrinsic (&CameraIntrinsics::cx, "cx", false)),
     ("principal point x, pixels (default " + number (defaults.cx) + ")").c_str ())
    ("cy", po::value<double> ()->value_name ("PX")->notifier (intrinsic (&CameraIntrinsics::cy, "cy", false)),
     ("principal point y, pixels (default " + number (defaults.cy) + "); without any of --fx --fy --cx --cy, "
      "depth images must be 640x480").c_str ())
    ("depth-scale", po::value<std::string> ()->default_value ("auto")->notifier ([&options] (const std::string &text) {
       if (text == "auto")
       {
         options.depth_scale = 0.0;
         return;
       }
       std::istringstream in (text);
       double v = 0.0;
       if (!(in >> v) || !(in >> std::ws).eof () || !intrinsicProblem (IntrinsicKind::kDepthScale, v).empty ())
         throw std::runtime_error ("--depth-scale must be a positive number of metres per depth unit, finite as a "
                                   "float, or auto; got '" + text + "'");
       options.depth_scale = v;
     }),
     "metres per depth unit; auto: 0.016 for 8-bit PNG (Bonn), 0.001 for 16-bit PNG and .u16")
    ("width", po::value (&options.width)->default_value (options.width), "width of a raw .u16 frame")
    ("height", po::value (&options.height)->default_value (options.height), "height of a raw .u16 frame");
  return desc;
}

po::options_description
pipelineOptionsDescription (DepthPipelineParams &p, std::vector<std::string> &storage)
{
  storage.assign (3, std::string ());
  storage[0] = formatVector (p.crop_min);
  storage[1] = formatVector (p.crop_max);
  storage[2] = formatVector (p.up);
  po::options_description desc ("Pipeline (defaults: people found by agex::PersonSegmentation, no crop box;\n"
                                 "doc/pipeline.md)");
  desc.add_options ()
    ("k", po::value (&p.k)->default_value (p.k), "AGEX points per mesh, centroid included")
    ("min-separation", floatValue (&p.min_separation),
     "AGEX stops on a mesh once the next point is closer than this to those found, geodesic metres "
     "(0: k points on every mesh)")
    ("delta-connected", floatValue (&p.delta_connected),
     "largest 3D gap between connected neighbour pixels, metres")
    ("depth-step-growth", floatValue (&p.depth_step_growth),
     "the sensor's depth steps, metres per squared metre of depth (Kinect 0.0029; 0: exact depth): "
     "connectivity and the mixed-pixel jump grow with them")
    ("delta-orient", floatValue (&p.delta_orient),
     "geodesic distance traced back for orientations, metres")
    ("min-mesh-size", po::value (&p.min_mesh_size)->default_value (p.min_mesh_size),
     "smallest mesh in points; -1: 0.1% of the frame's pixels")
    ("min-mesh-area", floatValue (&p.min_mesh_area),
     "smallest mesh in square metres as the camera sees it (0: none)")
    ("median-window", po::value (&p.median_window)->default_value (p.median_window),
     "median filter window in pixels (0 or 1: off); -1: --median-extent at the persons' depth")
    ("median-extent", floatValue (&p.median_extent),
     "median filter window in metres at the persons' depth, with --median-window -1")
    ("median-max-movement", floatValue (&p.median_max_movement),
     "largest depth change the median may make, metres")
    ("no-mixed-pixel-removal", po::bool_switch ()->notifier ([&p] (bool off) { p.remove_mixed_pixels = !off; }),
     "keep mixed pixels")
    ("mixed-window", po::value (&p.mixed_window_radius)->default_value (p.mixed_window_radius),
     "mixed-pixel neighbour radius, pixels; -1: --mixed-window-angle times the focal length")
    ("mixed-window-angle", floatValue (&p.mixed_window_angle),
     "mixed-pixel neighbour radius as an angle of view, radians, with --mixed-window -1")
    ("mixed-min-jump", floatValue (&p.mixed_min_jump),
     "smallest depth jump with mixed pixels, metres")
    ("mixed-max-angle", floatValue (&p.mixed_max_veil_angle_deg),
     "largest angle between a jump and the viewing ray, degrees")
    ("no-person-isolation", po::bool_switch ()->notifier ([&p] (bool off) { p.isolate_people = !off; }),
     "no agex::PersonSegmentation: the crop box alone isolates the person")
    ("no-hidden-people", po::bool_switch ()->notifier ([&p] (bool off) { p.hidden_people = p.hidden_people && !off; }),
     "no persons seen only in pieces behind a nearer person")
    ("crop-box", po::bool_switch ()->notifier ([&p] (bool on) { p.use_crop_box = p.use_crop_box || on; }),
     "keep only the points inside --crop-min/--crop-max (also with people)")
    ("crop-min", po::value (&storage[0])->default_value (storage[0]), "bounding box minimum x,y,z, metres")
    ("crop-max", po::value (&storage[1])->default_value (storage[1]), "bounding box maximum x,y,z, metres")
    ("no-floor-removal", po::bool_switch ()->notifier ([&p] (bool off) { p.remove_floor = !off; }),
     "keep the floor")
    ("up", po::value (&storage[2])->default_value (storage[2]), "the world's up direction in camera axes")
    ("floor-max-tilt", floatValue (&p.floor_max_tilt_deg),
     "largest angle between the floor normal and up, degrees")
    ("floor-distance", floatValue (&p.floor_distance),
     "points closer than this to the floor plane are removed, metres")
    ("naive", po::bool_switch (&p.naive), "reference AGEX: a full Dijkstra per point")
    ("spur-iterations", po::value (&p.spur_iterations)->default_value (p.spur_iterations, "auto"),
     "erosion passes removing spurs and ragged edges (0: off); auto: --spur-depth at each point's depth")
    ("spur-depth", floatValue (&p.spur_depth), "metres of ragged edge the auto erosion takes")
    ("spur-min-width", floatValue (&p.spur_min_width),
     "metres: narrower strands go, wider parts keep this much width (0: the plain erosion, which takes "
     "parts narrower than twice --spur-depth)")
    ("spur-min-connected", po::value (&p.spur_min_connected)->default_value (p.spur_min_connected),
     "connected 8-neighbours a point needs to survive a pass")
    ("working-spacing", floatValue (&p.working_spacing),
     "metres between the samples the stages after person isolation work on: every s-th pixel, s by the "
     "farthest person's depth and the focal length (0: every pixel)");
  return desc;
}

std::string
pipelineFlagName (const std::string &key)
{
  static const std::map<std::string, std::string> flags = {
      {"median_window", "median-window"},       {"median_max_movement", "median-max-movement"},
      {"median_extent", "median-extent"},       {"mixed_window_angle", "mixed-window-angle"},
      {"mixed_window_radius", "mixed-window"},  {"mixed_min_jump", "mixed-min-jump"},
      {"mixed_max_veil_angle_deg", "mixed-max-angle"}, {"crop_min", "crop-min"},
      {"crop_max", "crop-max"},                 {"up", "up"},
      {"floor_max_tilt_deg", "floor-max-tilt"}, {"floor_distance", "floor-distance"},
      {"spur_min_connected", "spur-min-connected"}, {"spur_iterations", "spur-iterations"},
      {"spur_depth", "spur-depth"},             {"delta_connected", "delta-connected"},
      {"spur_min_width", "spur-min-width"},     {"min_mesh_area", "min-mesh-area"},
      {"depth_step_growth", "depth-step-growth"},
      {"min_mesh_size", "min-mesh-size"},       {"k", "k"},
      {"min_separation", "min-separation"},
      {"delta_orient", "delta-orient"}, {"working_spacing", "working-spacing"}};
  const auto it = flags.find (key);
  return it == flags.end () ? key : "--" + it->second;
}

void
finishPipelineOptions (const std::vector<std::string> &storage, DepthPipelineParams &params)
{
  params.crop_min = parseVector ("crop-min", storage.at (0));
  params.crop_max = parseVector ("crop-max", storage.at (1));
  params.up = parseVector ("up", storage.at (2));
  // The library's ranges, the same for flags and model files.
  params.validate (pipelineFlagName);
  params.up.normalize ();
}
}  // namespace apps
}  // namespace agex
