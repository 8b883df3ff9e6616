// The detector's evaluation and settings: the box-overlap (IoU) and distance criteria on
// hand-built detections, and the model settings' schema and ranges.

#include <agex/common/pixel_box.h>
#include <agex/detection/detection_evaluation.h>
#include <agex/detection/detector_model.h>
#include <agex/detection/person_evaluation.h>

#include <gtest/gtest.h>

#include <cmath>

namespace
{
TEST (BoxOverlap, IntersectionOverUnionOfHandBuiltBoxes)
{
  using agex::PixelBox;
  const PixelBox a{0.f, 0.f, 2.f, 2.f};
  EXPECT_FLOAT_EQ (agex::intersectionOverUnion (a, a), 1.f);
  EXPECT_FLOAT_EQ (agex::intersectionOverUnion (a, PixelBox{1.f, 0.f, 3.f, 2.f}), 2.f / 6.f);
  EXPECT_FLOAT_EQ (agex::intersectionOverUnion (a, PixelBox{1.f, 1.f, 3.f, 3.f}), 1.f / 7.f);
  EXPECT_FLOAT_EQ (agex::intersectionOverUnion (a, PixelBox{2.f, 0.f, 4.f, 2.f}), 0.f);  // touching
  EXPECT_FLOAT_EQ (agex::intersectionOverUnion (a, PixelBox{0.5f, 0.5f, 1.5f, 1.5f}), 0.25f);
  EXPECT_FLOAT_EQ (agex::intersectionOverUnion (a, PixelBox{}), 0.f);  // empty

  // A head (0.25 m) at 2 m with f = 100 px: a 12.5 px square around the pixel's centre.
  const PixelBox head = agex::partBox (agex::BodyPart::Head, 50.f, 40.f, 2.f, 1.f, 100.f);
  EXPECT_FLOAT_EQ (head.u0, 50.5f - 6.25f);
  EXPECT_FLOAT_EQ (head.u1, 50.5f + 6.25f);
  EXPECT_FLOAT_EQ (head.v0, 40.5f - 6.25f);
  // Twice the scale: twice the side.
  const PixelBox big = agex::partBox (agex::BodyPart::Head, 50.f, 40.f, 2.f, 2.f, 100.f);
  EXPECT_FLOAT_EQ (big.u1 - big.u0, 25.f);
}

agex::BodyPartDetection
detectionAt (agex::BodyPart part, int u, int v, float z, float confidence, float scale = 1.f)
{
  agex::BodyPartDetection d;
  d.part = part;
  d.confidence = confidence;
  d.u = u;
  d.v = v;
  d.position = Eigen::Vector3f ((u - 40.f) * z / 100.f, (v - 30.f) * z / 100.f, z);
  d.scale = scale;
  return d;
}

TEST (BoxOverlap, DetectionEvaluationMatchesByOverlap)
{
  // One head label at pixel (50, 40), 2 m away, f = 100 px: its box is 12.5 px wide.
  agex::PartLabel head;
  head.part = agex::BodyPart::Head;
  head.tip_px = Eigen::Vector2f (50.f, 40.f);
  head.tip = Eigen::Vector3f ((50.f - 40.f) * 2.f / 100.f, (40.f - 30.f) * 2.f / 100.f, 2.f);
  const std::vector<agex::PartLabel> labels{head};

  auto ap = [&] (const std::vector<agex::BodyPartDetection> &detections) {
    auto evaluation = agex::DetectionEvaluation::boxOverlap (0.5f, 100.f);
    evaluation.addFrame (detections, labels);
    return evaluation.averagePrecision (agex::BodyPart::Head);
  };
  // 2 px off: IoU = 10.5 / 14.5 = 0.72, a match.
  EXPECT_DOUBLE_EQ (ap ({detectionAt (agex::BodyPart::Head, 52, 40, 2.f, 0.9f)}), 1.0);
  // 5 px off (10 cm, inside the distance criterion): IoU = 7.5 / 17.5 = 0.43, no match.
  EXPECT_DOUBLE_EQ (ap ({detectionAt (agex::BodyPart::Head, 55, 40, 2.f, 0.9f)}), 0.0);
  // Right place, wrong class: no head found.
  EXPECT_DOUBLE_EQ (ap ({detectionAt (agex::BodyPart::Hand, 50, 40, 2.f, 0.9f)}), 0.0);
  // A window twice the part's size on the spot: IoU = 1/4, no match.
  EXPECT_DOUBLE_EQ (ap ({detectionAt (agex::BodyPart::Head, 50, 40, 2.f, 0.9f, 2.f)}), 0.0);
  // A confident miss ranked above the hit halves the precision at full recall.
  EXPECT_DOUBLE_EQ (ap ({detectionAt (agex::BodyPart::Head, 10, 10, 2.f, 0.95f),
                         detectionAt (agex::BodyPart::Head, 51, 41, 2.f, 0.9f)}),
                    0.5);
  // The two hits on one part: only the more confident one counts, the other is a false positive.
  EXPECT_DOUBLE_EQ (ap ({detectionAt (agex::BodyPart::Head, 51, 40, 2.f, 0.9f),
                         detectionAt (agex::BodyPart::Head, 50, 41, 2.f, 0.8f)}),
                    1.0);

  // The same 5 px miss is a hit for the 10 cm criterion (the tip is 0.1 m away).
  agex::DetectionEvaluation by_distance (0.101f);
  by_distance.addFrame ({detectionAt (agex::BodyPart::Head, 55, 40, 2.f, 0.9f)}, labels);
  EXPECT_DOUBLE_EQ (by_distance.averagePrecision (agex::BodyPart::Head), 1.0);
}

TEST (DetectorSettings, KindStoredInTheSettingsAndChecked)
{
  agex::DetectorSettings settings;
  settings.kind = agex::DetectorKind::SlidingWindow;
  settings.sliding_window.stride = 2;
  settings.sliding_window.scales = {0.8f, 1.25f};
  nlohmann::json doc = settings.toJson ();
  const auto read = agex::DetectorSettings::fromJson (doc, "sw.yml");
  EXPECT_EQ (read.kind, agex::DetectorKind::SlidingWindow);
  EXPECT_EQ (read.sliding_window.stride, 2);
  EXPECT_EQ (read.sliding_window.scales, (std::vector<float>{0.8f, 1.25f}));
  // Models written before the field existed are AGEX models; an unknown kind is an error.
  doc.erase ("detector");
  EXPECT_EQ (agex::DetectorSettings::fromJson (doc, "m.yml").kind, agex::DetectorKind::Agex);
  doc["detector"] = "cascade";
  EXPECT_THROW (agex::DetectorSettings::fromJson (doc, "m.yml"), std::invalid_argument);
}

TEST (DetectorSettings, HiddenPeopleStoredAndOffInOlderModels)
{
  agex::DetectorSettings settings;
  EXPECT_TRUE (settings.pipeline.hidden_people);
  settings.pipeline.hidden_people = false;
  nlohmann::json doc = settings.toJson ();
  EXPECT_FALSE (agex::DetectorSettings::fromJson (doc, "m.yml").pipeline.hidden_people);
  doc["pipeline"]["hidden_people"] = true;
  EXPECT_TRUE (agex::DetectorSettings::fromJson (doc, "m.yml").pipeline.hidden_people);
  // Models written before the setting keep the persons they found then.
  doc["pipeline"].erase ("hidden_people");
  EXPECT_FALSE (agex::DetectorSettings::fromJson (doc, "m.yml").pipeline.hidden_people);
  doc["pipeline"]["hidden_people"] = "yes";
  EXPECT_THROW (agex::DetectorSettings::fromJson (doc, "m.yml"), std::invalid_argument);
}

/** The message of what f throws (empty if it does not). */
template <typename F>
std::string
messageOf (F &&f)
{
  try
  {
    f ();
  }
  catch (const std::exception &e)
  {
    return e.what ();
  }
  return std::string ();
}

TEST (DetectorSettings, EveryPipelineSettingIsRangeCheckedWithItsKeyNamed)
{
  // The cases that once took minutes or gigabytes per frame, or gave silent nonsense.
  const std::vector<std::pair<std::string, nlohmann::json>> bad{{"mixed_window_radius", 1e6},
                                                                {"median_window", 1e5},
                                                                {"k", 1e8},
                                                                {"delta_connected", -1},
                                                                {"delta_connected", 100},
                                                                {"floor_distance", 0},
                                                                {"spur_iterations", 1e9},
                                                                {"min_mesh_size", 0.5},
                                                                {"crop_min", nlohmann::json::array ({0, 0})},
                                                                {"remove_floor", "yes"}};
  for (const auto &[key, value] : bad)
  {
    nlohmann::json doc = agex::DetectorSettings ().toJson ();
    doc["pipeline"][key] = value;
    const std::string message = messageOf ([&] { agex::DetectorSettings::fromJson (doc, "m.yml"); });
    EXPECT_NE (message.find ("m.yml: pipeline." + key), std::string::npos) << key << " = " << value.dump () << ": '"
                                                                          << message << "'";
  }
  nlohmann::json doc = agex::DetectorSettings ().toJson ();
  doc["pipeline"].erase ("k");
  EXPECT_NE (messageOf ([&] { agex::DetectorSettings::fromJson (doc, "m.yml"); }).find ("pipeline.k is missing"),
             std::string::npos);
  // The defaults and the bundled model's own values pass.
  EXPECT_NO_THROW (agex::DetectorSettings::fromJson (agex::DetectorSettings ().toJson (), "m.yml"));
  agex::DepthPipelineParams params;
  params.k = 16;
  EXPECT_NO_THROW (params.validate ());
  params.mixed_window_radius = 1000000;
  EXPECT_THROW (params.validate (), std::invalid_argument);
}
}  // namespace

