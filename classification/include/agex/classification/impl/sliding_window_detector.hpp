#pragma once

#include <agex/classification/non_maximum_suppression.h>
#include <agex/classification/sliding_window_detector.h>
#include <agex/common/statistics.h>
#include <agex/features/depth_patch_estimation.h>

#include <pcl/console/print.h>

#include <algorithm>
#include <cmath>

template <typename PointT> bool
agex::SlidingWindowDetector<PointT>::detect (std::vector<WindowDetection> &output)
{
  output.clear ();
  window_count_ = 0;
  if (!input_)
  {
    PCL_ERROR ("[agex::SlidingWindowDetector::detect] No input cloud was given.\n");
    return false;
  }
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::SlidingWindowDetector::detect] The input cloud is not organized (height %u); "
               "windows are laid on the pixel grid of a depth frame.\n", input_->height);
    return false;
  }
  if (!classifier_ || !classifier_->trained ())
  {
    PCL_ERROR ("[agex::SlidingWindowDetector::detect] No trained classifier was given.\n");
    return false;
  }
  const PatchGeometry &geometry = classifier_->patchGeometry ();
  if (geometry.size < 1 || !(geometry.extent > 0.f) || !(geometry.clamp > 0.f))
  {
    PCL_ERROR ("[agex::SlidingWindowDetector::detect] The classifier has no patch geometry.\n");
    return false;
  }
  const bool scales_ok = !scales_.empty () && std::all_of (scales_.begin (), scales_.end (), [] (float s) {
    return std::isfinite (s) && s > 0.f;
  });
  if (stride_ < 1 || !scales_ok || !(focal_length_ >= 0.f) || !std::isfinite (focal_length_) ||
      !(stride_metres_ >= 0.f) || !std::isfinite (stride_metres_))
  {
    PCL_ERROR ("[agex::SlidingWindowDetector::detect] Invalid parameters: stride %d (>= 1), stride %g m (finite, "
               ">= 0), %zu scales (at least one, each finite and > 0), focal length %g (>= 0, 0 = estimate).\n",
               stride_, stride_metres_, scales_.size (), focal_length_);
    return false;
  }
  used_stride_ = 0;

  // Candidate pixels: finite ones, among the user's indices if any.
  const int width = static_cast<int> (input_->width);
  auto usable = [&] (int index) {
    if (index < 0 || static_cast<std::size_t> (index) >= input_->size ())
      return false;
    const PointT &p = (*input_)[index];
    return std::isfinite (p.x) && std::isfinite (p.y) && std::isfinite (p.z) && p.z > 0.f;
  };
  pcl::Indices pixels;
  if (indices_ && !fake_indices_)
  {
    for (const auto index : *indices_)
      if (usable (index))
        pixels.push_back (index);
    std::sort (pixels.begin (), pixels.end ());
    pixels.erase (std::unique (pixels.begin (), pixels.end ()), pixels.end ());
  }
  else
    for (int index = 0; index < static_cast<int> (input_->size ()); ++index)
      if (usable (index))
        pixels.push_back (index);
  if (pixels.empty ())
    return true;

  // One focal length for the stride and for every scale and chunk.
  const float focal = focal_length_ > 0.f ? focal_length_ : DepthPatchEstimation<PointT, DepthPatch>::estimateFocalLength (*input_);
  const auto no_focal = [] {
    PCL_ERROR ("[agex::SlidingWindowDetector::detect] Cannot estimate the focal length from the input cloud; "
               "call setFocalLength.\n");
    return false;
  };

  // Window centres: the candidates on the stride grid.
  int stride = stride_;
  if (stride_metres_ > 0.f)
  {
    if (!(focal > 0.f))
      return no_focal ();
    const std::size_t step = std::max<std::size_t> (1, pixels.size () / 2048);
    std::vector<float> depths;
    for (std::size_t k = 0; k < pixels.size (); k += step)
      depths.push_back ((*input_)[pixels[k]].z);
    std::nth_element (depths.begin (), depths.begin () + depths.size () / 2, depths.end ());
    stride = clampedInt (std::round (stride_metres_ * focal / depths[depths.size () / 2]), 1, 64);
  }
  used_stride_ = stride;
  pcl::IndicesPtr centres (new pcl::Indices);
  for (const auto index : pixels)
    if ((index % width) % stride == 0 && (index / width) % stride == 0)
      centres->push_back (index);
  if (centres->empty ())
    return true;
  if (!(focal > 0.f))
    return no_focal ();

  DepthPatchEstimation<PointT, DepthPatch> estimation;
  estimation.setInputCloud (input_);
  estimation.setPatchSize (geometry.size);
  estimation.setClampDepth (geometry.clamp);
  estimation.setFocalLength (focal);

  const int classes = classifier_->classes ();
  std::vector<float> margins (classes), confidences (classes);
  std::vector<WindowDetection> candidates;
  // Patches in chunks: a 41 x 41 patch is 6.7 kB, a whole frame's windows would be tens of MB.
  constexpr std::size_t kChunk = 512;
  pcl::PointCloud<DepthPatch> patches;
  for (const float scale : scales_)
  {
    estimation.setPatchExtent (scale * geometry.extent);
    for (std::size_t first = 0; first < centres->size (); first += kChunk)
    {
      pcl::IndicesPtr chunk (new pcl::Indices (centres->begin () + first,
                                               centres->begin () + std::min (centres->size (), first + kChunk)));
      estimation.setIndices (chunk);
      estimation.compute (patches);
      if (patches.size () != chunk->size ())
        return false;  // DepthPatchEstimation said why
      for (std::size_t i = 0; i < chunk->size (); ++i)
      {
        // With a minimum confidence the classifier's soft cascade (if it has one there) may
        // stop computing a window early (PatchClassifier::classifyCascade).
        const bool kept = classifier_->classifyCascade (patches[i], nullptr, min_confidence_, margins.data (),
                                                        confidences.data ());
        ++window_count_;
        if (!kept)
          continue;
        const int best = static_cast<int> (std::max_element (confidences.begin (), confidences.end ()) -
                                           confidences.begin ());
        if (confidences[best] < min_confidence_)
          continue;
        const int index = (*chunk)[i];
        WindowDetection d;
        d.cls = best;
        d.confidence = confidences[best];
        d.margin = margins[best];
        d.u = index % width;
        d.v = index / width;
        d.position = (*input_)[index].getVector3fMap ();
        d.scale = scale;
        d.extent = scale * geometry.extent;
        candidates.push_back (d);
      }
    }
  }

  std::vector<Eigen::Vector3f> positions;
  std::vector<int> labels;
  std::vector<float> scores;
  for (const auto &c : candidates)
  {
    positions.push_back (c.position);
    labels.push_back (c.cls);
    scores.push_back (c.confidence);
  }
  for (const std::size_t i : suppressNonMaxima (positions, labels, scores, suppression_radius_))
    output.push_back (candidates[i]);
  return true;
}

#define PCL_INSTANTIATE_SlidingWindowDetector(T) template class PCL_EXPORTS agex::SlidingWindowDetector<T>;
