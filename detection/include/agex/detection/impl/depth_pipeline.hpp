#pragma once

#include <agex/common/focal_length.h>
#include <agex/common/organized_neighbourhood.h>
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
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

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
  * measured with the median spacing of horizontally adjacent points (0: no spacing):
  * every seventh pixel of the frame, among the finite ones (points, in increasing order). */
inline int
autoSpurIterations (const pcl::PointCloud<pcl::PointXYZ> &cloud, const pcl::Indices &points, float spur_depth)
{
  std::vector<float> spacing;
  for (const auto index : points)
  {
    const auto i = static_cast<std::size_t> (index);
    if (i % 7 == 0 && i + 1 < cloud.size () && std::isfinite (cloud[i].z) && std::isfinite (cloud[i + 1].z) &&
        (i + 1) % cloud.width != 0)
      spacing.push_back ((cloud[i].getVector3fMap () - cloud[i + 1].getVector3fMap ()).norm ());
  }
  if (spacing.empty ())
    return 0;
  std::nth_element (spacing.begin (), spacing.begin () + spacing.size () / 2, spacing.end ());
  const float median_spacing = spacing[spacing.size () / 2];
  if (!(median_spacing > 0.f))
    return 0;
  return clampedInt (std::round (spur_depth / median_spacing), 1, 16);  // spacing may be absurd
}

/** The median depth of the points (indices into cloud), from at most about 2,000 of them
  * spread over the list; NaN when there are none. */
inline float
medianDepth (const pcl::PointCloud<pcl::PointXYZ> &cloud, const pcl::Indices &points)
{
  const std::size_t step = std::max<std::size_t> (1, points.size () / 2048);
  std::vector<float> z;
  z.reserve (points.size () / step + 1);
  for (std::size_t k = 0; k < points.size (); k += step)
  {
    const float d = cloud[static_cast<std::size_t> (points[k])].z;
    if (std::isfinite (d) && d > 0.f)
      z.push_back (d);
  }
  if (z.empty ())
    return std::numeric_limits<float>::quiet_NaN ();
  std::nth_element (z.begin (), z.begin () + z.size () / 2, z.end ());
  return z[z.size () / 2];
}

/** The sample spacing of a 3x3 median spanning about extent metres at depth z with focal
  * length f (2 spacing + 1 pixels); 0 (off) when that is under 2 pixels. */
inline int
metricMedianSpacing (float extent, float f, float z)
{
  const double pixels = static_cast<double> (extent) * f / z;
  if (!(pixels >= 2.0))  // NaN depth too
    return 0;
  return clampedInt (std::round ((pixels - 1.0) / 2.0), 1, DepthMedianFilter<pcl::PointXYZ>::kMaxSpacing);
}

/** The working stride (DepthPipelineParams::working_spacing): samples spacing metres apart
  * at depth z with focal length f; 1 when that is under 1.5 pixels or the depth unknown. */
inline int
workingStride (float spacing, float f, float z)
{
  const double pixels = static_cast<double> (spacing) * f / z;
  if (!(pixels >= 1.5))  // NaN depth too
    return 1;
  return clampedInt (std::round (pixels), 1, DepthPipelineParams::kMaxWorkingStride);
}

/** Every stride-th pixel of frame from offset on, in both directions, as an organized cloud. */
inline void
sampleFrame (const pcl::PointCloud<pcl::PointXYZ> &frame, int stride, int offset, pcl::PointCloud<pcl::PointXYZ> &out)
{
  const int width = static_cast<int> (frame.width), height = static_cast<int> (frame.height);
  const int w = (width - 1 - offset) / stride + 1, h = (height - 1 - offset) / stride + 1;
  out.header = frame.header;
  out.sensor_origin_ = frame.sensor_origin_;
  out.sensor_orientation_ = frame.sensor_orientation_;
  out.points.resize (static_cast<std::size_t> (w) * h);
  out.width = static_cast<std::uint32_t> (w);
  out.height = static_cast<std::uint32_t> (h);
  out.is_dense = false;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
      out[static_cast<std::size_t> (v) * w + u] =
          frame[static_cast<std::size_t> (stride * v + offset) * width + stride * u + offset];
}

/** The points of sorted that are not in removed, a sorted subsequence of it. */
inline void
removeSortedSubset (pcl::Indices &sorted, const pcl::Indices &removed)
{
  if (removed.empty ())
    return;
  pcl::Indices kept;
  kept.reserve (sorted.size () - std::min (sorted.size (), removed.size ()));
  std::set_difference (sorted.begin (), sorted.end (), removed.begin (), removed.end (), std::back_inserter (kept));
  sorted.swap (kept);
}
}  // namespace detail
}  // namespace agex

