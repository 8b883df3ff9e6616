#include <agex/apps/body_parts.h>

#include <agex/classification/non_maximum_suppression.h>
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

/** The pixels of all kept meshes. */
std::vector<int>
surfaceIndices (const PipelineResult &prepared)
{
  std::vector<int> surface;
  for (const auto &mesh : prepared.meshes)
    surface.insert (surface.end (), mesh.indices.begin (), mesh.indices.end ());
  return surface;
}

/** An interest point at a pixel without orientation: its patch is upright. */
agex::InterestPoint
uprightPoint (const pcl::PointCloud<pcl::PointXYZ> &cloud, int index)
{
  agex::InterestPoint ip;
  ip.getVector3fMap () = cloud[index].getVector3fMap ();
  ip.orientation[0] = ip.orientation[1] = ip.orientation[2] = 0.f;
  ip.u = index % static_cast<int> (cloud.width);
  ip.v = index / static_cast<int> (cloud.width);
  ip.rank = 0;
  return ip;
}

/** count random mesh points farther than min_distance from every tip, as background
  * (label -1); with random_orientation each gets a random in-plane orientation. */
void
appendRandomNegatives (const PipelineResult &prepared, const std::vector<PartLabel> &labels, float min_distance,
                       int count, bool random_orientation, std::mt19937_64 &rng,
                       pcl::PointCloud<agex::InterestPoint> &points, std::vector<int> &point_classes)
{
  const std::vector<int> surface = surfaceIndices (prepared);
  const auto &cloud = *prepared.filtered;
  for (int n = 0; n < count && !surface.empty (); ++n)
  {
    const int index = surface[rng () % surface.size ()];
    agex::InterestPoint ip = uprightPoint (cloud, index);
    if (nearestTip (ip.getVector3fMap (), labels, min_distance) >= 0)
      continue;
    if (random_orientation)
    {
      const double angle = (rng () % 3600) * M_PI / 1800.0;
      ip.orientation[0] = static_cast<float> (std::sin (angle));
      ip.orientation[1] = static_cast<float> (std::cos (angle));
    }
    points.push_back (ip);
    point_classes.push_back (-1);
  }
}

/** The patches of points, appended with their classes. */
void
appendPatches (const PipelineResult &prepared, const pcl::PointCloud<agex::InterestPoint> &points,
               const std::vector<int> &point_classes, const PatchParams &patch, std::vector<agex::DepthPatch> &patches,
               std::vector<int> &classes)
{
  std::vector<agex::DepthPatch> frame_patches;
  computePatches (prepared, points, patch, frame_patches);
  for (std::size_t i = 0; i < frame_patches.size () && i < point_classes.size (); ++i)
  {
    patches.push_back (frame_patches[i]);
    classes.push_back (point_classes[i]);
  }
}
}  // namespace

const char *
detectorKindName (DetectorKind kind)
{
  return kind == DetectorKind::SlidingWindow ? "sliding_window" : "agex";
}

void
DetectorSettings::requireDetector (DetectorKind expected, const std::string &model_path) const
{
  auto described = [] (DetectorKind kind) {
    return std::string (kind == DetectorKind::Agex ? "an AGEX model" : "a sliding-window model");
  };
  if (detector != expected)
    throw std::runtime_error (model_path + " is " + described (detector) + ", but " + described (expected) +
                              " is needed here" +
                              (expected == DetectorKind::Agex ? " (train one with agex_train without --sliding-window)"
                                                              : " (train one with agex_train --sliding-window)"));
}

