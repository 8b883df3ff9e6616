#pragma once

#include <agex/common/statistics.h>
#include <agex/detection/depth_pipeline.h>
#include <agex/filters/depth_median_filter.h>
#include <agex/filters/floor_removal.h>
#include <agex/filters/mixed_pixel_filter.h>
#include <agex/filters/spur_filter.h>
#include <agex/filters/surface_segmentation.h>
#include <agex/keypoints/agex_keypoint.h>

#include <pcl/common/io.h>
#include <pcl/filters/crop_box.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace agex
{
namespace detail
{
inline void
invalidate (pcl::PointXYZ &p)
{
  p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN ();
}

/** Erosion passes that take spur_depth metres off every edge whatever the resolution,
  * measured with the median spacing of horizontally adjacent points (0: no spacing). */
inline int
autoSpurIterations (const pcl::PointCloud<pcl::PointXYZ> &cloud, float spur_depth)
{
  std::vector<float> spacing;
  for (std::size_t i = 0; i + 1 < cloud.size (); i += 7)
    if (std::isfinite (cloud[i].z) && std::isfinite (cloud[i + 1].z) && (i + 1) % cloud.width != 0)
      spacing.push_back ((cloud[i].getVector3fMap () - cloud[i + 1].getVector3fMap ()).norm ());
  if (spacing.empty ())
    return 0;
  std::nth_element (spacing.begin (), spacing.begin () + spacing.size () / 2, spacing.end ());
  const float median_spacing = spacing[spacing.size () / 2];
  if (!(median_spacing > 0.f))
    return 0;
  return std::clamp (static_cast<int> (std::lround (spur_depth / median_spacing)), 1, 16);
}
}  // namespace detail
}  // namespace agex

