#pragma once

#include <agex/classification/body_part_labeling.h>
#include <agex/classification/model_error.h>
#include <agex/classification/non_maximum_suppression.h>
#include <agex/classification/sliding_window_detector.h>
#include <agex/common/statistics.h>
#include <agex/detection/body_part_detector.h>
#include <agex/detection/fused_candidates.h>
#include <agex/detection/training_samples.h>
#include <agex/features/depth_patch_estimation.h>

#include <pcl/common/io.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <type_traits>

template <typename PointT> typename agex::BodyPartDetector<PointT>::Ptr
agex::BodyPartDetector<PointT>::fromModel (const std::string &path)
{
  Ptr detector (new BodyPartDetector<PointT>);
  const auto model = std::make_shared<const DetectorModel> (DetectorModel::load (path));
  detector->setModel (model);
  if (!model->forestPath ().empty ())
    detector->setForest (BodyPartForest::load (model->forestPath ()));
  if (!model->windowPath ().empty () && model->settings ().window_weight > 0.f)
  {
    try
    {
      detector->setWindowRescoring (loadWindowModel (model->windowPath (), *model, path),
                                    model->settings ().window_weight);
    }
    catch (const std::invalid_argument &e)
    {
      throw ModelError (e.what ());
    }
  }
  return detector;
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::setModel (const DetectorModel::ConstPtr &model)
{
  model_ = model;
  if (model_)
    settings_ = model_->settings ();
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::setSettings (const DetectorSettings &settings)
{
  if (model_ && settings.kind != model_->settings ().kind)
    throw std::logic_error ("BodyPartDetector::setSettings: the detector kind must stay the model's");
  settings.validate ([] (const std::string &key) { return key; });
  settings_ = settings;
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::setWindowRescoring (const DetectorModel::ConstPtr &window_model, float weight)
{
  if (!(weight >= 0.f && weight <= 1.f))
    throw std::invalid_argument ("BodyPartDetector::setWindowRescoring: weight " + std::to_string (weight) +
                                 " outside [0, 1]");
  if (window_model && window_model->settings ().kind != DetectorKind::SlidingWindow)
    throw std::invalid_argument (std::string ("BodyPartDetector::setWindowRescoring: a ") +
                                 detectorKindName (window_model->settings ().kind) +
                                 " model, not a sliding-window model");
  window_model_ = window_model;
  window_weight_ = window_model ? weight : 0.f;
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::setCascadeMinConfidence (float confidence)
{
  if (!(confidence >= 0.f && confidence < 1.f))
    throw std::invalid_argument ("BodyPartDetector::setCascadeMinConfidence: " + std::to_string (confidence) +
                                 " outside [0, 1)");
  cascade_min_confidence_ = confidence;
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::setCascadeMissRate (float rate)
{
  if (!(rate >= 0.f && rate <= 0.5f))
    throw std::invalid_argument ("BodyPartDetector::setCascadeMissRate: " + std::to_string (rate) +
                                 " outside [0, 0.5]");
  cascade_miss_rate_ = rate;
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::compute (std::vector<BodyPartDetection> &detections)
{
  detections.clear ();
  intermediate_ = DepthPipelineResult ();
  patches_classified_ = 0;
  part_labels_.clear ();
  part_modes_.clear ();
  candidates_.clear ();
  if (!model_ || !model_->valid ())
  {
    PCL_ERROR ("[agex::BodyPartDetector::compute] No model was given (setModel or fromModel).\n");
    return;
  }
  const bool fused = mode_ == DetectorMode::Model && settings_.kind == DetectorKind::Fused;
  if ((mode_ == DetectorMode::Forest || fused) && !forest_)
  {
    PCL_ERROR ("[agex::BodyPartDetector::compute] The forest mode and fused models need a forest (setForest).\n");
    return;
  }
  pipeline_.setParams (settings_.pipeline);
  pipeline_.setInputCloud (input_);
  pipeline_.setIndices (use_indices_ ? indices_ : pcl::IndicesPtr ());
  pipeline_.compute (intermediate_);
  double total = intermediate_.ms.empty () ? 0.0 : intermediate_.ms.back ().second;
  intermediate_.ms.pop_back ();  // the total, given again below with the later stages'
  const std::size_t first_later_stage = intermediate_.ms.size ();

  // With a forest the pixels are labelled in every mode (getPartLabels); the forest mode
  // also names the parts from them.
  const bool labelled = forest_ && labelParts ();
  if (mode_ == DetectorMode::Forest)
  {
    if (labelled)
      detectFromModes (detections);
  }
  else if (fused)
    classifyFused (detections);
  else
    classify (detections, settings_.kind == DetectorKind::SlidingWindow);
  assignPersons (detections);
  // Found on the working frame: reported at the input's pixels.
  if (intermediate_.stride > 1)
    for (auto &d : detections)
    {
      const int width = static_cast<int> (intermediate_.filtered->width);
      const Eigen::Vector2i pixel = intermediate_.inputPixel (d.v * width + d.u);
      d.u = std::min (pixel.x (), static_cast<int> (intermediate_.input_width) - 1);
      d.v = std::min (pixel.y (), static_cast<int> (intermediate_.input_height) - 1);
    }
  for (std::size_t i = first_later_stage; i < intermediate_.ms.size (); ++i)
    total += intermediate_.ms[i].second;
  intermediate_.ms.emplace_back ("total", total);
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::assignPersons (std::vector<BodyPartDetection> &detections) const
{
  const DepthPipelineResult &r = intermediate_;
  if (!r.filtered)
    return;
  // Each pixel's mesh, for the detections that are no AGEX point (a part mode's tip, a window).
  std::vector<int> mesh_of (r.filtered->size (), -1);
  for (std::size_t m = 0; m < r.meshes.size (); ++m)
    for (const auto i : r.meshes[m].indices)
      mesh_of[static_cast<std::size_t> (i)] = static_cast<int> (m);
  // Forest mode may name a pixel the cleaning stages removed: its person is the segmented one.
  std::vector<int> person_of;
  if (mode_ == DetectorMode::Forest)
  {
    person_of.assign (r.filtered->size (), -1);
    for (std::size_t p = 0; p < r.persons.size (); ++p)
      for (const auto i : r.persons[p].indices)
        if (i >= 0 && static_cast<std::size_t> (i) < person_of.size ())
          person_of[static_cast<std::size_t> (i)] = static_cast<int> (p);
  }
  const int width = static_cast<int> (r.filtered->width);
  std::vector<BodyPartDetection> kept;
  for (auto &d : detections)
  {
    const int index = d.v * width + d.u;
    const bool inside = d.u >= 0 && d.u < width && index >= 0 && static_cast<std::size_t> (index) < mesh_of.size ();
    if (d.mesh < 0 && inside)
      d.mesh = mesh_of[static_cast<std::size_t> (index)];
    if (d.mesh >= 0 && static_cast<std::size_t> (d.mesh) < r.mesh_person.size ())
      d.person = r.mesh_person[static_cast<std::size_t> (d.mesh)];
    else if (d.mesh < 0 && inside && !person_of.empty ())
      d.person = person_of[static_cast<std::size_t> (index)];
    // A person too far for a hand to have pixels enough gets no hand guesses
    // (PersonInfo::too_far); its head and feet, several times a hand's size, still count.
    if (d.part == BodyPart::Hand && d.person >= 0 &&
        static_cast<std::size_t> (d.person) < r.person_info.size () &&
        r.person_info[static_cast<std::size_t> (d.person)].too_far)
      continue;
    kept.push_back (d);
  }
  detections.swap (kept);
}

template <typename PointT> bool
agex::BodyPartDetector<PointT>::labelParts ()
{
  const auto start = std::chrono::steady_clock::now ();
  const DepthPipelineResult &prepared = intermediate_;
  // The focal lengths given are the input's; the stages ran on the working frame.
  float fx = fx_ / static_cast<float> (prepared.stride), fy = fy_ / static_cast<float> (prepared.stride);
  if ((!(fx > 0.f) || !(fy > 0.f)) && prepared.filtered)
    fx = fy = DepthPatchEstimation<pcl::PointXYZ, DepthPatch>::estimateFocalLength (*prepared.filtered);
  used_fx_ = fx;
  // The fused classifier was trained on part modes found at the model's stride; the forest
  // alone (Forest mode) runs at the stride the user set.
  const int stride = mode_ == DetectorMode::Model && settings_.kind == DetectorKind::Fused ? settings_.forest_stride
                                                                                            : forest_stride_;
  std::pair<double, double> ms{0.0, 0.0};
  bool ok = false;
  if (mode_ == DetectorMode::Forest)
  {
    pcl::PointCloud<pcl::PointXYZ>::ConstPtr frame;
    if (prepared.stride > 1)
      frame = prepared.frame;  // the working frame, the persons' pixels are its
    else if constexpr (std::is_same<PointT, pcl::PointXYZ>::value)
      frame = input_;
    else if (input_)
    {
      if (!xyz_frame_)
        xyz_frame_.reset (new pcl::PointCloud<pcl::PointXYZ>);
      pcl::copyPointCloud (*input_, *xyz_frame_);
      frame = xyz_frame_;
    }
    ok = forestParts (prepared, frame, forest_, fx, fy, stride, forest_parts_, part_labels_, part_modes_, &ms);
  }
  else
    ok = labelPersonParts (prepared, forest_, fx, fy, stride, part_labels_, part_modes_, &ms);
  // The focal-length fit and the labelling are the forest's; the mean shift is the modes'.
  intermediate_.ms.emplace_back ("forest", ok ? msSince (start) - ms.second : msSince (start));
  intermediate_.ms.emplace_back ("part_modes", ms.second);
  return ok;
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::detectFromModes (std::vector<BodyPartDetection> &detections)
{
  const auto start = std::chrono::steady_clock::now ();
  std::vector<BodyPartDetection> candidates;
  const int width = static_cast<int> (part_labels_.width);
  for (const PartMode &m : part_modes_)
  {
    if (m.part < 0 || m.part >= kBodyPartCount || m.tip_index < 0 || width <= 0 || !m.tip.allFinite ())
      continue;
    BodyPartDetection d;
    d.part = static_cast<BodyPart> (m.part);
    d.confidence = m.confidence;
    d.margin = m.mass;
    d.position = m.tip;
    d.orientation = m.direction;
    d.u = m.tip_index % width;
    d.v = m.tip_index / width;
    candidates.push_back (d);
  }
  patches_classified_ = candidates.size ();
  suppress (candidates, detections);
  intermediate_.ms.emplace_back ("modes", msSince (start));
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::suppress (std::vector<BodyPartDetection> &candidates,
                                          std::vector<BodyPartDetection> &detections) const
{
  std::vector<Eigen::Vector3f> positions;
  std::vector<int> parts;
  std::vector<float> scores;
  for (const auto &d : candidates)
  {
    positions.push_back (d.position);
    parts.push_back (static_cast<int> (d.part));
    scores.push_back (d.confidence);
  }
  for (const std::size_t i : agex::suppressNonMaxima (positions, parts, scores, settings_.suppression_radius))
    detections.push_back (candidates[i]);
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::classifyFused (std::vector<BodyPartDetection> &detections)
{
  using Clock = std::chrono::steady_clock;
  auto start = Clock::now ();
  const DepthPipelineResult &prepared = intermediate_;
  candidates_ = fusedCandidates (prepared, part_modes_, settings_.fused);
  const std::vector<FusedCandidate> &candidates = candidates_;
  const int width = prepared.filtered ? static_cast<int> (prepared.filtered->width) : 0;
  pcl::PointCloud<agex::InterestPoint> points;
  for (const auto &c : candidates)
    points.push_back (candidatePoint (c, width));
  std::vector<agex::DepthPatch> patches;
  computePatches (prepared, points, model_->patchGeometry (), patches);
  intermediate_.ms.emplace_back ("patches", msSince (start));
  start = Clock::now ();
  const PatchClassifier &classifier = model_->classifier ();
  const FusedFeatures features (prepared, part_labels_, part_modes_, used_fx_, settings_.pipeline.up);
  std::vector<float> aux (fusedFeatureNames ().size ());
  const int classes = classifier.classes ();
  std::vector<float> margins (classes), confidences (classes);
  std::vector<ScoredCandidate> scored;
  std::vector<std::array<float, kBodyPartCount>> kept_margins;
  std::vector<std::size_t> kept;  // the candidates the cascade kept, in scored's order
  for (std::size_t i = 0; i < patches.size () && i < candidates.size (); ++i)
  {
    features.compute (candidates[i], aux.data ());
    if (!classifier.classifyCascade (patches[i], aux.data (), cascade_min_confidence_, margins.data (),
                                     confidences.data (), cascade_miss_rate_))
      continue;
    const FusedCandidate &c = candidates[i];
    BodyPartDetection d;
    d.position = c.position;
    d.orientation = c.orientation;
    d.u = width > 0 ? c.index % width : 0;
    d.v = width > 0 ? c.index / width : 0;
    d.rank = c.agex_rank;
    d.mesh = features.meshOf (c);  // a part mode's pixel has one too (the refinement needs it)
    ScoredCandidate s;
    s.detection = d;
    std::array<float, kBodyPartCount> m{};
    for (int k = 0; k < classes && k < kBodyPartCount; ++k)
    {
      s.confidences[static_cast<std::size_t> (k)] = confidences[static_cast<std::size_t> (k)];
      m[static_cast<std::size_t> (k)] = margins[static_cast<std::size_t> (k)];
    }
    s.geodesic_distance = c.agex_rank > 0 ? c.geodesic_distance : 0.f;
    scored.push_back (s);
    kept_margins.push_back (m);
    kept.push_back (i);
  }
  // The sliding window's view of each candidate the cascade kept: its upright patch at the
  // candidate's pixel (a window model of other classes than the fused model's is not blended:
  // loadWindowModel refuses one when loading).
  if (window_model_ && window_weight_ > 0.f && window_model_->classifier ().classes () == classes && !kept.empty ())
  {
    pcl::PointCloud<agex::InterestPoint> upright;
    for (const std::size_t i : kept)
    {
      upright.push_back (points[i]);
      upright.back ().orientation[0] = upright.back ().orientation[1] = upright.back ().orientation[2] = 0.f;
    }
    std::vector<agex::DepthPatch> window_patches;
    computePatches (prepared, upright, window_model_->patchGeometry (), window_patches);
    std::vector<float> window_margins (classes), window_confidences (classes);
    for (std::size_t j = 0; j < window_patches.size () && j < scored.size (); ++j)
    {
      window_model_->classifier ().classify (window_patches[j], window_margins.data (), window_confidences.data ());
      for (int k = 0; k < classes && k < kBodyPartCount; ++k)
      {
        float &confidence = scored[j].confidences[static_cast<std::size_t> (k)];
        confidence = (1.f - window_weight_) * confidence + window_weight_ * window_confidences[static_cast<std::size_t> (k)];
      }
    }
  }
  for (std::size_t j = 0; j < scored.size (); ++j)
  {
    const auto &conf = scored[j].confidences;
    const int best = static_cast<int> (std::max_element (conf.begin (), conf.begin () + std::min (classes, kBodyPartCount)) -
                                       conf.begin ());
    scored[j].detection.part = static_cast<BodyPart> (best);
    scored[j].detection.confidence = conf[static_cast<std::size_t> (best)];
    scored[j].detection.margin = kept_margins[j][static_cast<std::size_t> (best)];
  }
  patches_classified_ = std::min (patches.size (), candidates.size ());
  std::vector<BodyPartDetection> named = refineToTips (scored, tip_refinement_);
  suppress (named, detections);
  intermediate_.ms.emplace_back ("classify", msSince (start));
}

template <typename PointT> void
agex::BodyPartDetector<PointT>::classify (std::vector<BodyPartDetection> &detections, bool windows)
{
  using Clock = std::chrono::steady_clock;
  const DepthPipelineResult &prepared = intermediate_;
  const PatchClassifier &classifier = model_->classifier ();
  if (windows)
  {
    // The windows' patches are cut inside agex::SlidingWindowDetector, with the classifier.
    intermediate_.ms.emplace_back ("patches", 0.0);
    const auto start = Clock::now ();
    if (prepared.filtered && !prepared.meshes.empty ())
    {
      pcl::IndicesPtr surface (new pcl::Indices);
      for (const int i : prepared.meshIndices ())
        surface->push_back (i);
      agex::SlidingWindowDetector<pcl::PointXYZ> detector;
      detector.setInputCloud (prepared.filtered);
      detector.setIndices (surface);
      detector.setClassifier (model_->classifierPtr ());
      // Models written before the metric stride keep their pixels.
      detector.setStride (std::max (settings_.sliding_window.stride, 1));
      detector.setStrideMetres (settings_.sliding_window.stride < 0 ? settings_.sliding_window.stride_metres : 0.f);
      detector.setScales (settings_.sliding_window.scales);
      detector.setSuppressionRadius (settings_.suppression_radius);
      std::vector<agex::WindowDetection> found;
      detector.detect (found);
      patches_classified_ = detector.getWindowCount ();
      for (const auto &w : found)
      {
        BodyPartDetection d;
        d.part = static_cast<BodyPart> (w.cls);
        d.confidence = w.confidence;
        d.margin = w.margin;
        d.position = w.position;
        d.u = w.u;
        d.v = w.v;
        d.scale = w.scale;
        detections.push_back (d);
      }
    }
    intermediate_.ms.emplace_back ("classify", msSince (start));
    return;
  }

  auto start = Clock::now ();
  std::vector<agex::DepthPatch> patches;
  computePatches (prepared, prepared.interest_points, model_->patchGeometry (), patches);
  intermediate_.ms.emplace_back ("patches", msSince (start));
  start = Clock::now ();
  const int classes = classifier.classes ();
  std::vector<float> margins (classes), confidences (classes);
  std::vector<BodyPartDetection> candidates;
  for (std::size_t i = 0; i < patches.size () && i < prepared.interest_points.size (); ++i)
  {
    if (!classifier.classifyCascade (patches[i], nullptr, cascade_min_confidence_, margins.data (),
                                     confidences.data (), cascade_miss_rate_))
      continue;
    const int best = static_cast<int> (std::max_element (confidences.begin (), confidences.end ()) - confidences.begin ());
    const agex::InterestPoint &p = prepared.interest_points[i];
    BodyPartDetection d;
    d.part = static_cast<BodyPart> (best);
    d.confidence = confidences[best];
    d.margin = margins[best];
    d.position = p.getVector3fMap ();
    d.orientation = p.getOrientationVector3fMap ();
    d.u = p.u;
    d.v = p.v;
    d.rank = p.rank;
    d.mesh = p.mesh;
    candidates.push_back (d);
  }
  patches_classified_ = std::min (patches.size (), prepared.interest_points.size ());
  // Several extrema often sit on one part (a hand's fingers, the two sides of a head):
  // keep the most confident detection of a class within the suppression radius.
  suppress (candidates, detections);
  intermediate_.ms.emplace_back ("classify", msSince (start));
}

#define PCL_INSTANTIATE_BodyPartDetector(T) template class PCL_EXPORTS agex::BodyPartDetector<T>;
