// agex::RgbdContourAnnotator on hand-built frames: which meshes are people (metric size,
// silhouette fill, the most central with max_people), anchors from the interest points, too
// short people, and bad input.

#include <agex/landmarks/rgbd_contour_annotator.h>

#include "test_support.h"

#include <opencv2/imgproc.hpp>

namespace
{
constexpr float kMetresPerPixel = 0.011f;  // a 164-pixel figure is 1.8 m tall

// A frame of width x height at 3 m; meshes are drawn into it as masks.
struct Frame
{
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud;
  std::vector<pcl::PointIndices> meshes;
  pcl::PointCloud<agex::InterestPoint> points;

  Frame (int width, int height) : cloud (new pcl::PointCloud<pcl::PointXYZ> (width, height))
  {
    for (int v = 0; v < height; ++v)
      for (int u = 0; u < width; ++u)
        cloud->at (u, v) = pcl::PointXYZ (u * kMetresPerPixel, v * kMetresPerPixel, 3.f);
  }

  void
  addMesh (const cv::Mat &mask, const std::vector<cv::Point> &extremities = {})
  {
    pcl::PointIndices mesh;
    for (int v = 0; v < mask.rows; ++v)
      for (int u = 0; u < mask.cols; ++u)
        if (mask.at<unsigned char> (v, u))
          mesh.indices.push_back (v * mask.cols + u);
    const int id = static_cast<int> (meshes.size ());
    meshes.push_back (mesh);
    for (std::size_t k = 0; k < extremities.size (); ++k)
    {
      agex::InterestPoint p;
      p.mesh = id;
      p.rank = static_cast<int> (k) + 2;
      p.u = extremities[k].x;
      p.v = extremities[k].y;
      points.push_back (p);
    }
  }