namespace
{
TEST (PersonEvaluation, PeopleFoundByDistanceBandAndFiringOnNobody)
{
  // Person 1 at 1.5 m (its head found), person 2 at 3 m (its hand detected, but below the
  // firing confidence: found at any confidence only), person 3 at 5 m (its foot found by a
  // detection of the wrong class: not found).
  auto label = [] (int person, agex::BodyPart part, float x, float z) {
    agex::PartLabel l;
    l.person = person;
    l.part = part;
    l.tip = Eigen::Vector3f (x, 0.f, z);
    l.base = l.tip + Eigen::Vector3f (0.f, 0.2f, 0.f);
    return l;
  };
  const std::vector<agex::PartLabel> labels{label (1, agex::BodyPart::Head, 0.f, 1.5f),
                                            label (2, agex::BodyPart::Hand, 1.f, 3.f),
                                            label (3, agex::BodyPart::Foot, -1.f, 5.f)};
  auto detection = [] (agex::BodyPart part, float x, float z, int u, int v, float confidence = 0.9f) {
    agex::BodyPartDetection d;
    d.part = part;
    d.confidence = confidence;
    d.position = Eigen::Vector3f (x, 0.f, z);
    d.u = u, d.v = v;
    return d;
  };
  cv::Mat persons (48, 64, CV_8UC1, cv::Scalar (0));
  persons (cv::Rect (10, 10, 10, 10)) = 1;
  const std::vector<agex::BodyPartDetection> detections{detection (agex::BodyPart::Head, 0.02f, 1.5f, 15, 15),
                                                        detection (agex::BodyPart::Hand, -1.f, 5.f, 40, 40),
                                                        detection (agex::BodyPart::Hand, 1.03f, 3.f, 50, 5, 0.2f)};
  agex::PersonEvaluation evaluation (0.1f);
  evaluation.addFrame (detections, labels, &persons);
  const nlohmann::json r = evaluation.report ();
  EXPECT_EQ (r["persons"], 3);
  EXPECT_DOUBLE_EQ (r["person_recall"].get<double> (), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ (r["person_recall_within_4m"].get<double> (), 0.5);
  EXPECT_DOUBLE_EQ (r["person_recall_any_confidence"].get<double> (), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ (r["person_recall_any_confidence_within_4m"].get<double> (), 1.0);
  EXPECT_DOUBLE_EQ (r["bands"][1]["person_recall"].get<double> (), 0.0);
  EXPECT_DOUBLE_EQ (r["bands"][1]["person_recall_any_confidence"].get<double> (), 1.0);
  EXPECT_EQ (r["bands"][0]["persons"], 1);
  EXPECT_DOUBLE_EQ (r["bands"][0]["ap"]["head"].get<double> (), 1.0);
  EXPECT_DOUBLE_EQ (r["bands"][2]["ap"]["foot"].get<double> (), 0.0);
  // The hand at pixel (40, 40) fires on nobody's surface; the head on person 1's does not.
  EXPECT_DOUBLE_EQ (r["non_person_detections_per_frame"].get<double> (), 1.0);
  // Split and merged again: the same report.
  agex::PersonEvaluation a (0.1f), b (0.1f);
  a.addFrame (detections, labels, &persons);
  b.addFrame ({}, labels, nullptr);
  a.merge (agex::PersonEvaluation::fromState (b.state (), "b"));
  EXPECT_EQ (a.report ()["persons"], 6);
  EXPECT_DOUBLE_EQ (a.report ()["person_recall"].get<double> (), 1.0 / 6.0);
  EXPECT_DOUBLE_EQ (a.report ()["person_recall_any_confidence"].get<double> (), 2.0 / 6.0);
  EXPECT_DOUBLE_EQ (a.report ()["non_person_detections_per_frame"].get<double> (), 1.0);
  // A state from before firing detections were counted apart is refused, naming its source,
  // and so are counts that cannot be (more persons found than there are).
  nlohmann::json old_state = evaluation.state ();
  old_state.erase ("found_firing");
  try
  {
    agex::PersonEvaluation::fromState (old_state, "part-1.json");
    ADD_FAILURE () << "an old state was read";
  }
  catch (const std::invalid_argument &e)
  {
    EXPECT_NE (std::string (e.what ()).find ("part-1.json"), std::string::npos) << e.what ();
    EXPECT_NE (std::string (e.what ()).find ("found_firing"), std::string::npos) << e.what ();
  }
  nlohmann::json impossible = evaluation.state ();
  impossible["found_firing"][0] = 5;
  EXPECT_THROW (agex::PersonEvaluation::fromState (impossible, "part-2.json"), std::invalid_argument);
}
}  // namespace

namespace
{
agex::PartLabel
tipAt (agex::BodyPart part, const Eigen::Vector3f &tip)
{
  agex::PartLabel l;
  l.part = part;
  l.tip = tip;
  l.base = tip + Eigen::Vector3f (0.f, 0.2f, 0.f);
  return l;
}

agex::BodyPartDetection
foundAt (agex::BodyPart part, const Eigen::Vector3f &p, float confidence)
{
  agex::BodyPartDetection d;
  d.part = part;
  d.position = p;
  d.confidence = confidence;
  return d;
}

TEST (DetectionEvaluation, TopRecallTakesAsManyDetectionsAsTheFrameHasTips)
{
  using agex::BodyPart;
  const Eigen::Vector3f left (-0.3f, 0.f, 2.f), right (0.3f, 0.f, 2.f), head (0.f, -0.8f, 2.f);
  agex::DetectionEvaluation evaluation (0.1f);
  // Frame 1: two hands; the two most confident hand detections are one right, one on the
  // belly; the third (right, on the other hand) comes too late. The head is found.
  evaluation.addFrame ({foundAt (BodyPart::Hand, left + Eigen::Vector3f (0.05f, 0.f, 0.f), 0.9f),
                        foundAt (BodyPart::Hand, Eigen::Vector3f (0.f, 0.2f, 2.f), 0.8f),
                        foundAt (BodyPart::Hand, right, 0.7f), foundAt (BodyPart::Head, head, 0.4f)},
                       {tipAt (BodyPart::Hand, left), tipAt (BodyPart::Hand, right), tipAt (BodyPart::Head, head)});
  // Frame 2: one hand labelled (the other invisible), found by the best detection; no head
  // detection for the head.
  agex::PartLabel hidden = tipAt (BodyPart::Hand, right);
  hidden.visible = false;
  evaluation.addFrame ({foundAt (BodyPart::Hand, right, 0.6f), foundAt (BodyPart::Hand, left, 0.5f)},
                       {tipAt (BodyPart::Hand, right), hidden, tipAt (BodyPart::Head, head)});
  EXPECT_DOUBLE_EQ (evaluation.topRecall (BodyPart::Hand), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ (evaluation.topRecall (BodyPart::Head), 1.0 / 2.0);
  EXPECT_TRUE (std::isnan (evaluation.topRecall (BodyPart::Foot)));  // no foot labelled
  const auto report = evaluation.report (0.5f);
  EXPECT_DOUBLE_EQ (report["top_recall"]["hand"].get<double> (), 2.0 / 3.0);
  EXPECT_TRUE (report["top_recall"]["foot"].is_null ());
  // Kept through a state and a merge.
  auto merged = agex::DetectionEvaluation::fromState (evaluation.state (), "state");
  merged.merge (evaluation);
  EXPECT_DOUBLE_EQ (merged.topRecall (BodyPart::Hand), 2.0 / 3.0);
}
}  // namespace
