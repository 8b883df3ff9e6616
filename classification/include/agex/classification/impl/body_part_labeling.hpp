#pragma once

#include <agex/classification/body_part_labeling.h>

#include <pcl/console/print.h>

#include <cmath>

template <typename PointT> bool
agex::BodyPartLabeling<PointT>::compute (PointCloudOut &output)
{
  output.clear ();
  evaluation_ = BodyPartForest::Evaluation ();
  if (!input_)
  {
    PCL_ERROR ("[agex::BodyPartLabeling::compute] No input cloud was given.\n");
    return false;
  }
  if (!input_->isOrganized ())
  {
    PCL_ERROR ("[agex::BodyPartLabeling::compute] The input cloud is not organized (height %u); the forest's "
               "features read the pixel grid of a depth frame.\n", input_->height);
    return false;
  }
  if (!forest_ || forest_->empty ())
  {
    PCL_ERROR ("[agex::BodyPartLabeling::compute] No forest (or an empty one) was given.\n");
    return false;
  }
  if (options_.stride < 1)
  {
    PCL_ERROR ("[agex::BodyPartLabeling::compute] The stride must be at least 1 (is %d).\n", options_.stride);
    return false;
  }
  if (!std::isfinite (fx_) || !std::isfinite (fy_) || fx_ < 0.f || fy_ < 0.f)
  {
    PCL_ERROR ("[agex::BodyPartLabeling::compute] Focal lengths %g, %g are not finite and positive.\n", fx_, fy_);
    return false;
  }
  if (!initCompute ())
  {
    PCL_ERROR ("[agex::BodyPartLabeling::compute] initCompute failed.\n");
    return false;
  }
  BodyPartForest::EvaluationOptions options = options_;
  options.fx = fx_;
  options.fy = fy_;
  options.part_probabilities = true;  // all the output needs
  depth_.build (*input_, *indices_, dilation_);
  if (!forest_->evaluate (depth_, *indices_, options, evaluation_))
  {
    deinitCompute ();
    return false;
  }

  output.width = input_->width;
  output.height = input_->height;
  output.is_dense = false;
  output.header = input_->header;
  output.sensor_origin_ = input_->sensor_origin_;
  output.sensor_orientation_ = input_->sensor_orientation_;
  output.resize (static_cast<std::size_t> (input_->width) * input_->height);  // all unlabelled
  const int C = evaluation_.num_classes;
  const std::size_t n = input_->size ();
  for (std::size_t j = 0; j < indices_->size (); ++j)
  {
    const int cls = evaluation_.labels[j];
    const auto i = (*indices_)[j];
    if (cls < 0 || i < 0 || static_cast<std::size_t> (i) >= n)
      continue;
    BodyPartLabelPoint &q = output[static_cast<std::size_t> (i)];
    const PointT &p = (*input_)[static_cast<std::size_t> (i)];
    q.x = p.x;
    q.y = p.y;
    q.z = p.z;
    const float *probabilities = &evaluation_.probabilities[j * static_cast<std::size_t> (C)];
    q.p_head = probabilities[kLabelHead];
    q.p_hand = probabilities[kLabelHand];
    q.p_foot = probabilities[kLabelFoot];
    q.p_other = probabilities[kLabelOtherBody];
    q.label = forest_->classPart (cls);
  }
  deinitCompute ();
  return true;
}