nlohmann::json
DetectorSettings::toJson () const
{
  const PipelineParams &p = pipeline;
  auto vec = [] (const Eigen::Vector3f &v) { return nlohmann::json::array ({v.x (), v.y (), v.z ()}); };
  nlohmann::json doc = {{"detector", detectorKindName (detector)},
                        {"patch",
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
  if (detector == DetectorKind::SlidingWindow)
    doc["sliding_window"] = {{"stride", sliding_window.stride}, {"scales", sliding_window.scales}};
  return doc;
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
    const std::string kind = doc.value ("detector", std::string (detectorKindName (DetectorKind::Agex)));
    if (kind == detectorKindName (DetectorKind::SlidingWindow))
      s.detector = DetectorKind::SlidingWindow;
    else if (kind != detectorKindName (DetectorKind::Agex))
      throw std::runtime_error ("unknown detector '" + kind + "' (expected agex or sliding_window)");
    if (doc.contains ("sliding_window"))
    {
      s.sliding_window.stride = doc["sliding_window"].at ("stride").get<int> ();
      s.sliding_window.scales = doc["sliding_window"].at ("scales").get<std::vector<float>> ();
    }
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
  // Several extrema often sit on one part (a hand's fingers, the two sides of a head):
  // keep the most confident detection of a class within the suppression radius.
  std::vector<Eigen::Vector3f> positions;
  std::vector<int> parts;
  std::vector<float> scores;
  for (const auto &d : detections)
  {
    positions.push_back (d.point.getVector3fMap ());
    parts.push_back (static_cast<int> (d.part));
    scores.push_back (d.confidence);
  }
  std::vector<Detection> kept;
  for (const std::size_t i : agex::suppressNonMaxima (positions, parts, scores, params.suppression_radius))
    kept.push_back (detections[i]);
  detections.swap (kept);
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
  appendRandomNegatives (prepared, labels, 1.5f * radius, random_negatives, true, rng, points, point_classes);
  appendPatches (prepared, points, point_classes, patch, patches, classes);
}

void
collectWindowTrainingSamples (const PipelineResult &prepared, const std::vector<PartLabel> &labels, float radius,
                              int jitter, float jitter_radius, int random_negatives, const PatchParams &patch,
                              std::mt19937_64 &rng, std::vector<agex::DepthPatch> &patches, std::vector<int> &classes)
{
  if (!prepared.filtered)
    return;
  const auto &cloud = *prepared.filtered;
  const std::vector<int> surface = surfaceIndices (prepared);
  pcl::PointCloud<agex::InterestPoint> points;
  std::vector<int> point_classes;
  for (const auto &l : labels)
  {
    if (!l.visible || !l.tip.allFinite ())
      continue;
    int nearest = -1;
    float nearest_d = radius;
    std::vector<int> near;
    for (const int index : surface)
    {
      const float d = (cloud[index].getVector3fMap () - l.tip).norm ();
      if (d <= nearest_d)
      {
        nearest_d = d;
        nearest = index;
      }
      if (d <= jitter_radius)
        near.push_back (index);
    }
    if (nearest < 0)
      continue;  // the tip's part did not survive the pipeline
    points.push_back (uprightPoint (cloud, nearest));
    point_classes.push_back (static_cast<int> (l.part));
    for (int n = 0; n < jitter && !near.empty (); ++n)
    {
      points.push_back (uprightPoint (cloud, near[rng () % near.size ()]));
      point_classes.push_back (static_cast<int> (l.part));
    }
  }
  appendRandomNegatives (prepared, labels, 1.5f * radius, random_negatives, false, rng, points, point_classes);
  appendPatches (prepared, points, point_classes, patch, patches, classes);
}

float
partBoxSide (BodyPart part)
{
  switch (part)
  {
  case BodyPart::Head:
    return 0.25f;
  case BodyPart::Hand:
    return 0.15f;
  default:
    return 0.20f;
  }
}

PixelBox
partBox (BodyPart part, float u, float v, float z, float scale, float focal)
{
  const float half = 0.5f * partBoxSide (part) * scale * focal / z;
  if (!(half > 0.f) || !std::isfinite (half))
    return {};
  return {u + 0.5f - half, v + 0.5f - half, u + 0.5f + half, v + 0.5f + half};
}

float
intersectionOverUnion (const PixelBox &a, const PixelBox &b)
{
  const float area_a = std::max (0.f, a.u1 - a.u0) * std::max (0.f, a.v1 - a.v0);
  const float area_b = std::max (0.f, b.u1 - b.u0) * std::max (0.f, b.v1 - b.v0);
  const float overlap = std::max (0.f, std::min (a.u1, b.u1) - std::max (a.u0, b.u0)) *
                        std::max (0.f, std::min (a.v1, b.v1) - std::max (a.v0, b.v0));
  const float united = area_a + area_b - overlap;
  return area_a > 0.f && area_b > 0.f && united > 0.f ? overlap / united : 0.f;
}

DetectionEvaluation
DetectionEvaluation::boxOverlap (float min_iou, float focal)
{
  DetectionEvaluation e (0.f);
  e.min_iou_ = min_iou;
  e.focal_ = focal;
  return e;
}

float
DetectionEvaluation::matchQuality (const Detection &d, const PartLabel &l) const
{
  if (!l.visible || !l.tip.allFinite ())
    return -1.f;
  if (min_iou_ > 0.f)
  {
    // Both boxes are the same physical size for the detected class: the detection's at its
    // window scale and depth, the label's at scale 1 around the tip.
    const float iou = intersectionOverUnion (
        partBox (d.part, static_cast<float> (d.point.u), static_cast<float> (d.point.v), d.point.z, d.scale, focal_),
        partBox (d.part, l.tip_px.x (), l.tip_px.y (), l.tip.z (), 1.f, focal_));
    return iou > min_iou_ ? iou : -1.f;
  }
  const float dist = (l.tip - d.point.getVector3fMap ()).norm ();
  return dist <= radius_ ? radius_ - dist : -1.f;
}

int
DetectionEvaluation::bestLabel (const Detection &d, const std::vector<PartLabel> &labels) const
{
  int best = -1;
  float best_quality = -1.f;
  for (std::size_t i = 0; i < labels.size (); ++i)
  {
    const float q = matchQuality (d, labels[i]);
    if (q >= 0.f && q > best_quality)
    {
      best_quality = q;
      best = static_cast<int> (i);
    }
  }
  return best;
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
    int match = -1;
    float best = -1.f;
    for (std::size_t i = 0; i < labels.size (); ++i)
    {
      if (taken[i] || labels[i].part != d->part)
        continue;
      const float quality = matchQuality (*d, labels[i]);
      if (quality >= 0.f && quality >= best)
      {
        best = quality;
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
    const int tip = bestLabel (*d, labels);
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
      if (matchQuality (d, l) >= 0.f)
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
  if (min_iou_ > 0.f)
    doc["min_iou"] = min_iou_;
  else
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
