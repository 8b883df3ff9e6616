#include <agex/apps/body_parts.h>

#include <agex/classification/patch_classifier.h>
#include <agex/features/depth_patch_estimation.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace agex
{
namespace apps
{
namespace
{
using Clock = std::chrono::steady_clock;

double
msSince (Clock::time_point start)
{
  return std::chrono::duration<double, std::milli> (Clock::now () - start).count ();
}

double
median (std::vector<double> v)
{
  if (v.empty ())
    return std::nan ("");
  std::sort (v.begin (), v.end ());
  return v.size () % 2 ? v[v.size () / 2] : 0.5 * (v[v.size () / 2 - 1] + v[v.size () / 2]);
}

/** Index of the nearest visible tip within radius (any class), or -1. */
int
nearestTip (const Eigen::Vector3f &p, const std::vector<PartLabel> &labels, float radius)
{
  int best = -1;
  float best_d = radius;
  for (std::size_t i = 0; i < labels.size (); ++i)
  {
    if (!labels[i].visible || !labels[i].tip.allFinite ())
      continue;
    const float d = (labels[i].tip - p).norm ();
    if (d <= best_d)
    {
      best_d = d;
      best = static_cast<int> (i);
    }
  }
  return best;
}
}  // namespace

nlohmann::json
DetectorSettings::toJson () const
{
  const PipelineParams &p = pipeline;
  auto vec = [] (const Eigen::Vector3f &v) { return nlohmann::json::array ({v.x (), v.y (), v.z ()}); };
  return {{"patch",
           {{"size", patch.size},
            {"extent", patch.extent},
            {"clamp", patch.clamp},
            {"suppression_radius", patch.suppression_radius}}},
          {"pipeline",
           {{"median_window", p.median_window},
            {"median_max_movement", p.median_max_movement},
            {"remove_mixed_pixels", p.remove_mixed_pixels},
            {"mixed_window_radius", p.mixed_window_radius},
            {"mixed_min_jump", p.mixed_min_jump},
            {"mixed_max_veil_angle_deg", p.mixed_max_veil_angle_deg},
            {"crop_min", vec (p.crop_min)},
            {"crop_max", vec (p.crop_max)},
            {"remove_floor", p.remove_floor},
            {"up", vec (p.up)},
            {"floor_max_tilt_deg", p.floor_max_tilt_deg},
            {"floor_distance", p.floor_distance},
            {"floor_min_inliers", p.floor_min_inliers},
            {"spur_min_connected", p.spur_min_connected},
            {"spur_iterations", p.spur_iterations},
            {"spur_depth", p.spur_depth},
            {"delta_connected", p.delta_connected},
            {"min_mesh_size", p.min_mesh_size},
            {"k", p.k},
            {"delta_orient", p.delta_orient}}}};
}

DetectorSettings
DetectorSettings::fromJson (const nlohmann::json &doc)
{
  try
  {
    DetectorSettings s;
    const auto &patch = doc.at ("patch");
    s.patch.size = patch.at ("size").get<int> ();
    s.patch.extent = patch.at ("extent").get<float> ();
    s.patch.clamp = patch.at ("clamp").get<float> ();
    s.patch.suppression_radius = patch.value ("suppression_radius", s.patch.suppression_radius);
    const auto &p = doc.at ("pipeline");
    auto vec = [] (const nlohmann::json &a) {
      return Eigen::Vector3f (a.at (0).get<float> (), a.at (1).get<float> (), a.at (2).get<float> ());
    };
    PipelineParams &q = s.pipeline;
    q.median_window = p.at ("median_window").get<int> ();
    q.median_max_movement = p.at ("median_max_movement").get<float> ();
    q.remove_mixed_pixels = p.at ("remove_mixed_pixels").get<bool> ();
    q.mixed_window_radius = p.at ("mixed_window_radius").get<int> ();
    q.mixed_min_jump = p.at ("mixed_min_jump").get<float> ();
    q.mixed_max_veil_angle_deg = p.at ("mixed_max_veil_angle_deg").get<float> ();
    q.crop_min = vec (p.at ("crop_min"));
    q.crop_max = vec (p.at ("crop_max"));
    q.remove_floor = p.at ("remove_floor").get<bool> ();
    q.up = vec (p.at ("up"));
    q.floor_max_tilt_deg = p.at ("floor_max_tilt_deg").get<float> ();
    q.floor_distance = p.at ("floor_distance").get<float> ();
    q.floor_min_inliers = p.at ("floor_min_inliers").get<int> ();
    q.spur_min_connected = p.at ("spur_min_connected").get<int> ();
    q.spur_iterations = p.at ("spur_iterations").get<int> ();
    q.spur_depth = p.at ("spur_depth").get<float> ();
    q.delta_connected = p.at ("delta_connected").get<float> ();
    q.min_mesh_size = p.at ("min_mesh_size").get<int> ();
    q.k = p.at ("k").get<int> ();
    q.delta_orient = p.at ("delta_orient").get<float> ();
    return s;
  }
  catch (const nlohmann::json::exception &e)
  {
    throw std::runtime_error (std::string ("model settings are incomplete or malformed: ") + e.what ());
  }
}

void
computePatches (const PipelineResult &prepared, const pcl::PointCloud<agex::InterestPoint> &points,
                const PatchParams &params, std::vector<agex::DepthPatch> &patches)
{
  patches.clear ();
  if (points.empty () || !prepared.filtered || !prepared.filtered->isOrganized ())
    return;
  pcl::PointCloud<agex::InterestPoint>::Ptr located (new pcl::PointCloud<agex::InterestPoint> (points));
  agex::DepthPatchEstimation<pcl::PointXYZ, agex::DepthPatch> estimation;
  estimation.setInputCloud (prepared.filtered);
  estimation.setInterestPoints (located);
  estimation.setPatchSize (params.size);
  estimation.setPatchExtent (params.extent);
  estimation.setClampDepth (params.clamp);
  pcl::PointCloud<agex::DepthPatch> out;
  estimation.compute (out);
  patches.assign (out.begin (), out.end ());
}

std::vector<Detection>
detectBodyParts (const PipelineResult &prepared, const agex::PatchClassifier &classifier, const PatchParams &params,
                 double *patch_ms, double *classify_ms)
{
  auto start = Clock::now ();
  std::vector<agex::DepthPatch> patches;
  computePatches (prepared, prepared.interest_points, params, patches);
  if (patch_ms)
    *patch_ms = msSince (start);
  start = Clock::now ();
  std::vector<Detection> detections;
  const int classes = classifier.classes ();
  std::vector<float> margins (classes), confidences (classes);
  for (std::size_t i = 0; i < patches.size () && i < prepared.interest_points.size (); ++i)
  {
    classifier.classify (patches[i], margins.data (), confidences.data ());
    const int best = static_cast<int> (std::max_element (confidences.begin (), confidences.end ()) - confidences.begin ());
    Detection d;
    d.part = static_cast<BodyPart> (best);
    d.confidence = confidences[best];
    d.margin = margins[best];
    d.point = prepared.interest_points[i];
    detections.push_back (d);
  }
  std::stable_sort (detections.begin (), detections.end (),
                    [] (const Detection &a, const Detection &b) { return a.confidence > b.confidence; });
  // Several extrema often sit on one part (a hand's fingers, the two sides of a head):
  // keep the most confident detection of a class within the suppression radius.
  if (params.suppression_radius > 0.f)
  {
    std::vector<Detection> kept;
    for (const auto &d : detections)
    {
      const bool suppressed = std::any_of (kept.begin (), kept.end (), [&] (const Detection &k) {
        return k.part == d.part &&
               (k.point.getVector3fMap () - d.point.getVector3fMap ()).norm () < params.suppression_radius;
      });
      if (!suppressed)
        kept.push_back (d);
    }
    detections.swap (kept);
  }
  if (classify_ms)
    *classify_ms = msSince (start);
  return detections;
}

nlohmann::json
detectionJson (const Detection &d)
{
  const auto &p = d.point;
  return {{"class", bodyPartName (d.part)},
          {"confidence", d.confidence},
          {"margin", d.margin},
          {"position", {p.x, p.y, p.z}},
          {"orientation", {p.orientation[0], p.orientation[1], p.orientation[2]}},
          {"pixel", {p.u, p.v}},
          {"rank", p.rank},
          {"mesh", p.mesh}};
}

void
collectTrainingSamples (const PipelineResult &prepared, const std::vector<PartLabel> &labels, float radius,
                        int random_negatives, const PatchParams &patch, std::mt19937_64 &rng,
                        std::vector<agex::DepthPatch> &patches, std::vector<int> &classes)
{
  pcl::PointCloud<agex::InterestPoint> points = prepared.interest_points;
  std::vector<int> point_classes;
  for (const auto &p : points)
  {
    const int tip = nearestTip (p.getVector3fMap (), labels, radius);
    point_classes.push_back (tip < 0 ? -1 : static_cast<int> (labels[tip].part));
  }
  // Random surface points: the classifier must also reject what is not an extremum.
  std::vector<int> surface;
  for (const auto &mesh : prepared.meshes)
    surface.insert (surface.end (), mesh.indices.begin (), mesh.indices.end ());
  const auto &cloud = *prepared.filtered;
  for (int n = 0; n < random_negatives && !surface.empty (); ++n)
  {
    const int index = surface[rng () % surface.size ()];
    const Eigen::Vector3f pos = cloud[index].getVector3fMap ();
    if (nearestTip (pos, labels, 1.5f * radius) >= 0)
      continue;
    const double angle = (rng () % 3600) * M_PI / 1800.0;
    agex::InterestPoint ip;
    ip.getVector3fMap () = pos;
    ip.orientation[0] = static_cast<float> (std::sin (angle));
    ip.orientation[1] = static_cast<float> (std::cos (angle));
    ip.orientation[2] = 0.f;
    ip.u = index % static_cast<int> (cloud.width);
    ip.v = index / static_cast<int> (cloud.width);
    ip.rank = 0;
    points.push_back (ip);
    point_classes.push_back (-1);
  }
  std::vector<agex::DepthPatch> frame_patches;
  computePatches (prepared, points, patch, frame_patches);
  for (std::size_t i = 0; i < frame_patches.size () && i < point_classes.size (); ++i)
  {
    patches.push_back (frame_patches[i]);
    classes.push_back (point_classes[i]);
  }
}

void
DetectionEvaluation::addFrame (const std::vector<Detection> &detections, const std::vector<PartLabel> &labels)
{
  ++frames_;
  std::vector<bool> taken (labels.size (), false);
  for (const auto &l : labels)
    if (l.visible && l.tip.allFinite ())
      ++positives_[static_cast<int> (l.part)];
  // Most confident first: a tip goes to the best detection that names its class.
  std::vector<const Detection *> order;
  for (const auto &d : detections)
    order.push_back (&d);
  std::stable_sort (order.begin (), order.end (),
                    [] (const Detection *a, const Detection *b) { return a->confidence > b->confidence; });
  for (const Detection *d : order)
  {
    const Eigen::Vector3f p = d->point.getVector3fMap ();
    int match = -1;
    float best = radius_;
    for (std::size_t i = 0; i < labels.size (); ++i)
    {
      const auto &l = labels[i];
      if (taken[i] || l.part != d->part || !l.visible || !l.tip.allFinite ())
        continue;
      const float dist = (l.tip - p).norm ();
      if (dist <= best)
      {
        best = dist;
        match = static_cast<int> (i);
      }
    }
    const int cls = static_cast<int> (d->part);
    scored_[cls].push_back ({d->confidence, match >= 0});
    if (match >= 0)
    {
      taken[match] = true;
      const Eigen::Vector3f axis = labels[match].tip - labels[match].base;
      const Eigen::Vector3f o = d->point.getOrientationVector3fMap ();
      if (labels[match].base.allFinite () && axis.norm () > 0.f && o.norm () > 0.f)
        orientation_errors_[cls].push_back (
            std::acos (std::clamp (static_cast<double> (axis.normalized ().dot (o.normalized ())), -1.0, 1.0)) * 180.0 /
            M_PI);
    }
    const int tip = nearestTip (p, labels, radius_);
    pairs_.push_back ({tip < 0 ? 3 : static_cast<int> (labels[tip].part), cls, d->confidence});
  }
  // Tips no detection of any class reached, with the confidence it would have needed.
  for (std::size_t i = 0; i < labels.size (); ++i)
  {
    const auto &l = labels[i];
    if (!l.visible || !l.tip.allFinite ())
      continue;
    float best = -1.f;
    for (const auto &d : detections)
      if ((d.point.getVector3fMap () - l.tip).norm () <= radius_)
        best = std::max (best, d.confidence);
    pairs_.push_back ({static_cast<int> (l.part), -1, best});
  }
}

std::vector<std::pair<double, double>>
DetectionEvaluation::precisionRecall (BodyPart part) const
{
  auto scored = scored_[static_cast<int> (part)];
  std::stable_sort (scored.begin (), scored.end (), [] (const Scored &a, const Scored &b) { return a.confidence > b.confidence; });
  const int positives = positives_[static_cast<int> (part)];
  std::vector<std::pair<double, double>> curve;
  int tp = 0, fp = 0;
  for (const auto &s : scored)
  {
    s.correct ? ++tp : ++fp;
    curve.emplace_back (positives > 0 ? static_cast<double> (tp) / positives : 0.0, static_cast<double> (tp) / (tp + fp));
  }
  return curve;
}

double
DetectionEvaluation::averagePrecision (BodyPart part) const
{
  const auto curve = precisionRecall (part);
  if (positives_[static_cast<int> (part)] == 0)
    return std::nan ("");
  // All-points interpolation (PASCAL VOC 2010+): precision made monotone from the right.
  double ap = 0.0, previous_recall = 0.0;
  for (std::size_t i = 0; i < curve.size (); ++i)
  {
    double best_precision = 0.0;
    for (std::size_t j = i; j < curve.size (); ++j)
      best_precision = std::max (best_precision, curve[j].second);
    ap += (curve[i].first - previous_recall) * best_precision;
    previous_recall = curve[i].first;
  }
  return ap;
}

std::array<std::array<int, 4>, 4>
DetectionEvaluation::confusion (float threshold) const
{
  std::array<std::array<int, 4>, 4> m{};
  for (const auto &p : pairs_)
  {
    if (p.predicted >= 0 && p.confidence >= threshold)
      ++m[p.truth][p.predicted];
    else if (p.predicted < 0 && p.confidence < threshold)
      ++m[p.truth][3];  // a tip with no detection at or above the threshold
  }
  return m;
}

double
DetectionEvaluation::orientationMedianDeg (BodyPart part) const
{
  return median (orientation_errors_[static_cast<int> (part)]);
}

nlohmann::json
DetectionEvaluation::report (float threshold) const
{
  auto number = [] (double v) { return std::isfinite (v) ? nlohmann::json (v) : nlohmann::json (nullptr); };
  nlohmann::json doc;
  doc["frames"] = frames_;
  doc["radius_m"] = radius_;
  const char *names[] = {"head", "hand", "foot", "background"};
  for (int c = 0; c < kBodyPartCount; ++c)
  {
    const auto part = static_cast<BodyPart> (c);
    doc["ap"][names[c]] = number (averagePrecision (part));
    doc["orientation_median_deg"][names[c]] = number (orientationMedianDeg (part));
    doc["labels"][names[c]] = positives_[c];
  }
  const auto m = confusion (threshold);
  nlohmann::json cm;
  for (int t = 0; t < 4; ++t)
    for (int p = 0; p < 4; ++p)
      cm[names[t]][p == 3 ? "none" : names[p]] = m[t][p];
  const std::string key = "confusion_at_" + nlohmann::json (threshold).dump ();
  doc[key] = cm;
  doc["confusion_rows"] = "truth: the class of the labelled tip within the radius (background: none); "
                          "columns: the detection's class, or none for tips without a detection at or above the threshold";
  return doc;
}
}  // namespace apps
}  // namespace agex
