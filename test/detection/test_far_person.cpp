// A person too far for a hand to have pixels enough (PersonInfo::too_far) still has a head and
// feet: the detector drops only its hand guesses. The bundled Bonn frame, its scene moved 3 m
// back and seen in the Bonn portrait view (about 5.4 m: a hand covers about 15 pixels there).

#include <agex/detection/body_part_detector.h>
#include <agex/filters/person_segmentation.h>
#include <agex/io/frame_io.h>
#include <agex/simulation/bonn_sensor.h>
#include <agex/simulation/depth_frame_mesh.h>
#include <agex/simulation/frame_reprojection.h>
#include <agex/simulation/sensor_model.h>

#include <gtest/gtest.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <string>
#include <vector>

TEST (BodyPartDetectorFar, TooFarPersonKeepsHeadAndFeetGuessesButNoHands)
{
  const agex::Frame frame = agex::loadFrame (AGEX_SOURCE_DIR "/data/frames/bonn_1_002.png");
  agex::PersonSegmentation<pcl::PointXYZ> segmentation;
  segmentation.setInputCloud (frame.cloud);
  std::vector<pcl::PointIndices> found;
  segmentation.segment (found);
  ASSERT_EQ (found.size (), 1u);
  ASSERT_TRUE (segmentation.getFloorFound ());

  agex::FrameReprojection reprojection;
  reprojection.setInputCloud (frame.cloud);
  agex::DepthMeshSettings mesh;
  mesh.depth_quantum = agex::kBonnDepthStep;
  reprojection.setMeshSettings (mesh);
  agex::ReprojectionMove move;
  move.dz = 3.0;
  reprojection.setMove (move);
  reprojection.setTargetSensor (agex::sensorModel (agex::SynthSensor::Bonn));
  reprojection.setBonnDepthLevels (false);  // the 8-bit levels end at 4.09 m
  reprojection.setFloorPlane (segmentation.getFloorPlane ());
  agex::ReprojectedFrame far;
  reprojection.compute (far);
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>> (far.cloud);

  auto detector = agex::BodyPartDetector<pcl::PointXYZ>::fromModel (AGEX_SOURCE_DIR "/data/models/agex_bonn.yml");
  detector->setInputCloud (cloud);
  std::vector<agex::BodyPartDetection> detections;
  detector->compute (detections);
  const agex::DepthPipelineResult &r = detector->getIntermediate ();
  // Persons come out largest first: the person, then any clutter taken for one.
  ASSERT_GE (r.person_info.size (), 1u);
  EXPECT_GT (r.person_info[0].distance, 5.f);
  ASSERT_TRUE (r.person_info[0].too_far) << r.person_info[0].hand_pixels << " hand pixels";
  int on_person = 0;
  for (const agex::BodyPartDetection &d : detections)
  {
    if (d.person != 0)
      continue;
    ++on_person;
    EXPECT_NE (d.part, agex::BodyPart::Hand) << "a hand guess on a person too far for hands";
  }
  EXPECT_GT (on_person, 0) << "the too-far person lost its head and foot guesses too";
}