template <typename PointT> pcl::PointCloud<pcl::PointXYZ>::ConstPtr
agex::DepthPipeline<PointT>::xyzFrame () const
{
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;
  const bool limited = use_indices_ && indices_;
  if constexpr (std::is_same<PointT, pcl::PointXYZ>::value)
    if (input_ && !limited)
      return input_;  // read only: no copy of the frame
  Cloud::Ptr cloud (new Cloud);
  if (input_)
    pcl::copyPointCloud (*input_, *cloud);
  if (limited)
  {
    std::vector<unsigned char> given (cloud->size (), 0);
    for (const auto i : *indices_)
      if (i >= 0 && static_cast<std::size_t> (i) < cloud->size ())
        given[i] = 1;
    for (std::size_t i = 0; i < cloud->size (); ++i)
      if (!given[i])
        detail::invalidate ((*cloud)[i]);
  }
  return cloud;
}

template <typename PointT> void
agex::DepthPipeline<PointT>::startFilteredFrame (const pcl::PointCloud<pcl::PointXYZ> &frame)
{
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;
  pcl::PointXYZ nan;
  detail::invalidate (nan);
  // The last frame's buffer is reused once no result holds it: then only the points it
  // was given are cleared, not the whole frame (which would be paged in anew each time).
  if (!filtered_ || filtered_.use_count () > 1 || filtered_->width != frame.width ||
      filtered_->height != frame.height)
  {
    filtered_.reset (new Cloud);
    filtered_->points.assign (frame.size (), nan);
  }
  else
    for (const auto i : filtered_points_)
      (*filtered_)[i] = nan;
  filtered_->width = frame.width;
  filtered_->height = frame.height;
  filtered_->is_dense = false;
  filtered_->header = frame.header;
  filtered_->sensor_origin_ = frame.sensor_origin_;
  filtered_->sensor_orientation_ = frame.sensor_orientation_;
  for (const auto i : *points_)
    (*filtered_)[i] = frame[i];
  filtered_points_ = *points_;
}

template <typename PointT> void
agex::DepthPipeline<PointT>::setFocalLength (float fx, float fy)
{
  const auto ok = [] (float f) { return f == 0.f || saneFocalLength (f); };
  if (!ok (fx) || !ok (fy) || ((fx == 0.f) != (fy == 0.f)))
    throw std::invalid_argument ("focal lengths " + std::to_string (fx) + ", " + std::to_string (fy) +
                                 " px: both 0 (estimated) or both within " + std::to_string (kMinFocalLength) +
                                 " to " + std::to_string (kMaxFocalLength) + " px");
  fx_ = fx;
  fy_ = fy;
}

template <typename PointT> float
agex::DepthPipeline<PointT>::focalLength (const pcl::PointCloud<pcl::PointXYZ> &frame, bool isolated) const
{
  if (fx_ > 0.f && fy_ > 0.f)
    return 0.5f * (fx_ + fy_);
  // The person isolation has fitted them on this frame already.
  if (isolated && saneFocalLength (people_.getUsedFocalLengthX ()) && saneFocalLength (people_.getUsedFocalLengthY ()))
    return 0.5f * (people_.getUsedFocalLengthX () + people_.getUsedFocalLengthY ());
  float fx = 0.f, fy = 0.f;
  if (estimateFocalLengths (frame, fx, fy) && saneFocalLength (fx) && saneFocalLength (fy))
    return 0.5f * (fx + fy);
  return 525.f * static_cast<float> (frame.width) / 640.f;  // too few points to tell: little to clean
}

