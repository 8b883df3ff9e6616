// The bundled detector on real frames without labels, against what we see in them by hand:
// PCL's five_people.pcd (five people walking away down a corridor, 1.8-2.8 m) and Skeltrack's
// two-person frame (a near person at 1.3 m, one behind at 1.9 m).

#include "test_support.h"

#include <agex/detection/body_part_detector.h>
#include <agex/io/frame_io.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <set>

namespace
{
const std::string kModel = AGEX_SOURCE_DIR "/data/models/agex_bonn.yml";

struct DetectorRun
{
  std::vector<agex::BodyPartDetection> detections;
  agex::DepthPipelineResult intermediate;
};

DetectorRun
detect (const std::string &path)
{
  const agex::Frame frame = agex::loadFrame (path);
  auto detector = agex::BodyPartDetector<pcl::PointXYZ>::fromModel (kModel);
  detector->setInputCloud (frame.cloud);
  DetectorRun run;
  detector->compute (run.detections);
  run.intermediate = detector->getIntermediate ();
  return run;
}
}  // namespace

TEST (BodyPartDetectorReal, FivePeopleAreFivePersonsWithHeadsOnTheirTops)
{
  const std::string path = agex_test::sharedData ("kinect/five_people.pcd");
  AGEX_REQUIRE_SHARED_FILE (path, "PCL's five_people.pcd (../shared/data/kinect)");
  const DetectorRun run = detect (path);
  const agex::DepthPipelineResult &r = run.intermediate;
  ASSERT_TRUE (r.floor_found);
  ASSERT_EQ (r.persons.size (), 5u);
  for (const agex::PersonInfo &info : r.person_info)
  {
    EXPECT_GT (info.distance, 1.7f);
    EXPECT_LT (info.distance, 2.9f);
    EXPECT_FALSE (info.too_far);
  }
  // Every detection belongs to one of the five; every head detection that fires (0.3) lies
  // on the top of its person (within 0.35 m of the person's top, above the floor).
  std::set<int> with_head;
  for (const agex::BodyPartDetection &d : run.detections)
  {
    ASSERT_GE (d.person, 0);
    ASSERT_LT (d.person, 5);
    if (d.part != agex::BodyPart::Head || d.confidence < 0.3f)
      continue;
    const float height = r.floor_plane.head<3> ().dot (d.position) + r.floor_plane[3];
    EXPECT_GT (height, r.person_info[static_cast<std::size_t> (d.person)].top - 0.35f)
        << "head at pixel " << d.u << "," << d.v;
    with_head.insert (d.person);
  }
  // All five are within 4 m and should have their heads found; the bundled model, trained on
  // Bonn's people facing the camera, finds the heads of the three nearest, seen from behind
  // (doc/results.md, "People anywhere").
  EXPECT_GE (with_head.size (), 3u);
  EXPECT_TRUE (with_head.count (0) && with_head.count (1) && with_head.count (2));
}

TEST (BodyPartDetectorReal, SkeltrackTwoPeopleHaveTheirOwnDetections)
{
  const std::string path = agex_test::sharedData ("kinect/skeltrack/depth-data-1399145206.u16");
  AGEX_REQUIRE_SHARED_FILE (path, "Skeltrack's depth frames (../shared/data/kinect/skeltrack)");
  const DetectorRun run = detect (path);
  ASSERT_EQ (run.intermediate.persons.size (), 2u);
  std::set<int> persons;
  for (const agex::BodyPartDetection &d : run.detections)
  {
    ASSERT_GE (d.person, 0);
    ASSERT_LT (d.person, 2);
    persons.insert (d.person);
  }
  EXPECT_EQ (persons.size (), 2u);
}

