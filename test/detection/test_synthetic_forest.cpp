// The bundled synthetic-only forest (data/models/agex_synthetic_forest.agexforest, trained on
// synthetic people alone) on real frames of people it never saw, in forest mode: Skeltrack's
// close-range upper body (another person, another Kinect, background removed) gets its head
// on the top of the person.

#include "test_support.h"

#include <agex/classification/body_part_forest.h>
#include <agex/detection/body_part_detector.h>
#include <agex/io/frame_io.h>

#include <gtest/gtest.h>

#include <algorithm>

namespace
{
const std::string kForest = AGEX_SOURCE_DIR "/data/models/agex_synthetic_forest.agexforest";
const std::string kPipeline = AGEX_SOURCE_DIR "/data/models/agex_bonn_agex.yml";

struct ForestRun
{
  std::vector<agex::BodyPartDetection> detections;
  agex::DepthPipelineResult intermediate;
  pcl::PointCloud<pcl::PointXYZ>::ConstPtr cloud;
};

ForestRun
forestMode (const std::string &path)
{
  const agex::Frame frame = agex::loadFrame (path);
  auto detector = agex::BodyPartDetector<pcl::PointXYZ>::fromModel (kPipeline);
  detector->setForest (agex::BodyPartForest::load (kForest));
  detector->setMode (agex::DetectorMode::Forest);
  detector->setInputCloud (frame.cloud);
  ForestRun run;
  detector->compute (run.detections);
  run.intermediate = detector->getIntermediate ();
  run.cloud = frame.cloud;
  return run;
}

/** The best head detection, or null. */
const agex::BodyPartDetection *
bestHead (const std::vector<agex::BodyPartDetection> &detections)
{
  const agex::BodyPartDetection *best = nullptr;
  for (const auto &d : detections)
    if (d.part == agex::BodyPart::Head && (!best || d.confidence > best->confidence))
      best = &d;
  return best;
}
}  // namespace

TEST (SyntheticForestReal, SkeltrackUpperBodyHasItsHeadOnTop)
{
  const std::string path = agex_test::sharedData ("kinect/skeltrack/depth-data-1028894671.u16");
  AGEX_REQUIRE_SHARED_FILE (path, "Skeltrack's depth frames (../shared/data/kinect/skeltrack)");
  const ForestRun run = forestMode (path);
  ASSERT_EQ (run.intermediate.persons.size (), 1u);
  // The person's rows: the head's pixel lies in the top fifth of them.
  int top = run.cloud->height, bottom = 0;
  for (const int i : run.intermediate.persons.front ().indices)
  {
    const int v = i / static_cast<int> (run.cloud->width);
    top = std::min (top, v);
    bottom = std::max (bottom, v);
  }
  const agex::BodyPartDetection *head = bestHead (run.detections);
  ASSERT_NE (head, nullptr) << "no head detected";
  EXPECT_LT (head->v, top + 0.2 * (bottom - top)) << "head at row " << head->v << ", person rows " << top << "-" << bottom;
  EXPECT_GT (head->confidence, 0.3f);
}
