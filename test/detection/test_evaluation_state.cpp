// Evaluations run apart and merged (agex_eval over MPI ranks or --shard runs): frames split
// into contiguous parts, each part's state written as JSON, read back and merged in order,
// give the serial evaluation exactly (its state and its report, ties in confidence included);
// different criteria and malformed states are refused with the key named.

#include <agex/detection/detection_evaluation.h>

#include <gtest/gtest.h>

#include <random>

namespace
{
struct Frame
{
  std::vector<agex::BodyPartDetection> detections;
  std::vector<agex::PartLabel> labels;
  pcl::PointCloud<agex::InterestPoint> points;
  std::vector<agex::FusedCandidate> candidates;
};

/** Frames of a few labelled parts and detections near them or not, confidences on a coarse
  * grid so that ties occur. */
std::vector<Frame>
randomFrames (int n, unsigned seed)
{
  std::mt19937 rng (seed);
  std::uniform_real_distribution<float> offset (-0.15f, 0.15f);
  std::uniform_int_distribution<int> part (0, agex::kBodyPartCount - 1), count (0, 4), grid (0, 10);
  std::vector<Frame> frames (n);
  for (auto &f : frames)
  {
    for (int i = count (rng); i > 0; --i)
    {
      agex::PartLabel l;
      l.part = static_cast<agex::BodyPart> (part (rng));
      l.tip = Eigen::Vector3f (offset (rng) * 5.f, offset (rng) * 5.f, 2.f + offset (rng));
      l.base = l.tip + Eigen::Vector3f (0.f, 0.1f, 0.f);
      l.tip_px = Eigen::Vector2f (100.f + 100.f * l.tip.x () / l.tip.z (), 100.f + 100.f * l.tip.y () / l.tip.z ());
      l.visible = grid (rng) > 1;
      f.labels.push_back (l);
      agex::InterestPoint p;
      p.getVector3fMap () = l.tip + Eigen::Vector3f (offset (rng), offset (rng), 0.f);
      p.rank = 2 + count (rng);
      f.points.push_back (p);
    }
    for (int i = count (rng); i > 0; --i)
    {
      agex::BodyPartDetection d;
      d.part = static_cast<agex::BodyPart> (part (rng));
      d.confidence = grid (rng) / 10.f;
      const Eigen::Vector3f near = f.labels.empty () ? Eigen::Vector3f (0.f, 0.f, 2.f) : f.labels[0].tip;
      d.position = near + Eigen::Vector3f (offset (rng), offset (rng), offset (rng) * 0.2f);
      d.orientation = Eigen::Vector3f (offset (rng), -1.f, 0.f).normalized ();
      d.u = static_cast<int> (100.f + 100.f * d.position.x () / d.position.z ());
      d.v = static_cast<int> (100.f + 100.f * d.position.y () / d.position.z ());
      f.detections.push_back (d);
      agex::FusedCandidate c;
      c.position = d.position;
      c.sources = agex::kFromModeTip;
      f.candidates.push_back (c);
    }
  }
  return frames;
}

/** A state through its JSON text and back, as a rank or a shard hands it on. */
template <typename Evaluation>
Evaluation
throughText (const Evaluation &evaluation)
{
  return Evaluation::fromState (nlohmann::json::parse (evaluation.state ().dump ()), "test");
}

void
checkSplitsMergeToTheSerialEvaluation (const agex::DetectionEvaluation &empty)
{
  const auto frames = randomFrames (60, 7);
  agex::DetectionEvaluation serial = empty;
  agex::CandidateCoverage serial_coverage (0.1f);
  for (const auto &f : frames)
  {
    serial.addFrame (f.detections, f.labels);
    serial_coverage.addFrame (f.points, f.candidates, f.labels);
  }
  ASSERT_GT (serial.report (0.75f)["labels"]["head"].get<int> (), 0);
  for (std::size_t parts : {1u, 2u, 3u, 7u})
  {
    agex::DetectionEvaluation merged = empty;
    agex::CandidateCoverage merged_coverage (0.1f);
    for (std::size_t k = 0; k < parts; ++k)
    {
      agex::DetectionEvaluation part = empty;
      agex::CandidateCoverage part_coverage (0.1f);
      for (std::size_t i = k * frames.size () / parts; i < (k + 1) * frames.size () / parts; ++i)
      {
        part.addFrame (frames[i].detections, frames[i].labels);
        part_coverage.addFrame (frames[i].points, frames[i].candidates, frames[i].labels);
      }
      merged.merge (throughText (part));
      merged_coverage.merge (throughText (part_coverage));
    }
    EXPECT_EQ (merged.state (), serial.state ()) << parts << " parts";
    EXPECT_EQ (merged.report (0.75f), serial.report (0.75f)) << parts << " parts";
    EXPECT_EQ (merged_coverage.report (), serial_coverage.report ()) << parts << " parts";
  }
}

TEST (EvaluationState, SplitsMergeToTheSerialEvaluationByDistance)
{
  checkSplitsMergeToTheSerialEvaluation (agex::DetectionEvaluation (0.1f));
}

TEST (EvaluationState, SplitsMergeToTheSerialEvaluationByOverlap)
{
  checkSplitsMergeToTheSerialEvaluation (agex::DetectionEvaluation::boxOverlap (0.5f, 100.f));
}

TEST (EvaluationState, DifferentCriteriaAreNotMerged)
{
  agex::DetectionEvaluation a (0.1f);
  EXPECT_THROW (a.merge (agex::DetectionEvaluation (0.2f)), std::invalid_argument);
  EXPECT_THROW (a.merge (agex::DetectionEvaluation::boxOverlap (0.5f, 100.f)), std::invalid_argument);
  agex::CandidateCoverage c (0.1f);
  EXPECT_THROW (c.merge (agex::CandidateCoverage (0.2f)), std::invalid_argument);
}

TEST (EvaluationState, MalformedStatesAreRefusedWithTheKeyNamed)
{
  agex::DetectionEvaluation e (0.1f);
  const auto frames = randomFrames (5, 3);
  for (const auto &f : frames)
    e.addFrame (f.detections, f.labels);
  const nlohmann::json good = e.state ();
  auto expectRefused = [] (const nlohmann::json &state, const std::string &needle) {
    try
    {
      agex::DetectionEvaluation::fromState (state, "part-3.json");
      ADD_FAILURE () << "accepted: " << state.dump ().substr (0, 200);
    }
    catch (const std::invalid_argument &e)
    {
      EXPECT_NE (std::string (e.what ()).find ("part-3.json"), std::string::npos) << e.what ();
      EXPECT_NE (std::string (e.what ()).find (needle), std::string::npos) << e.what ();
    }
  };
  expectRefused (nlohmann::json::array (), "not a JSON object");
  auto bad = good;
  bad["format"] = "something else";
  expectRefused (bad, "format");
  bad = good;
  bad.erase ("frames");
  expectRefused (bad, "frames");
  bad = good;
  bad["frames"] = -1;
  expectRefused (bad, "frames");
  bad = good;
  bad["positives"] = {1, 2};
  expectRefused (bad, "positives");
  bad = good;
  bad["scored"][0] = {{1.5, 1}};
  expectRefused (bad, "scored confidence");
  bad = good;
  bad["scored"][1] = {{0.5, 2}};
  expectRefused (bad, "scored correct");
  bad = good;
  bad["pairs"] = {{7, 0, 0.5}};
  expectRefused (bad, "pairs truth");
  bad = good;
  bad["orientation_errors"][2] = {"x"};
  expectRefused (bad, "orientation_errors");
  bad = good;
  bad["radius"] = nullptr;
  expectRefused (bad, "radius");
  EXPECT_EQ (agex::DetectionEvaluation::fromState (good, "part-3.json").state (), good);

  auto coverage = agex::CandidateCoverage (0.1f).state ();
  coverage["covered"][0][0] = 5;  // more covered than labels
  EXPECT_THROW (agex::CandidateCoverage::fromState (coverage, "x"), std::invalid_argument);
}
}  // namespace
