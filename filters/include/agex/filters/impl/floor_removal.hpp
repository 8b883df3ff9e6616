#pragma once

#include <agex/filters/floor_removal.h>

#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_perpendicular_plane.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace agex
{
namespace detail
{
/** PCL's perpendicular-plane model without its error message for a degenerate sample:
  * RANSAC draws again, so such a sample is routine, not an error worth printing (and
  * silencing PCL's process-wide verbosity instead would race with other threads). */
template <typename PointT>
class QuietPerpendicularPlaneModel : public pcl::SampleConsensusModelPerpendicularPlane<PointT>
{
public:
  using Base = pcl::SampleConsensusModelPerpendicularPlane<PointT>;
  using Base::Base;

  bool isSampleGood (const pcl::Indices &samples) const override
  {
    if (samples.size () != this->sample_size_)
      return false;
    const auto &cloud = *this->input_;
    const Eigen::Vector3f p0 = cloud[samples[0]].getVector3fMap ();
    const Eigen::Vector3f p1 = cloud[samples[1]].getVector3fMap ();
    const Eigen::Vector3f p2 = cloud[samples[2]].getVector3fMap ();
    // The test of pcl::SampleConsensusModelPlane::isSampleGood, so RANSAC draws the same.
    return !((p1 - p0).cross (p2 - p0).stableNorm () < Eigen::NumTraits<float>::dummy_precision ());
  }
};

/** PCL's RANSAC (pcl::RandomSampleConsensus::computeModel, single-threaded, BSD) step for
  * step, so that it draws the same samples and finds the same plane, but without its
  * error message when no sample gives a valid model: a frame without a floor is normal. */
template <typename PointT>
class QuietRansac : public pcl::RandomSampleConsensus<PointT>
{
public:
  using Base = pcl::RandomSampleConsensus<PointT>;
  using Base::Base;

  bool computeModel (int = 0) override
  {
    auto &model = this->sac_model_;
    this->iterations_ = 0;
    std::size_t best_inliers = 0;
    double k = std::numeric_limits<double>::max ();
    pcl::Indices selection;
    Eigen::VectorXf coefficients (model->getModelSize ());
    const double log_probability = std::log (1.0 - this->probability_);
    const double one_over_indices = 1.0 / static_cast<double> (model->getIndices ()->size ());
    unsigned skipped = 0;
    const unsigned max_skip = this->max_iterations_ * 10;
    this->model_.clear ();
    while (true)
    {
      model->getSamples (this->iterations_, selection);
      if (selection.empty ())
        break;
      if (!model->computeModelCoefficients (selection, coefficients))
      {
        if (++skipped < max_skip)
          continue;
        break;
      }
      const std::size_t inliers = model->countWithinDistance (coefficients, this->threshold_);
      if (inliers > best_inliers)
      {
        best_inliers = inliers;
        this->model_ = selection;
        this->model_coefficients_ = coefficients;
        const double w = static_cast<double> (best_inliers) * one_over_indices;
        double p_outliers = 1.0 - std::pow (w, static_cast<double> (selection.size ()));
        p_outliers = std::max (std::numeric_limits<double>::epsilon (), p_outliers);
        p_outliers = std::min (1.0 - std::numeric_limits<double>::epsilon (), p_outliers);
        k = log_probability / std::log (p_outliers);
      }
      ++this->iterations_;
      if (this->iterations_ > k || this->iterations_ > this->max_iterations_)
        break;
    }
    if (this->model_.empty ())
    {
      this->inliers_.clear ();
      return false;
    }
    model->selectWithinDistance (this->model_coefficients_, this->threshold_, this->inliers_);
    return true;
  }
};
}  // namespace detail
}  // namespace agex