template <typename PointT> void
agex::DepthPipeline<PointT>::compute (DepthPipelineResult &result)
{
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;
  using Clock = std::chrono::steady_clock;
  result = DepthPipelineResult ();
  const DepthPipelineParams &params = params_;
  Cloud::Ptr cloud (new Cloud);
  if (input_)
    pcl::copyPointCloud (*input_, *cloud);
  if (use_indices_ && indices_)
  {
    std::vector<unsigned char> given (cloud->size (), 0);
    for (const auto i : *indices_)
      if (i >= 0 && static_cast<std::size_t> (i) < cloud->size ())
        given[i] = 1;
    for (std::size_t i = 0; i < cloud->size (); ++i)
      if (!given[i])
        detail::invalidate ((*cloud)[i]);
  }
  const bool organized = cloud->isOrganized () && !cloud->empty ();

  // 1. Which points we keep: the people's pixels, within the crop box if there is one.
  auto start = Clock::now ();
  pcl::IndicesPtr inside (new pcl::Indices);
  pcl::PointCloud<pcl::Label> person_labels;
  bool people_floor = false;
  if (params.isolate_people && organized)
  {
    agex::PersonSegmentation<pcl::PointXYZ> people;
    people.setInputCloud (cloud);
    people.setUpAxis (params.up);
    people.setFloorMaxTilt (params.floor_max_tilt_deg);
    people.setFloorDistance (params.floor_distance);
    people.segment (person_labels, result.persons);
    result.person_info = people.getPersons ();
    people_floor = people.getFloorFound ();
    if (people_floor)
    {
      result.floor_found = true;
      result.floor_plane = people.getFloorPlane ();
    }
    for (const auto &person : result.persons)
      inside->insert (inside->end (), person.indices.begin (), person.indices.end ());
    std::sort (inside->begin (), inside->end ());
  }
  else
  {
    for (std::size_t i = 0; i < cloud->size (); ++i)
      inside->push_back (static_cast<int> (i));
  }
  result.ms.emplace_back ("people", msSince (start));
  start = Clock::now ();
  if (params.use_crop_box || !params.isolate_people)
  {
    pcl::CropBox<pcl::PointXYZ> crop;
    crop.setInputCloud (cloud);
    crop.setIndices (inside);
    crop.setMin (Eigen::Vector4f (params.crop_min.x (), params.crop_min.y (), params.crop_min.z (), 1.f));
    crop.setMax (Eigen::Vector4f (params.crop_max.x (), params.crop_max.y (), params.crop_max.z (), 1.f));
    pcl::IndicesPtr boxed (new pcl::Indices);
    crop.filter (*boxed);
    inside = boxed;
  }
  result.ms.emplace_back ("crop", msSince (start));

  // 2. Mixed pixels among the kept points, judged against neighbours from the whole
  // frame: outside the box the far side of a silhouette is still there to be seen.
  start = Clock::now ();
  std::vector<unsigned char> keep (cloud->size (), 0);
  for (const auto i : *inside)
    keep[i] = 1;
  if (params.remove_mixed_pixels && organized && !inside->empty ())
  {
    agex::MixedPixelFilter<pcl::PointXYZ> mixed;
    mixed.setInputCloud (cloud);
    mixed.setIndices (inside);
    mixed.setWindowRadius (params.mixed_window_radius);
    mixed.setMinJump (params.mixed_min_jump);
    mixed.setMinJumpGrowth (2.5f * params.depth_step_growth);
    mixed.setMaxVeilAngle (params.mixed_max_veil_angle_deg);
    mixed.setNegative (true);  // the mixed pixels themselves, to blank them
    pcl::Indices flying;
    mixed.filter (flying);
    for (const auto i : flying)
      keep[i] = 0;
    result.mixed_pixels_removed = static_cast<int> (flying.size ());
  }
  for (std::size_t i = 0; i < cloud->size (); ++i)
    if (!keep[i])
      detail::invalidate ((*cloud)[i]);
  result.ms.emplace_back ("mixed_pixels", msSince (start));

  // 3. Denoise depth: a median over each point's valid neighbours, moving the point along
  // its pixel's viewing ray. Everything outside the box is NaN by now.
  start = Clock::now ();
  if (params.median_window > 1 && organized)
  {
    agex::DepthMedianFilter<pcl::PointXYZ> median_filter;
    median_filter.setInputCloud (cloud);
    median_filter.setWindowSize (params.median_window);
    median_filter.setMaxAllowedMovement (params.median_max_movement);
    median_filter.setKeepOnViewingRay (true);
    Cloud::Ptr smoothed (new Cloud);
    median_filter.filter (*smoothed);
    if (!smoothed->empty ())
      cloud = smoothed;
  }
  result.ms.emplace_back ("denoise", msSince (start));

  // 4. Floor, and everything below it: the people's floor (their pixels are above it by
  // construction), else RANSAC's.
  start = Clock::now ();
  if (params.remove_floor && !cloud->empty () && !params.isolate_people)
  {
    agex::FloorRemoval<pcl::PointXYZ> floor;
    floor.setInputCloud (cloud);
    floor.setUpAxis (params.up);
    floor.setMaxTilt (params.floor_max_tilt_deg);
    floor.setDistanceThreshold (params.floor_distance);
    floor.setMinInliers (params.floor_min_inliers);
    floor.setNegative (true);  // the floor points, to blank them
    pcl::Indices on_floor;
    floor.filter (on_floor);
    for (const auto i : on_floor)
      detail::invalidate ((*cloud)[i]);
    result.floor_found = floor.getFloorFound ();
    result.floor_plane = floor.getFloorPlane ();
  }
  result.ms.emplace_back ("floor", msSince (start));

  // 5. Spurs and ragged edges: geodesic extrema are drawn to them.
  start = Clock::now ();
  int spur_iterations = params.spur_iterations;
  if (spur_iterations < 0)
    spur_iterations = organized ? detail::autoSpurIterations (*cloud, params.spur_depth) : 0;
  result.spur_iterations = spur_iterations;
  if (spur_iterations > 0 && organized)
  {
    agex::SpurFilter<pcl::PointXYZ> spurs;
    spurs.setInputCloud (cloud);
    spurs.setMinConnected (params.spur_min_connected);
    spurs.setIterations (spur_iterations);
    spurs.setDeltaConnected (params.delta_connected);
    spurs.setDeltaConnectedGrowth (1.5f * params.depth_step_growth);
    spurs.setNegative (true);  // the spur points themselves, to blank them
    pcl::Indices removed;
    spurs.filter (removed);
    for (const auto i : removed)
      detail::invalidate ((*cloud)[i]);
  }
  result.ms.emplace_back ("spurs", msSince (start));

  // 6. Surface meshes.
  start = Clock::now ();
  const int min_mesh = params.min_mesh_size >= 0 ? params.min_mesh_size
                                                 : std::max (1, static_cast<int> (cloud->size () / 1000));
  if (organized)
  {
    agex::SurfaceSegmentation<pcl::PointXYZ> segmentation;
    segmentation.setInputCloud (cloud);
    segmentation.setDeltaConnected (params.delta_connected);
    segmentation.setDeltaConnectedGrowth (1.5f * params.depth_step_growth);
    segmentation.setMinMeshSize (static_cast<std::size_t> (min_mesh));
    segmentation.segment (result.meshes);
  }
  result.ms.emplace_back ("segmentation", msSince (start));

  // 7. AGEX interest points per mesh.
  start = Clock::now ();
  if (organized)
  {
    agex::AGEXKeypoint<pcl::PointXYZ, agex::InterestPoint> agex;
    agex.setInputCloud (cloud);
    agex.setMeshes (result.meshes);
    agex.setPointsPerMesh (params.k);
    agex.setDeltaConnected (params.delta_connected);
    agex.setDeltaConnectedGrowth (1.5f * params.depth_step_growth);
    agex.setDeltaOrient (params.delta_orient);
    agex.setMinMeshSize (static_cast<std::size_t> (min_mesh));
    agex.setMode (params.naive ? agex::AGEXKeypoint<pcl::PointXYZ>::Mode::Naive
                               : agex::AGEXKeypoint<pcl::PointXYZ>::Mode::Incremental);
    agex.compute (result.interest_points);
  }
  result.ms.emplace_back ("agex", msSince (start));
  result.mesh_person = params.isolate_people ? agex::personOfMeshes (person_labels, result.meshes)
                                             : std::vector<int> (result.meshes.size (), -1);

  double total = 0.0;
  for (const auto &stage : result.ms)
    total += stage.second;
  result.ms.emplace_back ("total", total);
  result.filtered = cloud;
}

#define PCL_INSTANTIATE_DepthPipeline(T) template class PCL_EXPORTS agex::DepthPipeline<T>;
