#include <agex/detection/detection_evaluation.h>

#include <agex/common/statistics.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace agex
{
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

DetectionEvaluation
DetectionEvaluation::boxOverlap (float min_iou, float focal)
{
  DetectionEvaluation e (0.f);
  e.min_iou_ = min_iou;
  e.focal_ = focal;
  return e;
}

float
DetectionEvaluation::matchQuality (const BodyPartDetection &d, const PartLabel &l) const
{
  if (!l.visible || !l.tip.allFinite ())
    return -1.f;
  if (min_iou_ > 0.f)
  {
    // Both boxes are the same physical size for the detected class: the detection's at its
    // window scale and depth, the label's at scale 1 around the tip.
    const float iou = intersectionOverUnion (
        partBox (d.part, static_cast<float> (d.u), static_cast<float> (d.v), d.position.z (), d.scale, focal_),
        partBox (d.part, l.tip_px.x (), l.tip_px.y (), l.tip.z (), 1.f, focal_));
    return iou > min_iou_ ? iou : -1.f;
  }
  const float dist = (l.tip - d.position).norm ();
  return dist <= radius_ ? radius_ - dist : -1.f;
}

int
DetectionEvaluation::bestLabel (const BodyPartDetection &d, const std::vector<PartLabel> &labels) const
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
DetectionEvaluation::addFrame (const std::vector<BodyPartDetection> &detections, const std::vector<PartLabel> &labels)
{
  ++frames_;
  std::vector<bool> taken (labels.size (), false);
  for (const auto &l : labels)
    if (l.visible && l.tip.allFinite ())
      ++positives_[static_cast<int> (l.part)];
  // Most confident first: a tip goes to the best detection that names its class.
  std::vector<const BodyPartDetection *> order;
  for (const auto &d : detections)
    order.push_back (&d);
  std::stable_sort (order.begin (), order.end (),
                    [] (const BodyPartDetection *a, const BodyPartDetection *b) { return a->confidence > b->confidence; });
  for (const BodyPartDetection *d : order)
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
      const double error = angleBetweenDeg (labels[match].tip - labels[match].base, d->orientation);
      if (labels[match].base.allFinite () && std::isfinite (error))
        orientation_errors_[cls].push_back (error);
    }
    const int tip = bestLabel (*d, labels);
    pairs_.push_back ({tip < 0 ? 3 : static_cast<int> (labels[tip].part), cls, d->confidence});
  }
  // The top detections: per class, as many as the frame has visible tips of it, matched
  // most confident first.
  for (int cls = 0; cls < kBodyPartCount; ++cls)
  {
    std::vector<bool> used (labels.size (), false);
    int wanted = 0;
    for (const auto &l : labels)
      wanted += l.visible && l.tip.allFinite () && static_cast<int> (l.part) == cls;
    for (const BodyPartDetection *d : order)
    {
      if (wanted == 0)
        break;
      if (static_cast<int> (d->part) != cls)
        continue;
      --wanted;
      int match = -1;
      float best = -1.f;
      for (std::size_t i = 0; i < labels.size (); ++i)
        if (!used[i] && labels[i].part == d->part)
        {
          const float quality = matchQuality (*d, labels[i]);
          if (quality >= 0.f && quality >= best)
            best = quality, match = static_cast<int> (i);
        }
      if (match >= 0)
      {
        used[match] = true;
        ++top_hits_[cls];
      }
    }
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
  const int positives = positives_[static_cast<int> (part)];
  if (positives == 0)
    return std::nan ("");
  std::vector<std::pair<double, bool>> scored;
  for (const Scored &s : scored_[static_cast<int> (part)])
    scored.emplace_back (s.confidence, s.correct);
  return agex::averagePrecision (std::move (scored), static_cast<std::size_t> (positives));
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

double
DetectionEvaluation::topRecall (BodyPart part) const
{
  const int c = static_cast<int> (part);
  return positives_[c] > 0 ? static_cast<double> (top_hits_[c]) / positives_[c] : std::numeric_limits<double>::quiet_NaN ();
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
    doc["top_recall"][names[c]] = number (topRecall (part));
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

void
CandidateCoverage::addFrame (const pcl::PointCloud<InterestPoint> &agex_points,
                             const std::vector<FusedCandidate> &candidates, const std::vector<PartLabel> &labels)
{
  for (const auto &l : labels)
  {
    if (!l.visible || !l.tip.allFinite ())
      continue;
    const int c = static_cast<int> (l.part);
    ++labels_[c];
    const auto near = [&] (const Eigen::Vector3f &p) { return (p - l.tip).norm () <= radius_; };
    bool agex5 = false, agex_all = false, modes = false, any = false;
    for (const auto &p : agex_points)
    {
      const bool n = near (p.getVector3fMap ());
      agex_all = agex_all || n;
      agex5 = agex5 || (n && p.rank >= 2 && p.rank <= 6);
    }
    for (const auto &cand : candidates)
    {
      const bool n = near (cand.position);
      any = any || n;
      modes = modes || (n && (cand.sources & (kFromModeTip | kFromModePosition | kFromModeEnd)));
    }
    covered_[0][c] += agex5;
    covered_[1][c] += agex_all;
    covered_[2][c] += modes;
    covered_[3][c] += any || agex_all;
  }
}

nlohmann::json
CandidateCoverage::report () const
{
  nlohmann::json doc;
  const char *kinds[kKinds] = {"agex5", "agex_all", "modes", "union"};
  for (int c = 0; c < kBodyPartCount; ++c)
  {
    const char *name = bodyPartName (static_cast<BodyPart> (c));
    doc["labels"][name] = labels_[c];
    for (int k = 0; k < kKinds; ++k)
      doc[kinds[k]][name] = labels_[c] ? nlohmann::json (static_cast<double> (covered_[k][c]) / labels_[c])
                                       : nlohmann::json (nullptr);
  }
  doc["radius_m"] = radius_;
  return doc;
}
// --- state, for evaluations run apart and merged --------------------------------------
namespace
{
constexpr const char *kEvaluationFormat = "agex-detection-evaluation-state";
constexpr const char *kCoverageFormat = "agex-candidate-coverage-state";
// A state holds a few numbers per detection and label; this bounds what a damaged or hostile
// file can make us allocate (a million frames of a dozen detections each).
constexpr std::size_t kMaxStateEntries = std::size_t (1) << 24;

/** Reads state fields, naming source and the key on any problem. */
class StateReader
{
public:
  StateReader (const nlohmann::json &doc, const std::string &source, const char *format)
    : doc_ (doc), source_ (source)
  {
    if (!doc.is_object ())
      fail ("", "is not a JSON object");
    if (!doc.contains ("format") || doc["format"] != format)
      fail ("format", std::string ("must be \"") + format + "\"");
    if (!doc.contains ("version") || doc["version"] != 1)
      fail ("version", "must be 1");
  }
  [[noreturn]] void fail (const std::string &key, const std::string &problem) const
  {
    throw std::invalid_argument (source_ + ": evaluation state" + (key.empty () ? "" : " " + key) + " " + problem);
  }
  const nlohmann::json &at (const std::string &key) const
  {
    if (!doc_.contains (key))
      fail (key, "is missing");
    return doc_[key];
  }
  double number (const nlohmann::json &v, const std::string &key, double lo, double hi) const
  {
    if (!v.is_number () || !std::isfinite (v.get<double> ()) || v.get<double> () < lo || v.get<double> () > hi)
      fail (key, "must be a number in [" + nlohmann::json (lo).dump () + ", " + nlohmann::json (hi).dump () + "]");
    return v.get<double> ();
  }
  long long integer (const nlohmann::json &v, const std::string &key, long long lo, long long hi) const
  {
    if (!v.is_number_integer () || v.get<long long> () < lo || v.get<long long> () > hi)
      fail (key, "must be an integer in [" + std::to_string (lo) + ", " + std::to_string (hi) + "]");
    return v.get<long long> ();
  }
  const nlohmann::json &array (const nlohmann::json &v, const std::string &key, std::size_t size = 0) const
  {
    if (!v.is_array () || v.size () > kMaxStateEntries || (size > 0 && v.size () != size))
      fail (key, size > 0 ? "must be an array of " + std::to_string (size) : std::string ("must be an array"));
    return v;
  }

private:
  const nlohmann::json &doc_;
  std::string source_;
};
}  // namespace

nlohmann::json
DetectionEvaluation::state () const
{
  nlohmann::json doc = {{"format", kEvaluationFormat}, {"version", 1}, {"radius", radius_}, {"min_iou", min_iou_},
                        {"focal", focal_}, {"frames", frames_}};
  doc["positives"] = positives_;
  doc["top_hits"] = top_hits_;
  for (int c = 0; c < kBodyPartCount; ++c)
  {
    nlohmann::json scored = nlohmann::json::array ();
    for (const auto &s : scored_[c])
      scored.push_back ({s.confidence, s.correct ? 1 : 0});
    doc["scored"].push_back (scored);
    doc["orientation_errors"].push_back (orientation_errors_[c]);
  }
  doc["pairs"] = nlohmann::json::array ();
  for (const auto &p : pairs_)
    doc["pairs"].push_back ({p.truth, p.predicted, p.confidence});
  return doc;
}

DetectionEvaluation
DetectionEvaluation::fromState (const nlohmann::json &doc, const std::string &source)
{
  const StateReader r (doc, source, kEvaluationFormat);
  DetectionEvaluation e (static_cast<float> (r.number (r.at ("radius"), "radius", 0.0, 1e3)));
  e.min_iou_ = static_cast<float> (r.number (r.at ("min_iou"), "min_iou", 0.0, 1.0));
  e.focal_ = static_cast<float> (r.number (r.at ("focal"), "focal", 0.0, 1e7));
  e.frames_ = static_cast<int> (r.integer (r.at ("frames"), "frames", 0, std::numeric_limits<int>::max ()));
  const auto &positives = r.array (r.at ("positives"), "positives", kBodyPartCount);
  const auto &scored = r.array (r.at ("scored"), "scored", kBodyPartCount);
  const auto &errors = r.array (r.at ("orientation_errors"), "orientation_errors", kBodyPartCount);
  const auto &top_hits = r.array (r.at ("top_hits"), "top_hits", kBodyPartCount);
  for (int c = 0; c < kBodyPartCount; ++c)
  {
    e.positives_[c] = static_cast<int> (r.integer (positives[c], "positives", 0, std::numeric_limits<int>::max ()));
    e.top_hits_[c] = static_cast<int> (r.integer (top_hits[c], "top_hits", 0, e.positives_[c]));
    for (const auto &s : r.array (scored[c], "scored"))
    {
      r.array (s, "scored entry", 2);
      e.scored_[c].push_back ({static_cast<float> (r.number (s[0], "scored confidence", 0.0, 1.0)),
                               r.integer (s[1], "scored correct", 0, 1) == 1});
    }
    for (const auto &v : r.array (errors[c], "orientation_errors"))
      e.orientation_errors_[c].push_back (r.number (v, "orientation_errors", 0.0, 180.0));
  }
  for (const auto &p : r.array (r.at ("pairs"), "pairs"))
  {
    r.array (p, "pairs entry", 3);
    // Truth 3 is background; predicted -1 a tip no detection reached (confidence -1: none came near).
    e.pairs_.push_back ({static_cast<int> (r.integer (p[0], "pairs truth", 0, kBodyPartCount)),
                         static_cast<int> (r.integer (p[1], "pairs predicted", -1, kBodyPartCount - 1)),
                         static_cast<float> (r.number (p[2], "pairs confidence", -1.0, 1.0))});
  }
  return e;
}

void
DetectionEvaluation::merge (const DetectionEvaluation &other)
{
  if (other.radius_ != radius_ || other.min_iou_ != min_iou_ || other.focal_ != focal_)
    throw std::invalid_argument ("evaluations with different criteria (radius, IoU, focal length) cannot be merged");
  frames_ += other.frames_;
  for (int c = 0; c < kBodyPartCount; ++c)
  {
    positives_[c] += other.positives_[c];
    top_hits_[c] += other.top_hits_[c];
    scored_[c].insert (scored_[c].end (), other.scored_[c].begin (), other.scored_[c].end ());
    orientation_errors_[c].insert (orientation_errors_[c].end (), other.orientation_errors_[c].begin (),
                                   other.orientation_errors_[c].end ());
  }
  pairs_.insert (pairs_.end (), other.pairs_.begin (), other.pairs_.end ());
}

nlohmann::json
CandidateCoverage::state () const
{
  nlohmann::json doc = {{"format", kCoverageFormat}, {"version", 1}, {"radius", radius_}};
  doc["labels"] = labels_;
  doc["covered"] = covered_;
  return doc;
}

CandidateCoverage
CandidateCoverage::fromState (const nlohmann::json &doc, const std::string &source)
{
  const StateReader r (doc, source, kCoverageFormat);
  CandidateCoverage coverage (static_cast<float> (r.number (r.at ("radius"), "radius", 0.0, 1e3)));
  const auto &labels = r.array (r.at ("labels"), "labels", kBodyPartCount);
  const auto &covered = r.array (r.at ("covered"), "covered", kKinds);
  for (int c = 0; c < kBodyPartCount; ++c)
    coverage.labels_[c] = static_cast<int> (r.integer (labels[c], "labels", 0, std::numeric_limits<int>::max ()));
  for (int k = 0; k < kKinds; ++k)
  {
    const auto &row = r.array (covered[k], "covered", kBodyPartCount);
    for (int c = 0; c < kBodyPartCount; ++c)
      coverage.covered_[k][c] = static_cast<int> (r.integer (row[c], "covered", 0, coverage.labels_[c]));
  }
  return coverage;
}

void
CandidateCoverage::merge (const CandidateCoverage &other)
{
  if (other.radius_ != radius_)
    throw std::invalid_argument ("candidate coverages with different radii cannot be merged");
  for (int c = 0; c < kBodyPartCount; ++c)
  {
    labels_[c] += other.labels_[c];
    for (int k = 0; k < kKinds; ++k)
      covered_[k][c] += other.covered_[k][c];
  }
}
}  // namespace agex
