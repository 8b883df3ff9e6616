#include <agex/detection/person_evaluation.h>

#include <agex/common/statistics.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <stdexcept>

namespace agex
{
namespace
{
/** The band of a depth, or kBands when outside them all. */
int
bandOf (float z)
{
  for (int b = 0; b < PersonEvaluation::kBands; ++b)
    if (z >= PersonEvaluation::kBandEdges[b] && z < PersonEvaluation::kBandEdges[b + 1])
      return b;
  return PersonEvaluation::kBands;
}

bool
onNobody (const cv::Mat &persons, int u, int v)
{
  for (int dv = -2; dv <= 2; ++dv)
    for (int du = -2; du <= 2; ++du)
    {
      const int x = u + du, y = v + dv;
      if (x >= 0 && y >= 0 && x < persons.cols && y < persons.rows && persons.at<std::uint8_t> (y, x) != 0)
        return false;
    }
  return true;
}
}  // namespace

PersonEvaluation::PersonEvaluation (float radius)
  : radius_ (radius), bands_{DetectionEvaluation (radius), DetectionEvaluation (radius), DetectionEvaluation (radius)}
{
}

void
PersonEvaluation::addFrame (const std::vector<BodyPartDetection> &detections, const std::vector<PartLabel> &labels,
                            const cv::Mat *persons)
{
  ++frames_;
  // Each labelled person's distance: the median depth of its visible tips.
  std::map<int, std::vector<double>> depths;
  for (const auto &l : labels)
    if (l.visible && l.tip.allFinite ())
      depths[l.person].push_back (l.tip.z ());
  std::map<int, int> band;
  for (const auto &[person, z] : depths)
    band[person] = bandOf (static_cast<float> (median (z)));
  for (const auto &[person, b] : band)
  {
    ++persons_[b];
    bool found = false, found_firing = false;
    for (const auto &l : labels)
      if (l.person == person && l.visible && l.tip.allFinite ())
        for (const auto &d : detections)
          if (d.part == l.part && (d.position - l.tip).norm () <= radius_)
          {
            found = true;
            found_firing = found_firing || d.confidence >= kFiringConfidence;
          }
    found_[b] += found;
    found_firing_[b] += found_firing;
  }
  for (int b = 0; b < kBands; ++b)
  {
    std::vector<PartLabel> in_band;
    for (const auto &l : labels)
      if (band.count (l.person) && band[l.person] == b)
        in_band.push_back (l);
    std::vector<BodyPartDetection> near;
    for (const auto &d : detections)
      if (bandOf (d.position.z ()) == b)
        near.push_back (d);
    bands_[b].addFrame (near, in_band);
  }
  if (persons && !persons->empty () && persons->type () == CV_8UC1)
  {
    ++frames_with_person_images_;
    for (const auto &d : detections)
      non_person_detections_ += d.confidence >= kFiringConfidence && onNobody (*persons, d.u, d.v);
  }
}

nlohmann::json
PersonEvaluation::report () const
{
  auto fraction = [] (int n, int of) { return of ? nlohmann::json (static_cast<double> (n) / of) : nlohmann::json (nullptr); };
  int persons = 0, found = 0, found_firing = 0, near_persons = 0, near_found = 0, near_found_firing = 0;
  for (int b = 0; b <= kBands; ++b)
  {
    persons += persons_[b], found += found_[b], found_firing += found_firing_[b];
    if (b < kBands && kBandEdges[b + 1] <= 4.f)
      near_persons += persons_[b], near_found += found_[b], near_found_firing += found_firing_[b];
  }
  nlohmann::json doc = {{"frames", frames_},
                        {"persons", persons},
                        {"person_recall", fraction (found_firing, persons)},
                        {"person_recall_within_4m", fraction (near_found_firing, near_persons)},
                        {"person_recall_any_confidence", fraction (found, persons)},
                        {"person_recall_any_confidence_within_4m", fraction (near_found, near_persons)},
                        {"firing_confidence", kFiringConfidence},
                        {"radius_m", radius_}};
  for (int b = 0; b < kBands; ++b)
  {
    nlohmann::json band = {{"metres", {kBandEdges[b], kBandEdges[b + 1]}},
                           {"persons", persons_[b]},
                           {"person_recall", fraction (found_firing_[b], persons_[b])},
                           {"person_recall_any_confidence", fraction (found_[b], persons_[b])}};
    for (int c = 0; c < kBodyPartCount; ++c)
    {
      const double ap = bands_[b].averagePrecision (static_cast<BodyPart> (c));
      band["ap"][bodyPartName (static_cast<BodyPart> (c))] = std::isfinite (ap) ? nlohmann::json (ap) : nlohmann::json (nullptr);
    }
    doc["bands"].push_back (band);
  }
  doc["persons_outside_the_bands"] = persons_[kBands];
  doc["non_person_detections_per_frame"] =
      frames_with_person_images_ ? nlohmann::json (static_cast<double> (non_person_detections_) / frames_with_person_images_)
                                 : nlohmann::json (nullptr);
  return doc;
}

nlohmann::json
PersonEvaluation::state () const
{
  nlohmann::json doc = {{"radius", radius_},
                        {"persons", persons_},
                        {"found", found_},
                        {"found_firing", found_firing_},
                        {"frames", frames_},
                        {"frames_with_person_images", frames_with_person_images_},
                        {"non_person_detections", non_person_detections_}};
  for (const auto &b : bands_)
    doc["bands"].push_back (b.state ());
  return doc;
}

PersonEvaluation
PersonEvaluation::fromState (const nlohmann::json &doc, const std::string &source)
{
  try
  {
    PersonEvaluation e (doc.at ("radius").get<float> ());
    e.persons_ = doc.at ("persons").get<std::array<int, kBands + 1>> ();
    e.found_ = doc.at ("found").get<std::array<int, kBands + 1>> ();
    // States written before person recall counted firing detections only are refused
    // rather than read as finding no one.
    if (doc.is_object () && !doc.contains ("found_firing"))
      throw std::invalid_argument (source + ": person evaluation state without \"found_firing\" (written by an "
                                            "older agex_eval detect; run that share again)");
    e.found_firing_ = doc.at ("found_firing").get<std::array<int, kBands + 1>> ();
    for (int b = 0; b <= kBands; ++b)
      if (e.persons_[b] < 0 || e.found_[b] < 0 || e.found_[b] > e.persons_[b] || e.found_firing_[b] < 0 ||
          e.found_firing_[b] > e.found_[b])
        throw std::invalid_argument (source + ": malformed person evaluation state (person counts out of range)");
    // Counts read as what they are: a number past int would wrap to another count.
    const auto count = [&] (const char *key) {
      const auto &value = doc.at (key);
      if (!value.is_number_integer () || value.get<std::int64_t> () < 0 ||
          value.get<std::int64_t> () > std::numeric_limits<int>::max ())
        throw std::invalid_argument (source + ": person evaluation state \"" + key +
                                     "\" must be a whole number from 0 to " +
                                     std::to_string (std::numeric_limits<int>::max ()));
      return value.get<int> ();
    };
    e.frames_ = count ("frames");
    e.frames_with_person_images_ = count ("frames_with_person_images");
    e.non_person_detections_ = count ("non_person_detections");
    const auto &bands = doc.at ("bands");
    if (!bands.is_array () || bands.size () != kBands)
      throw std::invalid_argument (source + ": person evaluation state \"bands\" must be a list of " +
                                   std::to_string (kBands) + " distance bands");
    for (int b = 0; b < kBands; ++b)
      e.bands_[b] = DetectionEvaluation::fromState (bands[b], source);
    return e;
  }
  catch (const std::invalid_argument &)
  {
    throw;
  }
  catch (const std::exception &e)
  {
    throw std::invalid_argument (source + ": malformed person evaluation state (" + e.what () + ")");
  }
}

void
PersonEvaluation::merge (const PersonEvaluation &other)
{
  if (other.radius_ != radius_)
    throw std::invalid_argument ("person evaluations with different radii cannot be merged");
  for (int b = 0; b <= kBands; ++b)
    persons_[b] += other.persons_[b], found_[b] += other.found_[b], found_firing_[b] += other.found_firing_[b];
  for (int b = 0; b < kBands; ++b)
    bands_[b].merge (other.bands_[b]);
  frames_ += other.frames_;
  frames_with_person_images_ += other.frames_with_person_images_;
  non_person_detections_ += other.non_person_detections_;
}
}  // namespace agex
