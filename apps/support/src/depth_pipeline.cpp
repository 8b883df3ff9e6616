#include <agex/apps/depth_pipeline.h>

#include <agex/filters/depth_median_filter.h>
#include <agex/filters/mixed_pixel_filter.h>
#include <agex/filters/spur_filter.h>
#include <agex/filters/surface_segmentation.h>
#include <agex/keypoints/agex_keypoint.h>

#include <pcl/ModelCoefficients.h>
#include <pcl/console/print.h>
#include <pcl/filters/crop_box.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <boost/program_options.hpp>

#include <chrono>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace po = boost::program_options;

namespace agex
{
namespace apps
{
namespace
{
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Clock = std::chrono::steady_clock;

/** RANSAC tries for the floor before giving up. */
constexpr int kFloorAttempts = 3;
/** A point this far under a candidate floor (or 3 floor distances, if more) is clearly
  * below it, not noise; a floor has few such points, at most a quarter of its inliers. */
constexpr float kFloorClearlyBelow = 0.10f;

double
msSince (Clock::time_point start)
{
  return std::chrono::duration<double, std::milli> (Clock::now () - start).count ();
}

void
invalidate (pcl::PointXYZ &p)
{
  p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN ();
}

pcl::IndicesPtr
finiteIndices (const Cloud &cloud, int stride = 1)
{
  pcl::IndicesPtr indices (new pcl::Indices);
  int seen = 0;
  for (std::size_t i = 0; i < cloud.size (); ++i)
    if (std::isfinite (cloud[i].z) && (seen++ % stride) == 0)
      indices->push_back (static_cast<int> (i));
  return indices;
}

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

PipelineResult
runDepthPipeline (const pcl::PointCloud<pcl::PointXYZ>::ConstPtr &input, const PipelineParams &params)
{
  PipelineResult result;
  Cloud::Ptr cloud (new Cloud (*input));

  // 1. Bounding box: which points we keep.
  auto start = Clock::now ();
  pcl::IndicesPtr inside (new pcl::Indices);
  {
    pcl::CropBox<pcl::PointXYZ> crop;
    crop.setInputCloud (cloud);
    crop.setMin (Eigen::Vector4f (params.crop_min.x (), params.crop_min.y (), params.crop_min.z (), 1.f));
    crop.setMax (Eigen::Vector4f (params.crop_max.x (), params.crop_max.y (), params.crop_max.z (), 1.f));
    crop.filter (*inside);
  }
  result.ms.emplace_back ("crop", msSince (start));

  // 2. Mixed pixels among the kept points, judged against neighbours from the whole
  // frame: outside the box the far side of a silhouette is still there to be seen.
  start = Clock::now ();
  std::vector<unsigned char> keep (cloud->size (), 0);
  for (const auto i : *inside)
    keep[i] = 1;
  if (params.remove_mixed_pixels && cloud->isOrganized () && !inside->empty ())
  {
    agex::MixedPixelFilter<pcl::PointXYZ> mixed;
    mixed.setInputCloud (cloud);
    mixed.setIndices (inside);
    mixed.setWindowRadius (params.mixed_window_radius);
    mixed.setMinJump (params.mixed_min_jump);
    mixed.setMaxVeilAngle (params.mixed_max_veil_angle_deg);
    mixed.setNegative (true);  // we want the mixed pixels themselves, to blank them
    pcl::Indices flying;
    mixed.filter (flying);
    for (const auto i : flying)
      keep[i] = 0;
    result.mixed_pixels_removed = static_cast<int> (flying.size ());
  }
  for (std::size_t i = 0; i < cloud->size (); ++i)
    if (!keep[i])
      invalidate ((*cloud)[i]);
  result.ms.emplace_back ("mixed_pixels", msSince (start));

  // 3. Denoise depth: a median over each point's valid neighbours, moving the point
  // along its pixel's viewing ray. Everything outside the box is NaN by now, so only the
  // box is filtered.
  start = Clock::now ();
  if (params.median_window > 1 && cloud->isOrganized ())
  {
    agex::DepthMedianFilter<pcl::PointXYZ> median;
    median.setInputCloud (cloud);
    median.setWindowSize (params.median_window);
    median.setMaxAllowedMovement (params.median_max_movement);
    median.setKeepOnViewingRay (true);
    Cloud::Ptr smoothed (new Cloud);
    median.filter (*smoothed);
    if (!smoothed->empty ())  // empty: bad parameters, reported by the filter
      cloud = smoothed;
  }
  result.ms.emplace_back ("denoise", msSince (start));

  // 4. Floor: RANSAC for a plane whose normal is within the tilt limit of "up",
  // then every point on or below it goes, including the soles where feet touch it.
  // The floor is the lowest surface in view: a plane with much of the scene under it (a
  // desk top, or a tilted plane through a patch of wall) is not the floor, and removing
  // everything below it would take the legs. RANSAC then tries again among the points
  // under that plane, where the floor must be and where it is no longer outnumbered.
  start = Clock::now ();
  if (params.remove_floor)
  {
    // Every 4th point is plenty for RANSAC and keeps the stage cheap.
    pcl::IndicesPtr sample = finiteIndices (*cloud, 4);
    const auto verbosity = pcl::console::getVerbosityLevel ();
    for (int attempt = 0; attempt < kFloorAttempts && static_cast<int> (sample->size ()) >= params.floor_min_inliers;
         ++attempt)
    {
      pcl::SACSegmentation<pcl::PointXYZ> sac;
      sac.setInputCloud (cloud);
      sac.setIndices (sample);
      sac.setModelType (pcl::SACMODEL_PERPENDICULAR_PLANE);
      sac.setMethodType (pcl::SAC_RANSAC);
      sac.setAxis (params.up);
      sac.setEpsAngle (params.floor_max_tilt_deg * M_PI / 180.0);
      sac.setDistanceThreshold (params.floor_distance);
      sac.setMaxIterations (1000);
      pcl::PointIndices inliers;
      pcl::ModelCoefficients coefficients;
      // A frame without a floor in view is normal here, not an error worth printing.
      pcl::console::setVerbosityLevel (pcl::console::L_ALWAYS);
      sac.segment (inliers, coefficients);
      pcl::console::setVerbosityLevel (verbosity);
      if (static_cast<int> (inliers.indices.size ()) < params.floor_min_inliers / 4 || coefficients.values.size () != 4)
        break;
      Eigen::Vector4f plane (coefficients.values[0], coefficients.values[1], coefficients.values[2],
                             coefficients.values[3]);
      plane /= plane.head<3> ().norm ();
      if (plane.head<3> ().dot (params.up) < 0.f)
        plane = -plane;  // normal points up: signed distance > 0 above the floor
      const float below_limit = -std::max (kFloorClearlyBelow, 3.f * params.floor_distance);
      std::size_t below = 0;
      for (const auto i : *sample)
        below += plane.head<3> ().dot ((*cloud)[i].getVector3fMap ()) + plane[3] < below_limit;
      if (below * 4 > inliers.indices.size ())
      {
        // Not the floor, which must lie under it: look again among the points below.
        pcl::IndicesPtr under (new pcl::Indices);
        for (const auto i : *sample)
          if (plane.head<3> ().dot ((*cloud)[i].getVector3fMap ()) + plane[3] < -params.floor_distance)
            under->push_back (i);
        sample = under;
        continue;
      }
      result.floor_found = true;
      result.floor_plane = plane;
      for (auto &p : cloud->points)
        if (std::isfinite (p.z) && plane.head<3> ().dot (p.getVector3fMap ()) + plane[3] < params.floor_distance)
          invalidate (p);
      break;
    }
  }
  result.ms.emplace_back ("floor", msSince (start));

  // 5. Spurs and ragged edges: geodesic extrema are drawn to them.
  start = Clock::now ();
  int spur_iterations = params.spur_iterations;
  if (spur_iterations < 0 && cloud->isOrganized ())
  {
    // Auto: erode spur_depth metres whatever the resolution, measured with the
    // median spacing of horizontally adjacent points.
    std::vector<float> spacing;
    for (std::size_t i = 0; i + 1 < cloud->size (); i += 7)
      if (std::isfinite ((*cloud)[i].z) && std::isfinite ((*cloud)[i + 1].z) && (i + 1) % cloud->width != 0)
        spacing.push_back (((*cloud)[i].getVector3fMap () - (*cloud)[i + 1].getVector3fMap ()).norm ());
    spur_iterations = 0;
    if (!spacing.empty ())
    {
      std::nth_element (spacing.begin (), spacing.begin () + spacing.size () / 2, spacing.end ());
      const float median = spacing[spacing.size () / 2];
      if (median > 0.f)
        spur_iterations = std::clamp (static_cast<int> (std::lround (params.spur_depth / median)), 1, 16);
    }
  }
  result.spur_iterations = spur_iterations;
  if (spur_iterations > 0 && cloud->isOrganized ())
  {
    agex::SpurFilter<pcl::PointXYZ> spurs;
    spurs.setInputCloud (cloud);
    spurs.setMinConnected (params.spur_min_connected);
    spurs.setIterations (spur_iterations);
    spurs.setDeltaConnected (params.delta_connected);
    spurs.setNegative (true);  // the spur points themselves, to blank them
    pcl::Indices removed;
    spurs.filter (removed);
    for (const auto i : removed)
      invalidate ((*cloud)[i]);
  }
  result.ms.emplace_back ("spurs", msSince (start));

  // 6. Surface meshes.
  start = Clock::now ();
  const int min_mesh = params.min_mesh_size >= 0
                           ? params.min_mesh_size
                           : std::max (1, static_cast<int> (cloud->size () / 1000));
  if (cloud->isOrganized ())
  {
    agex::SurfaceSegmentation<pcl::PointXYZ> segmentation;
    segmentation.setInputCloud (cloud);
    segmentation.setDeltaConnected (params.delta_connected);
    segmentation.setMinMeshSize (static_cast<std::size_t> (min_mesh));
    segmentation.segment (result.meshes);
  }
  result.ms.emplace_back ("segmentation", msSince (start));

  // 7. AGEX interest points per mesh.
  start = Clock::now ();
  if (cloud->isOrganized ())
  {
    agex::AGEXKeypoint<pcl::PointXYZ, agex::InterestPoint> agex;
    agex.setInputCloud (cloud);
    agex.setMeshes (result.meshes);
    agex.setPointsPerMesh (params.k);
    agex.setDeltaConnected (params.delta_connected);
    agex.setDeltaOrient (params.delta_orient);
    agex.setMinMeshSize (static_cast<std::size_t> (min_mesh));
    agex.setMode (params.naive ? agex::AGEXKeypoint<pcl::PointXYZ>::Mode::Naive
                               : agex::AGEXKeypoint<pcl::PointXYZ>::Mode::Incremental);
    agex.compute (result.interest_points);
  }
  result.ms.emplace_back ("agex", msSince (start));

  double total = 0.0;
  for (const auto &stage : result.ms)
    total += stage.second;
  result.ms.emplace_back ("total", total);
  result.filtered = cloud;
  return result;
}

po::options_description
frameOptionsDescription (FrameOptions &options)
{
  // Checked as they are parsed: a NaN focal length would give empty frames, not an error.
  const auto positive = [] (const char *name) {
    return [name] (double v) {
      if (!(v > 0.0) || !std::isfinite (v))
        throw std::runtime_error (std::string ("--") + name + " must be a positive number");
    };
  };
  const auto finite = [] (const char *name) {
    return [name] (double v) {
      if (!std::isfinite (v))
        throw std::runtime_error (std::string ("--") + name + " must be a finite number");
    };
  };
  po::options_description desc ("Frame input (depth images; defaults: Kinect, see ../shared/README.md)");
  desc.add_options ()
    ("fx", po::value (&options.intrinsics.fx)->default_value (options.intrinsics.fx)->notifier (positive ("fx")),
     "focal length x, pixels")
    ("fy", po::value (&options.intrinsics.fy)->default_value (options.intrinsics.fy)->notifier (positive ("fy")),
     "focal length y, pixels")
    ("cx", po::value (&options.intrinsics.cx)->default_value (options.intrinsics.cx)->notifier (finite ("cx")),
     "principal point x, pixels")
    ("cy", po::value (&options.intrinsics.cy)->default_value (options.intrinsics.cy)->notifier (finite ("cy")),
     "principal point y, pixels")
    ("depth-scale", po::value (&options.depth_scale)->default_value (0.0, "auto")->notifier ([] (double v) {
       if (!(v >= 0.0) || !std::isfinite (v))
         throw std::runtime_error ("--depth-scale must be a positive number of metres per depth unit");
     }),
     "metres per depth unit; auto: 0.016 for 8-bit PNG (Bonn), 0.001 for 16-bit PNG and .u16")
    ("width", po::value (&options.width)->default_value (options.width), "width of a raw .u16 frame")
    ("height", po::value (&options.height)->default_value (options.height), "height of a raw .u16 frame");
  return desc;
}

po::options_description
pipelineOptionsDescription (PipelineParams &p, std::vector<std::string> &storage)
{
  storage.assign (3, std::string ());
  storage[0] = formatVector (p.crop_min);
  storage[1] = formatVector (p.crop_max);
  storage[2] = formatVector (p.up);
  po::options_description desc ("Pipeline (defaults isolate a person 1.3-2.6 m in front of the sensor,\n"
                                 "within 0.75 m of its optical axis, as in the Bonn frames)");
  desc.add_options ()
    ("k", po::value (&p.k)->default_value (p.k), "AGEX points per mesh, centroid included")
    ("delta-connected", floatValue (&p.delta_connected),
     "largest 3D gap between connected neighbour pixels, metres")
    ("delta-orient", floatValue (&p.delta_orient),
     "geodesic distance traced back for orientations, metres")
    ("min-mesh-size", po::value (&p.min_mesh_size)->default_value (p.min_mesh_size, "auto"),
     "smallest mesh in points; auto: 0.1% of the frame's pixels")
    ("median-window", po::value (&p.median_window)->default_value (p.median_window),
     "median filter window in pixels (0 or 1: off)")
    ("median-max-movement", floatValue (&p.median_max_movement),
     "largest depth change the median may make, metres")
    ("no-mixed-pixel-removal", po::bool_switch ()->notifier ([&p] (bool off) { p.remove_mixed_pixels = !off; }),
     "keep mixed pixels")
    ("mixed-window", po::value (&p.mixed_window_radius)->default_value (p.mixed_window_radius),
     "mixed-pixel neighbour radius, pixels")
    ("mixed-min-jump", floatValue (&p.mixed_min_jump),
     "smallest depth jump with mixed pixels, metres")
    ("mixed-max-angle", floatValue (&p.mixed_max_veil_angle_deg),
     "largest angle between a jump and the viewing ray, degrees")
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
     "erosion passes removing spurs and ragged edges (0: off); auto: --spur-depth over the point spacing")
    ("spur-depth", floatValue (&p.spur_depth), "metres of ragged edge the auto erosion takes")
    ("spur-min-connected", po::value (&p.spur_min_connected)->default_value (p.spur_min_connected),
     "connected 8-neighbours a point needs to survive a pass");
  return desc;
}

void
finishPipelineOptions (const std::vector<std::string> &storage, PipelineParams &params)
{
  params.crop_min = parseVector ("crop-min", storage.at (0));
  params.crop_max = parseVector ("crop-max", storage.at (1));
  params.up = parseVector ("up", storage.at (2));
  if ((params.crop_max - params.crop_min).minCoeff () <= 0.f)
    throw std::runtime_error ("--crop-min must be below --crop-max on every axis");
  if (params.up.norm () == 0.f)
    throw std::runtime_error ("--up must be a non-zero vector");
  params.up.normalize ();
  if (params.k < 1)
    throw std::runtime_error ("--k must be at least 1");
  if (!(params.delta_connected > 0.f) || !(params.delta_orient >= 0.f))
    throw std::runtime_error ("--delta-connected must be > 0 and --delta-orient >= 0");
  if (!(params.median_max_movement >= 0.f))
    throw std::runtime_error ("--median-max-movement must be >= 0");
  if (params.median_window < 0 || params.median_window > 31)
    throw std::runtime_error ("--median-window must lie in [0, 31] pixels");
  if (params.mixed_window_radius < 1 || params.mixed_window_radius > 31 || !(params.mixed_min_jump > 0.f) ||
      !(params.mixed_max_veil_angle_deg > 0.f && params.mixed_max_veil_angle_deg < 90.f))
    throw std::runtime_error ("--mixed-window must lie in [1, 31], --mixed-min-jump be positive and "
                              "--mixed-max-angle lie in (0, 90) degrees");
  if (!(params.floor_distance > 0.f) || !(params.floor_max_tilt_deg >= 0.f && params.floor_max_tilt_deg < 90.f))
    throw std::runtime_error ("--floor-distance must be positive and --floor-max-tilt lie in [0, 90) degrees");
  // -1 is "auto", the defaults' own value.
  if (params.min_mesh_size < -1 || params.spur_iterations < -1)
    throw std::runtime_error ("--min-mesh-size and --spur-iterations must be 0 or more (or auto)");
  if (!(params.spur_depth > 0.f) || params.spur_min_connected < 0 || params.spur_min_connected > 8)
    throw std::runtime_error ("--spur-depth must be positive and --spur-min-connected lie in [0, 8]");
}
}  // namespace apps
}  // namespace agex