  std::vector<agex::RgbdPerson>
  annotate (const agex::RgbdPersonSelectionParams &params, std::vector<agex::RgbdRejection> *rejections = nullptr)
  {
    agex::RgbdContourAnnotator annotator;
    annotator.setInputCloud (cloud);
    annotator.setMeshes (meshes);
    annotator.setInterestPoints (points);
    annotator.setParams (params);
    std::vector<agex::RgbdPerson> people;
    annotator.compute (people);
    if (rejections)
      *rejections = annotator.rejections ();
    return people;
  }
};

// A stick figure, arms held out, 164 pixels tall with its head top at (cx, top).
cv::Mat
figure (cv::Size size, int cx, int top, std::vector<cv::Point> *extremities = nullptr)
{
  cv::Mat mask = cv::Mat::zeros (size, CV_8UC1);
  const cv::Point head (cx, top + 12), neck (cx, top + 24), hip (cx, top + 94);
  cv::circle (mask, head, 12, 255, cv::FILLED);
  cv::line (mask, neck, hip, 255, 28);
  const cv::Point hand_l (cx - 50, top + 50), hand_r (cx + 50, top + 50), foot_l (cx - 25, top + 158),
    foot_r (cx + 25, top + 158);
  for (const cv::Point &end : {hand_l, hand_r})
    cv::line (mask, neck + cv::Point (0, 8), end, 255, 7);
  for (const cv::Point &end : {foot_l, foot_r})
    cv::line (mask, hip, end, 255, 10);
  if (extremities)
    *extremities = {foot_r, cv::Point (cx, top), hand_l, foot_l, hand_r};
  return mask;
}

TEST (RgbdContourAnnotator, KeepsPeopleAndSaysWhyTheRestIsNot)
{
  Frame frame (320, 240);
  std::vector<cv::Point> extremities;
  frame.addMesh (figure (cv::Size (320, 240), 160, 40, &extremities), extremities);
  cv::Mat wall = cv::Mat::zeros (240, 320, CV_8UC1), box = wall.clone (), slab = wall.clone ();
  wall (cv::Rect (0, 0, 320, 120)).setTo (255);    // 3.5 m wide, 1.3 m tall
  box (cv::Rect (10, 200, 30, 30)).setTo (255);    // 0.3 m tall
  slab (cv::Rect (260, 40, 40, 164)).setTo (255);  // person-sized, but it fills its box
  frame.addMesh (wall);
  frame.addMesh (box);
  frame.addMesh (slab);
  std::vector<agex::RgbdRejection> rejections;
  const auto people = frame.annotate (agex::RgbdPersonSelectionParams (), &rejections);
  ASSERT_EQ (people.size (), 1u);
  EXPECT_EQ (people[0].mesh, 0);
  EXPECT_FALSE (people[0].too_small);
  const agex::ContourAnnotation &a = people[0].annotation;
  ASSERT_TRUE (a.ok);
  EXPECT_LT (cv::norm (a.landmarks[0] - cv::Point2f (160, 40)), 4.0);
  // The extremities anchor the hands: landmarks 36 and 144 at the hand tips.
  EXPECT_LT (cv::norm (a.landmarks[36] - cv::Point2f (110, 90)), 8.0) << a.landmarks[36];
  EXPECT_LT (cv::norm (a.landmarks[144] - cv::Point2f (210, 90)), 8.0) << a.landmarks[144];
  for (int k = 0; k < agex::kContourAnchorCount; ++k)
    EXPECT_TRUE (a.anchor_from_hint[k]) << k;
  ASSERT_EQ (rejections.size (), 3u);
  EXPECT_EQ (rejections[0].mesh, 1);
  EXPECT_EQ (rejections[0].reason, "wider than a person");
  EXPECT_EQ (rejections[1].reason, "shorter than a person");
  EXPECT_NE (rejections[2].reason.find ("fills its box"), std::string::npos);
}

TEST (RgbdContourAnnotator, MaxPeopleKeepsTheMostCentralAndShortPeopleAreIgnoreBoxes)
{
  Frame frame (480, 240);
  frame.addMesh (figure (cv::Size (480, 240), 80, 40));
  frame.addMesh (figure (cv::Size (480, 240), 250, 40));
  frame.addMesh (figure (cv::Size (480, 240), 400, 40));
  agex::RgbdPersonSelectionParams params;
  auto people = frame.annotate (params);
  ASSERT_EQ (people.size (), 3u);
  EXPECT_EQ (people[0].mesh, 1);  // most central first
  EXPECT_LE (people[0].centre_distance_px, people[1].centre_distance_px);
  params.max_people = 1;
  std::vector<agex::RgbdRejection> rejections;
  people = frame.annotate (params, &rejections);
  ASSERT_EQ (people.size (), 1u);
  EXPECT_EQ (people[0].mesh, 1);
  EXPECT_EQ (rejections.size (), 2u);
  // Shorter (in pixels) than min_height_px: listed as too small, and not counted by max_people.
  params.max_people = 0;
  params.min_height_px = 500;
  people = frame.annotate (params);
  ASSERT_EQ (people.size (), 3u);
  for (const auto &person : people)
    EXPECT_TRUE (person.too_small);
  // Metric limits come from the params.
  params.min_height_px = 0;
  params.min_person_height = 2.0f;
  EXPECT_TRUE (frame.annotate (params).empty ());
}

TEST (RgbdContourAnnotator, BadInputGivesNoPeopleNotACrash)
{
  agex_test::QuietPcl quiet;
  agex::RgbdContourAnnotator annotator;
  std::vector<agex::RgbdPerson> people (1);
  annotator.compute (people);  // no cloud
  EXPECT_TRUE (people.empty ());
  auto unorganized = std::make_shared<pcl::PointCloud<pcl::PointXYZ>> ();
  unorganized->resize (10);
  annotator.setInputCloud (unorganized);
  annotator.compute (people);
  EXPECT_TRUE (people.empty ());
  Frame frame (40, 30);
  pcl::PointIndices outside;
  outside.indices = {5, 40 * 30 + 7};
  annotator.setInputCloud (frame.cloud);
  annotator.setMeshes ({outside});
  annotator.compute (people);
  EXPECT_TRUE (people.empty ());
}
}  // namespace