TEST (BodyPartDetectorWorkingDensity, DetectionsComeAtTheInputsPixelsAndWhereEveryPixelPutsThem)
{
  // The bundled Bonn frame (640x480, a person at about 2 m) through the bundled detector at
  // every pixel and at a working spacing of 1 cm (every second pixel): the detections are
  // reported at the input's pixels, where the camera sees their positions, and the head is
  // found where the full-density run finds it.
  const agex::Frame frame = agex::loadFrame (AGEX_SOURCE_DIR "/data/frames/bonn_1_002.png");
  const auto fx = static_cast<float> (frame.intrinsics.fx), fy = static_cast<float> (frame.intrinsics.fy);
  std::vector<agex::BodyPartDetection> found[2];
  for (int k = 0; k < 2; ++k)
  {
    auto detector = agex::BodyPartDetector<pcl::PointXYZ>::fromModel (AGEX_SOURCE_DIR "/data/models/agex_bonn.yml");
    agex::DetectorSettings settings = detector->getSettings ();
    settings.pipeline.working_spacing = k == 0 ? 0.f : 0.01f;
    detector->setSettings (settings);
    detector->setFocalLength (fx, fy);
    detector->setInputCloud (frame.cloud);
    detector->compute (found[k]);
    const agex::DepthPipelineResult &r = detector->getIntermediate ();
    ASSERT_EQ (r.stride, k == 0 ? 1 : 2);
    ASSERT_TRUE (r.filtered);
    EXPECT_EQ (r.filtered->width, k == 0 ? 640u : 320u);
    ASSERT_FALSE (found[k].empty ());
    for (const auto &d : found[k])
    {
      SCOPED_TRACE ("detection at " + std::to_string (d.u) + ", " + std::to_string (d.v));
      ASSERT_TRUE (d.u >= 0 && d.u < 640 && d.v >= 0 && d.v < 480);
      EXPECT_NEAR (fx * d.position.x () / d.position.z () + frame.intrinsics.cx, d.u, 1.0 + r.stride);
      EXPECT_NEAR (fy * d.position.y () / d.position.z () + frame.intrinsics.cy, d.v, 1.0 + r.stride);
    }
  }
  const auto best_head = [] (const std::vector<agex::BodyPartDetection> &detections) {
    const agex::BodyPartDetection *best = nullptr;
    for (const auto &d : detections)
      if (d.part == agex::BodyPart::Head && (!best || d.confidence > best->confidence))
        best = &d;
    return best;
  };
  const agex::BodyPartDetection *every = best_head (found[0]), *working = best_head (found[1]);
  ASSERT_TRUE (every && working);
  EXPECT_LT ((every->position - working->position).norm (), 0.1f);
}

TEST (BodyPartDetectorCascade, KeepsTheConfidentDetectionsExactlyAndClassifiesAsMany)
{
  // The bundled Bonn frame through the bundled detector with its soft cascade off and at the
  // default confidence and miss rate: the same candidates are classified, the cascade drops some of the
  // least confident, and every detection well above its level comes out unchanged.
  const agex::Frame frame = agex::loadFrame (AGEX_SOURCE_DIR "/data/frames/bonn_1_002.png");
  auto detector = agex::BodyPartDetector<pcl::PointXYZ>::fromModel (AGEX_SOURCE_DIR "/data/models/agex_bonn.yml");
  ASSERT_FALSE (detector->getModel ()->classifier ().cascade ().empty ()) << "the bundled model has no cascade";
  EXPECT_EQ (detector->getCascadeMinConfidence (), agex::BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMinConfidence);
  EXPECT_THROW (detector->setCascadeMinConfidence (1.f), std::invalid_argument);
  EXPECT_THROW (detector->setCascadeMinConfidence (-0.1f), std::invalid_argument);
  EXPECT_THROW (detector->setCascadeMinConfidence (std::numeric_limits<float>::quiet_NaN ()), std::invalid_argument);
  EXPECT_EQ (detector->getCascadeMissRate (), agex::BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMissRate);
  EXPECT_THROW (detector->setCascadeMissRate (0.6f), std::invalid_argument);
  EXPECT_THROW (detector->setCascadeMissRate (std::numeric_limits<float>::quiet_NaN ()), std::invalid_argument);
  detector->setFocalLength (static_cast<float> (frame.intrinsics.fx), static_cast<float> (frame.intrinsics.fy));
  detector->setInputCloud (frame.cloud);
  std::vector<agex::BodyPartDetection> found[2];
  std::size_t classified[2];
  for (int k = 0; k < 2; ++k)
  {
    detector->setCascadeMinConfidence (k == 0 ? 0.f : agex::BodyPartDetector<pcl::PointXYZ>::kDefaultCascadeMinConfidence);
    detector->compute (found[k]);
    classified[k] = detector->getPatchesClassified ();
  }
  EXPECT_EQ (classified[0], classified[1]);
  EXPECT_GT (classified[0], 20u);
  ASSERT_FALSE (found[1].empty ());
  EXPECT_LT (found[1].size (), found[0].size ()) << "the cascade rejected nothing";
  int confident = 0;
  for (const auto &d : found[0])
  {
    if (d.confidence < 0.5f)
      continue;
    ++confident;
    const bool kept = std::any_of (found[1].begin (), found[1].end (), [&d] (const agex::BodyPartDetection &e) {
      return e.part == d.part && e.confidence == d.confidence && e.u == d.u && e.v == d.v;
    });
    EXPECT_TRUE (kept) << agex::bodyPartName (d.part) << " at " << d.u << ", " << d.v << " (confidence "
                       << d.confidence << ") lost";
  }
  EXPECT_GE (confident, 3);
}
