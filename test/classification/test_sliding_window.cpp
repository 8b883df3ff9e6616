// The sliding-window baseline: non-maximum suppression and agex::SlidingWindowDetector
// finding a part planted in a synthetic frame.

#include "test_support.h"

#include <agex/classification/non_maximum_suppression.h>
#include <agex/classification/patch_classifier.h>
#include <agex/classification/sliding_window_detector.h>
#include <agex/features/depth_patch_estimation.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace
{
using agex_test::Camera;
using agex_test::Figure;

TEST (NonMaximumSuppression, KeepsThePeaksOfAHandBuiltScoreMap)
{
  // A 1D score map, 5 cm between cells, radius 8 cm: the two peaks (0.9 at cell 1, 0.8 at
  // cell 4) each suppress their neighbours; class 1's weaker cell next to the first peak
  // survives (suppression is per class).
  const std::vector<float> scores{0.1f, 0.9f, 0.5f, 0.2f, 0.8f, 0.3f};
  const std::vector<int> classes{0, 0, 0, 0, 0, 1};
  std::vector<Eigen::Vector3f> positions;
  for (int i = 0; i < 5; ++i)
    positions.emplace_back (0.05f * i, 0.f, 2.f);
  positions.emplace_back (0.06f, 0.f, 2.f);
  EXPECT_EQ (agex::suppressNonMaxima (positions, classes, scores, 0.08f), (std::vector<std::size_t>{1, 4, 5}));
  // Radius 0 keeps every candidate, sorted by score.
  EXPECT_EQ (agex::suppressNonMaxima (positions, classes, scores, 0.f),
             (std::vector<std::size_t>{1, 4, 2, 5, 3, 0}));
  // A candidate without a finite score or position is dropped, not kept or suppressing:
  // without the first peak, cell 2 leads its side and cell 0 (10 cm from it) survives.
  auto broken = positions;
  broken[1].x () = std::nanf ("");
  EXPECT_EQ (agex::suppressNonMaxima (broken, classes, scores, 0.08f), (std::vector<std::size_t>{4, 2, 5, 0}));
  EXPECT_THROW (agex::suppressNonMaxima (positions, {0}, scores, 0.08f), std::invalid_argument);
}

TEST (NonMaximumSuppression, TwoDimensionalScoreMapLeavesOnePerBump)
{
  // Two Gaussian bumps 0.3 m apart on a 2 cm grid: with a 0.15 m radius the two first kept
  // cells are the bump centres, and no two kept cells are closer than the radius.
  std::vector<Eigen::Vector3f> positions;
  std::vector<float> scores;
  const Eigen::Vector2f a (0.10f, 0.10f), b (0.40f, 0.10f);
  for (int y = 0; y < 11; ++y)
    for (int x = 0; x < 26; ++x)
    {
      const Eigen::Vector2f p (0.02f * x, 0.02f * y);
      positions.emplace_back (p.x (), p.y (), 2.f);
      scores.push_back (std::exp (-(p - a).squaredNorm () / 0.005f) + 0.9f * std::exp (-(p - b).squaredNorm () / 0.005f));
    }
  const std::vector<int> classes (scores.size (), 0);
  const auto kept = agex::suppressNonMaxima (positions, classes, scores, 0.15f);
  ASSERT_GE (kept.size (), 2u);
  EXPECT_LT ((positions[kept[0]].head<2> () - a).norm (), 1e-5f);
  EXPECT_LT ((positions[kept[1]].head<2> () - b).norm (), 1e-5f);
  for (std::size_t i = 0; i < kept.size (); ++i)
    for (std::size_t j = i + 1; j < kept.size (); ++j)
      EXPECT_GE ((positions[kept[i]] - positions[kept[j]]).norm (), 0.15f);
}

// A figure with one arm pointing up: the arm's tip is the part to find.
const Camera kCamera{100.0, 100.0, 39.5, 29.5, 80, 60};  // fx, fy, cx, cy, width, height

Figure
figureAt (double x, double y, double depth)
{
  return agex_test::makeStar (Eigen::Vector2d (x, y), depth, 1, 0.35, 0.05, 0.22, -90.0);
}

constexpr int kPatchSize = 21;
constexpr float kExtent = 0.6f, kClamp = 0.3f;

/** Upright patches of a frame at the given pixel indices. */
pcl::PointCloud<agex::DepthPatch>
uprightPatches (const agex_test::Cloud::Ptr &cloud, const pcl::Indices &indices)
{
  agex::DepthPatchEstimation<pcl::PointXYZ, agex::DepthPatch> estimation;
  estimation.setInputCloud (cloud);
  estimation.setIndices (pcl::IndicesPtr (new pcl::Indices (indices)));
  estimation.setPatchSize (kPatchSize);
  estimation.setPatchExtent (kExtent);
  estimation.setClampDepth (kClamp);
  estimation.setFocalLength (static_cast<float> (kCamera.fx));
  pcl::PointCloud<agex::DepthPatch> patches;
  estimation.compute (patches);
  return patches;
}

/** A one-class model of the arm's tip, trained the sliding-window way: upright patches
  * within 3 cm of the tip against random pixels of the figure farther than 15 cm. */
std::shared_ptr<const agex::PatchClassifier>
tipClassifier ()
{
  static const auto classifier = [] {
    std::mt19937_64 rng (3);
    std::vector<agex::DepthPatch> patches;
    std::vector<int> labels;
    for (int i = 0; i < 12; ++i)
    {
      const Figure f = figureAt (-0.25 + 0.05 * i, 0.10 + 0.02 * (i % 4), 1.8 + 0.04 * i);
      const auto cloud = agex_test::rasterise ({f}, kCamera);
      const Eigen::Vector3f tip = f.tip3D (0);
      pcl::Indices indices;
      std::vector<int> index_labels;
      for (int index = 0; index < static_cast<int> (cloud->size ()); ++index)
      {
        if (!agex_test::isFinite ((*cloud)[index]))
          continue;
        const float d = ((*cloud)[index].getVector3fMap () - tip).norm ();
        if (d <= 0.03f)
        {
          indices.push_back (index);
          index_labels.push_back (0);
        }
        else if (d > 0.15f && rng () % 8 == 0)
        {
          indices.push_back (index);
          index_labels.push_back (-1);
        }
      }
      const auto frame_patches = uprightPatches (cloud, indices);
      patches.insert (patches.end (), frame_patches.begin (), frame_patches.end ());
      labels.insert (labels.end (), index_labels.begin (), index_labels.end ());
    }
    agex::PatchClassifierParams params;
    params.dictionary.fragments_per_class = 30;
    params.dictionary.min_size = 3;
    params.dictionary.max_size = 7;
    params.weak_count = 40;
    auto c = std::make_shared<agex::PatchClassifier> ();
    c->train (patches, labels, 1, params);
    c->setPatchGeometry ({kPatchSize, kExtent, kClamp});
    return c;
  }();
  return classifier;
}

TEST (SlidingWindowDetector, FindsAPlantedPart)
{
  // A figure where no training figure stood, at another depth.
  const Figure f = figureAt (0.12, 0.2, 2.1);
  const auto cloud = agex_test::rasterise ({f}, kCamera);
  agex::SlidingWindowDetector<pcl::PointXYZ> detector;
  detector.setInputCloud (cloud);
  detector.setClassifier (tipClassifier ());
  detector.setStride (2);
  detector.setScales ({0.9f, 1.f, 1.1f});
  std::vector<agex::WindowDetection> detections;
  ASSERT_TRUE (detector.detect (detections));
  ASSERT_FALSE (detections.empty ());
  EXPECT_GT (detector.getWindowCount (), detections.size ());
  const auto &best = detections.front ();
  EXPECT_EQ (best.cls, 0);
  EXPECT_GT (best.confidence, 0.5f);
  EXPECT_LT ((best.position - f.tip3D (0)).norm (), 0.06f) << "best window at pixel (" << best.u << ", " << best.v << ")";
  // Sorted, suppressed, on the stride grid.
  for (std::size_t i = 0; i < detections.size (); ++i)
  {
    EXPECT_EQ (detections[i].u % 2, 0);
    EXPECT_EQ (detections[i].v % 2, 0);
    if (i > 0)
    {
      EXPECT_LE (detections[i].confidence, detections[i - 1].confidence);
    }
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_GE ((detections[i].position - detections[j].position).norm (), detector.getSuppressionRadius ());
  }

  // Only windows centred on the given indices: none near the tip, so the tip is not found.
  pcl::IndicesPtr far_from_tip (new pcl::Indices);
  for (int index = 0; index < static_cast<int> (cloud->size ()); ++index)
    if (agex_test::isFinite ((*cloud)[index]) && ((*cloud)[index].getVector3fMap () - f.tip3D (0)).norm () > 0.2f)
      far_from_tip->push_back (index);
  detector.setIndices (far_from_tip);
  ASSERT_TRUE (detector.detect (detections));
  for (const auto &d : detections)
    EXPECT_GT ((d.position - f.tip3D (0)).norm (), 0.2f);
}

TEST (SlidingWindowDetector, StrideInMetresFollowsTheFocalLengthAndDepth)
{
  // 8 cm between window centres at the figure's 2.1 m: 3.8 pixels at f = 100 (stride 4), 1.9
  // at f = 50 (stride 2), the same windows on the figure at both resolutions.
  const Figure f = figureAt (0.12, 0.2, 2.1);
  for (const double scale : {1.0, 0.5})
  {
    Camera cam = kCamera;
    cam.fx *= scale, cam.fy *= scale;
    cam.width = static_cast<int> (cam.width * scale), cam.height = static_cast<int> (cam.height * scale);
    cam.cx = (cam.width - 1) / 2.0, cam.cy = (cam.height - 1) / 2.0;
    agex::SlidingWindowDetector<pcl::PointXYZ> detector;
    detector.setInputCloud (agex_test::rasterise ({f}, cam));
    detector.setClassifier (tipClassifier ());
    detector.setStrideMetres (0.08f);
    detector.setSuppressionRadius (0.f);
    std::vector<agex::WindowDetection> detections;
    ASSERT_TRUE (detector.detect (detections));
    const int expected = static_cast<int> (std::lround (0.08 * cam.fx / 2.1));
    EXPECT_EQ (detector.getUsedStride (), expected) << "f = " << cam.fx;
    ASSERT_FALSE (detections.empty ());
    for (const auto &d : detections)
    {
      EXPECT_EQ (d.u % expected, 0);
      EXPECT_EQ (d.v % expected, 0);
    }
  }
  // Without metres the pixel stride, and a negative or NaN stride in metres is refused.
  agex_test::QuietPcl quiet;
  agex::SlidingWindowDetector<pcl::PointXYZ> detector;
  detector.setInputCloud (agex_test::rasterise ({f}, kCamera));
  detector.setClassifier (tipClassifier ());
  std::vector<agex::WindowDetection> detections;
  ASSERT_TRUE (detector.detect (detections));
  EXPECT_EQ (detector.getUsedStride (), 3);
  for (const float bad : {-0.01f, std::nanf ("")})
  {
    detector.setStrideMetres (bad);
    EXPECT_FALSE (detector.detect (detections));
  }
}

TEST (SlidingWindowDetector, BadInputIsReportedNotCrashed)
{
  agex_test::QuietPcl quiet;
  agex::SlidingWindowDetector<pcl::PointXYZ> detector;
  std::vector<agex::WindowDetection> detections{agex::WindowDetection ()};
  EXPECT_FALSE (detector.detect (detections));  // no input
  EXPECT_TRUE (detections.empty ());
  detector.setInputCloud (agex_test::rasterise ({figureAt (0.0, 0.1, 2.0)}, kCamera));
  EXPECT_FALSE (detector.detect (detections));  // no classifier
  detector.setClassifier (std::make_shared<agex::PatchClassifier> ());
  EXPECT_FALSE (detector.detect (detections));  // untrained
  detector.setClassifier (tipClassifier ());
  detector.setStride (0);
  EXPECT_FALSE (detector.detect (detections));
  detector.setStride (3);
  detector.setScales ({});
  EXPECT_FALSE (detector.detect (detections));
  detector.setScales ({1.f, std::nanf ("")});
  EXPECT_FALSE (detector.detect (detections));
  detector.setScales ({1.f});
  agex_test::Cloud::Ptr unorganized (new agex_test::Cloud);
  unorganized->push_back (pcl::PointXYZ (0.f, 0.f, 2.f));
  detector.setInputCloud (unorganized);
  EXPECT_FALSE (detector.detect (detections));
  // An all-NaN frame: nothing to find, and no error.
  detector.setInputCloud (agex_test::nanCloud (kCamera.width, kCamera.height));
  EXPECT_TRUE (detector.detect (detections));
  EXPECT_TRUE (detections.empty ());
  EXPECT_EQ (detector.getWindowCount (), 0u);
}
}  // namespace