template <typename PointT> void
agex::DepthPipeline<PointT>::compute (DepthPipelineResult &result)
{
  using Clock = std::chrono::steady_clock;
  result = DepthPipelineResult ();  // lets go of the last frame's buffer, if result held it
  const DepthPipelineParams &params = params_;
  auto start = Clock::now ();
  pcl::PointCloud<pcl::PointXYZ>::ConstPtr frame = xyzFrame ();
  const bool organized = frame->isOrganized () && !frame->empty ();
  result.input_width = frame->width;
  result.input_height = frame->height;

  // 1. Which points we keep: the people's pixels, within the crop box if there is one.
  // points_ holds them from here on, in increasing order: every later stage works on them
  // alone, never on the whole frame.
  pcl::IndicesPtr inside (new pcl::Indices);
  person_labels_.clear ();
  if (params.isolate_people && organized)
  {
    people_.setInputCloud (frame);
    people_.setUpAxis (params.up);
    people_.setFloorMaxTilt (params.floor_max_tilt_deg);
    people_.setFloorDistance (params.floor_distance);
    people_.setHiddenPersons (params.hidden_people, people_.getHiddenPersonMinArea ());
    people_.setFocalLength (fx_, fy_);
    people_.segment (person_labels_, result.persons);
    result.person_info = people_.getPersons ();
    if (people_.getFloorFound ())
    {
      result.floor_found = true;
      result.floor_plane = people_.getFloorPlane ();
    }
    // Each person's pixels come sorted: merged, not sorted again.
    for (const auto &person : result.persons)
    {
      const auto middle = static_cast<std::ptrdiff_t> (inside->size ());
      inside->insert (inside->end (), person.indices.begin (), person.indices.end ());
      std::inplace_merge (inside->begin (), inside->begin () + middle, inside->end ());
    }
  }
  else
  {
    inside->reserve (frame->size ());
    for (std::size_t i = 0; i < frame->size (); ++i)
      if (agex::isFinitePoint ((*frame)[i]))
        inside->push_back (static_cast<int> (i));
  }
  result.ms.emplace_back ("people", msSince (start));
  start = Clock::now ();
  if (params.use_crop_box || !params.isolate_people)
  {
    pcl::CropBox<pcl::PointXYZ> crop;
    crop.setInputCloud (frame);
    crop.setIndices (inside);
    crop.setMin (Eigen::Vector4f (params.crop_min.x (), params.crop_min.y (), params.crop_min.z (), 1.f));
    crop.setMax (Eigen::Vector4f (params.crop_max.x (), params.crop_max.y (), params.crop_max.z (), 1.f));
    pcl::IndicesPtr boxed (new pcl::Indices);
    crop.filter (*boxed);
    inside = boxed;
  }
  // The focal length, for the settings given in metres (or as an angle) rather than pixels.
  const bool spur_metric = params.spur_min_width > 0.f;
  const bool needs_focal = params.median_window < 0 || (params.remove_mixed_pixels && params.mixed_window_radius < 0) ||
                           (spur_metric && params.spur_iterations != 0) || params.min_mesh_area > 0.f ||
                           params.working_spacing > 0.f;
  float focal = organized && needs_focal ? focalLength (*frame, params.isolate_people) : 0.f;
  result.ms.emplace_back ("crop", msSince (start));

  // 1b. The working density: the farthest person decides, so that no one is sampled more
  // coarsely than working_spacing; people nearer than that are sampled finer.
  start = Clock::now ();
  const pcl::PointCloud<pcl::Label> *labels_in_use = &person_labels_;
  if (params.working_spacing > 0.f && organized && focal > 0.f && !inside->empty ())
  {
    float z = 0.f;
    for (const auto &info : result.person_info)
      if (std::isfinite (info.distance))
        z = std::max (z, info.distance);
    if (!(z > 0.f))
      z = detail::medianDepth (*frame, *inside);
    // At least two rows and columns: the organized stages need neighbours.
    const int stride = std::min ({detail::workingStride (params.working_spacing, focal, z),
                                  static_cast<int> (frame->width) / 2, static_cast<int> (frame->height) / 2});
    if (stride > 1)
    {
      const int offset = (stride - 1) / 2;
      if (!working_frame_ || working_frame_.use_count () > 1)
        working_frame_.reset (new pcl::PointCloud<pcl::PointXYZ>);
      detail::sampleFrame (*frame, stride, offset, *working_frame_);
      const int width = static_cast<int> (frame->width);
      const int w = static_cast<int> (working_frame_->width), h = static_cast<int> (working_frame_->height);
      const auto source = [&] (int u, int v) {
        return static_cast<std::size_t> (stride * v + offset) * width + stride * u + offset;
      };
      // The kept points and the persons, as working pixels (still in increasing order).
      pcl::IndicesPtr sampled (new pcl::Indices);
      for (const auto i : *inside)
      {
        const int u = i % width - offset, v = i / width - offset;
        if (u >= 0 && v >= 0 && u % stride == 0 && v % stride == 0)
          sampled->push_back (v / stride * w + u / stride);
      }
      inside = sampled;
      if (!result.persons.empty ())
      {
        // A buffer of its own: person_labels_ keeps the input's size for the next frame.
        pcl::PointCloud<pcl::Label> &labels = working_labels_;
        labels.points.resize (working_frame_->size ());
        labels.width = working_frame_->width;
        labels.height = working_frame_->height;
        for (auto &person : result.persons)
          person.indices.clear ();
        for (int v = 0; v < h; ++v)
          for (int u = 0; u < w; ++u)
          {
            const std::uint32_t label = person_labels_[source (u, v)].label;
            labels[static_cast<std::size_t> (v) * w + u].label = label;
            if (label < result.persons.size ())
              result.persons[label].indices.push_back (v * w + u);
          }
        labels_in_use = &working_labels_;
      }
      result.stride = stride;
      result.offset = offset;
      frame = working_frame_;
      result.frame = working_frame_;
      focal /= static_cast<float> (stride);
    }
  }
  result.focal_length = focal;
  result.ms.emplace_back ("working_density", msSince (start));

  // 2. Mixed pixels among the kept points, judged against neighbours from the whole
  // frame: outside the box the far side of a silhouette is still there to be seen. The
  // points left are copied into the filtered frame, NaN everywhere else.
  start = Clock::now ();
  points_->assign (inside->begin (), inside->end ());
  if (params.remove_mixed_pixels && organized && !inside->empty ())
  {
    // A veil spans an angle of the sensor's view: as many pixels as the focal length says.
    const int radius = params.mixed_window_radius > 0
                           ? params.mixed_window_radius
                           : clampedInt (std::round (params.mixed_window_angle * focal), 1, 31);
    result.mixed_window_radius = radius;
    mixed_.setInputCloud (frame);
    mixed_.setIndices (inside);
    mixed_.setWindowRadius (radius);
    mixed_.setMinJump (params.mixed_min_jump);
    mixed_.setMinJumpGrowth (2.5f * params.depth_step_growth);
    mixed_.setMaxVeilAngle (params.mixed_max_veil_angle_deg);
    mixed_.setNegative (true);  // the mixed pixels themselves, to leave out
    pcl::Indices flying;
    mixed_.filter (flying);
    detail::removeSortedSubset (*points_, flying);
    result.mixed_pixels_removed = static_cast<int> (flying.size ());
  }
  startFilteredFrame (*frame);
  pcl::PointCloud<pcl::PointXYZ> &cloud = *filtered_;
  result.ms.emplace_back ("mixed_pixels", msSince (start));

  // 3. Denoise depth: a median over each point's valid neighbours, moving the point along
  // its pixel's viewing ray. Everything but the kept points is NaN by now.
  start = Clock::now ();
  // In metres: one window per frame, at the kept points' median depth (a window per pixel
  // would need a window size per pixel; persons at very different depths share it), as 3x3
  // samples spread over it, so that it costs the same at any resolution and distance.
  int median_window = params.median_window, median_spacing = 1;
  if (median_window < 0)
  {
    median_spacing = organized && !points_->empty ()
                         ? detail::metricMedianSpacing (params.median_extent, focal, detail::medianDepth (cloud, *points_))
                         : 0;
    median_window = median_spacing > 0 ? 3 : 1;
    median_spacing = std::max (median_spacing, 1);
  }
  if (median_window > 1 && organized && !points_->empty ())
  {
    result.median_window = 2 * (median_window / 2) * median_spacing + 1;
    median_.setInputCloud (filtered_);
    median_.setIndices (points_);
    median_.setWindowSize (median_window);
    median_.setSampleSpacing (median_spacing);
    median_.setMaxAllowedMovement (params.median_max_movement);
    median_.setKeepOnViewingRay (true);
    median_.filterInPlace (cloud);
  }
  result.ms.emplace_back ("denoise", msSince (start));

  // 4. Floor, and everything below it: the people's floor (their pixels are above it by
  // construction), else RANSAC's.
  start = Clock::now ();
  if (params.remove_floor && !cloud.empty () && !params.isolate_people)
  {
    agex::FloorRemoval<pcl::PointXYZ> floor;
    floor.setInputCloud (filtered_);
    floor.setUpAxis (params.up);
    floor.setMaxTilt (params.floor_max_tilt_deg);
    floor.setDistanceThreshold (params.floor_distance);
    floor.setMinInliers (params.floor_min_inliers);
    floor.setNegative (true);  // the floor points, to blank them
    pcl::Indices on_floor;
    floor.filter (on_floor);
    for (const auto i : on_floor)
      detail::invalidate (cloud[i]);
    std::sort (on_floor.begin (), on_floor.end ());
    detail::removeSortedSubset (*points_, on_floor);
    result.floor_found = floor.getFloorFound ();
    result.floor_plane = floor.getFloorPlane ();
  }
  result.ms.emplace_back ("floor", msSince (start));

  // 5. Spurs and ragged edges: geodesic extrema are drawn to them.
  start = Clock::now ();
  int spur_iterations = params.spur_iterations;
  if (spur_iterations < 0 && !spur_metric)
    spur_iterations = organized ? detail::autoSpurIterations (cloud, *points_, params.spur_depth) : 0;
  result.spur_iterations = spur_metric ? 0 : spur_iterations;
  if (spur_iterations != 0 && organized && !points_->empty ())
  {
    spurs_.setInputCloud (filtered_);
    spurs_.setIndices (points_);
    spurs_.setMinConnected (params.spur_min_connected);
    // In metres: each point's erosion depth and width at its own depth (no window, so no
    // cost per pixel beyond the erosion's); a fixed pass count keeps the width rule.
    spurs_.setFocalLength (spur_metric ? focal : 0.f);
    spurs_.setMinWidth (spur_metric ? params.spur_min_width : 0.f);
    spurs_.setErosionDepth (spur_metric && spur_iterations < 0 ? params.spur_depth : 0.f);
    spurs_.setIterations (std::max (spur_iterations, 0));
    spurs_.setDeltaConnected (params.delta_connected);
    spurs_.setDeltaConnectedGrowth (1.5f * params.depth_step_growth);
    spurs_.setNegative (true);  // the spur points themselves, to blank them
    pcl::Indices removed;
    spurs_.filter (removed);
    for (const auto i : removed)
      detail::invalidate (cloud[i]);
    detail::removeSortedSubset (*points_, removed);
    if (spur_metric)
      result.spur_iterations = spurs_.getPassesRun ();
  }
  result.ms.emplace_back ("spurs", msSince (start));

  // 6. Surface meshes.
  start = Clock::now ();
  const int min_mesh = params.min_mesh_size >= 0 ? params.min_mesh_size
                                                 : std::max (1, static_cast<int> (cloud.size () / 1000));
  if (organized)
  {
    segmentation_.setInputCloud (filtered_);
    segmentation_.setIndices (points_);
    segmentation_.setDeltaConnected (params.delta_connected);
    segmentation_.setDeltaConnectedGrowth (1.5f * params.depth_step_growth);
    segmentation_.setMinMeshSize (static_cast<std::size_t> (min_mesh));
    segmentation_.segment (result.meshes);
    // The area a mesh covers as the camera sees it: each pixel (z / f)^2 at its depth.
    if (params.min_mesh_area > 0.f && focal > 0.f)
    {
      const double per_pixel = 1.0 / (static_cast<double> (focal) * focal);
      const auto small = [&] (const pcl::PointIndices &mesh) {
        double area = 0.0;
        for (const auto i : mesh.indices)
          area += static_cast<double> (cloud[i].z) * cloud[i].z * per_pixel;
        return area < params.min_mesh_area;
      };
      result.meshes.erase (std::remove_if (result.meshes.begin (), result.meshes.end (), small), result.meshes.end ());
    }
  }
  result.ms.emplace_back ("segmentation", msSince (start));

  // 7. AGEX interest points per mesh.
  start = Clock::now ();
  if (organized)
  {
    auto &agex = agex_;
    agex.setInputCloud (filtered_);
    agex.setMeshes (result.meshes);
    agex.setPointsPerMesh (params.k);
    agex.setMinSeparation (params.min_separation);
    agex.setDeltaConnected (params.delta_connected);
    agex.setDeltaConnectedGrowth (1.5f * params.depth_step_growth);
    agex.setDeltaOrient (params.delta_orient);
    agex.setMinMeshSize (static_cast<std::size_t> (min_mesh));
    agex.setMode (params.naive ? agex::AGEXKeypoint<pcl::PointXYZ>::Mode::Naive
                               : agex::AGEXKeypoint<pcl::PointXYZ>::Mode::Incremental);
    agex.compute (result.interest_points);
  }
  result.ms.emplace_back ("agex", msSince (start));
  result.mesh_person = params.isolate_people && organized ? agex::personOfMeshes (*labels_in_use, result.meshes)
                                                          : std::vector<int> (result.meshes.size (), -1);

  double total = 0.0;
  for (const auto &stage : result.ms)
    total += stage.second;
  result.ms.emplace_back ("total", total);
  result.filtered = filtered_;
  // The stages let go of the frames: the user's input is not kept alive, and filtered_ is
  // held by the result alone, so that the next frame can reuse it.
  const pcl::PointCloud<pcl::PointXYZ>::ConstPtr none;
  people_.setInputCloud (none);
  mixed_.setInputCloud (none);
  median_.setInputCloud (none);
  spurs_.setInputCloud (none);
  segmentation_.setInputCloud (none);
  agex_.setInputCloud (none);
}

#define PCL_INSTANTIATE_DepthPipeline(T) template class PCL_EXPORTS agex::DepthPipeline<T>;