template <typename PointT> bool
agex::FloorRemoval<PointT>::findFloor (pcl::IndicesPtr sample)
{
  const PointCloud &cloud = *input_;
  const float below_limit = -std::max (0.10f, 3.f * distance_);
  for (int attempt = 0; attempt < max_attempts_ && static_cast<int> (sample->size ()) >= min_inliers_; ++attempt)
  {
    // What pcl::SACSegmentation (SACMODEL_PERPENDICULAR_PLANE, SAC_RANSAC, optimised
    // coefficients) does, step by step, without its messages for a frame with no floor.
    typename detail::QuietPerpendicularPlaneModel<PointT>::Ptr model (
        new detail::QuietPerpendicularPlaneModel<PointT> (input_, *sample, false));
    model->setAxis (up_);
    model->setEpsAngle (max_tilt_deg_ * M_PI / 180.0);
    detail::QuietRansac<PointT> ransac (model, distance_);
    ransac.setMaxIterations (max_iterations_);
    if (!ransac.computeModel ())
      return false;
    pcl::Indices inliers;
    ransac.getInliers (inliers);
    Eigen::VectorXf coefficients (4);
    ransac.getModelCoefficients (coefficients);
    Eigen::VectorXf refined = coefficients;
    if (inliers.size () > 3)  // fewer: PCL keeps the coefficients (and says so, also at exactly 3)
      model->optimizeModelCoefficients (inliers, coefficients, refined);
    model->selectWithinDistance (refined, distance_, inliers);
    if (static_cast<int> (inliers.size ()) < min_inliers_ / 4 || refined.size () != 4)
      return false;

    Eigen::Vector4f plane (refined[0], refined[1], refined[2], refined[3]);
    plane /= plane.head<3> ().norm ();
    if (plane.head<3> ().dot (up_) < 0.f)
      plane = -plane;  // normal points up: signed distance > 0 above the floor
    std::size_t below = 0;
    for (const auto i : *sample)
      below += plane.head<3> ().dot (cloud[i].getVector3fMap ()) + plane[3] < below_limit;
    // The camera sees the floor from above: a plane with the viewpoint on or under it (a
    // steep slice through a torso or a wall) is no floor either.
    const float viewpoint_height = plane.head<3> ().dot (cloud.sensor_origin_.template head<3> ()) + plane[3];
    if (below * 4 > inliers.size () || !(viewpoint_height > distance_))
    {
      // Not the floor, which must lie under it: look again among the points below.
      pcl::IndicesPtr under (new pcl::Indices);
      for (const auto i : *sample)
        if (plane.head<3> ().dot (cloud[i].getVector3fMap ()) + plane[3] < -distance_)
          under->push_back (i);
      sample = under;
      continue;
    }
    floor_plane_ = plane;
    return true;
  }
  return false;
}

template <typename PointT> void
agex::FloorRemoval<PointT>::applyFilter (pcl::Indices &indices)
{
  indices.clear ();
  removed_indices_->clear ();
  floor_found_ = false;
  floor_plane_.setZero ();
  if (!(up_.norm () > 0.f) || !up_.allFinite () || !(distance_ > 0.f) || !std::isfinite (distance_) ||
      !(max_tilt_deg_ >= 0.f && max_tilt_deg_ < 90.f) || min_inliers_ < 3 || sample_stride_ < 1 ||
      max_attempts_ < 1 || max_iterations_ < 1)
  {
    PCL_ERROR ("[agex::%s::applyFilter] Invalid parameters: up axis (%g, %g, %g) (non-zero), distance %g (> 0), "
               "max tilt %g (0-90 degrees), min inliers %d (>= 3), sample stride %d, max attempts %d and "
               "max iterations %d (>= 1).\n",
               getClassName ().c_str (), up_.x (), up_.y (), up_.z (), distance_, max_tilt_deg_, min_inliers_,
               sample_stride_, max_attempts_, max_iterations_);
    return;
  }
  const PointCloud &cloud = *input_;
  pcl::IndicesPtr sample (new pcl::Indices);
  int seen = 0;
  for (const auto i : *indices_)
    if (std::isfinite (cloud[i].z) && (seen++ % sample_stride_) == 0)
      sample->push_back (i);
  floor_found_ = findFloor (sample);

  indices.reserve (indices_->size ());
  for (const auto i : *indices_)
  {
    const PointT &p = cloud[i];
    const bool finite = std::isfinite (p.x) && std::isfinite (p.y) && std::isfinite (p.z);
    const bool floor = finite && floor_found_ &&
                       floor_plane_.head<3> ().dot (p.getVector3fMap ()) + floor_plane_[3] < distance_;
    if (finite && floor == negative_)
      indices.push_back (i);
    else if (extract_removed_indices_)
      removed_indices_->push_back (i);
  }
}

#define PCL_INSTANTIATE_FloorRemoval(T) template class PCL_EXPORTS agex::FloorRemoval<T>;
