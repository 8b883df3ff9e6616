// agex::DepthPatchEstimation: patches of an oriented limb are the same at every
// in-plane angle once aligned (and differ without), values are relative depths with
// clamping and a background, the metric extent makes distance irrelevant, the focal
// length is estimated from the cloud, bad input never crashes, and agex::DepthPatch
// survives a PCD round trip. On a real Bonn frame: 20 patches, timed.

#include "test_support.h"

#include <agex/io/frame_io.h>
#include <agex/features/depth_patch_estimation.h>
#include <agex/keypoints/agex_keypoint.h>

#include <pcl/common/io.h>
#include <pcl/io/pcd_io.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <random>

namespace
{
using namespace agex_test;
using Patches = pcl::PointCloud<agex::DepthPatch>;
using IPCloud = pcl::PointCloud<agex::InterestPoint>;
using Estimation = agex::DepthPatchEstimation<pcl::PointXYZ>;

constexpr double kPi = 3.14159265358979323846;

Camera
kinectCamera ()
{
  return Camera ();  // 320x240, f = 525
}

/** The 144x176 portrait view of the Bonn data: f = 525 * 0.4. */
Camera
portraitCamera ()
{
  Camera cam;
  cam.fx = cam.fy = 210.0;
  cam.width = 144;
  cam.height = 176;
  cam.cx = 71.5;
  cam.cy = 87.5;
  return cam;
}

/** A limb: a capsule whose front half bulges towards the camera (a cylinder of
  * radius r around an axis at axis_depth), in front of a plane. The tip's cap centre
  * projects exactly onto pixel (tip_u, tip_v); the limb extends from there away from
  * its orientation (angle_deg in the image: 0 = +x, 90 = +y, down). */
struct LimbScene
{
  double axis_depth = 2.0;
  double radius = 0.05;
  double length = 0.45;  ///< between the two cap centres
  double angle_deg = 0.0;
  double plane_depth = 2.2;  ///< <= 0: no plane (NaN background)
  int tip_u = -1, tip_v = -1;  ///< default: the image centre

  Eigen::Vector2d direction () const
  {
    const double a = angle_deg * kPi / 180.0;
    return Eigen::Vector2d (std::cos (a), std::sin (a));
  }
};

struct Rendered
{
  Cloud::Ptr cloud;
  int tip_index = -1;
  Eigen::Vector3f orientation;
};

Rendered
renderLimb (const LimbScene &s, const Camera &cam)
{
  Rendered r;
  r.cloud = nanCloud (cam.width, cam.height);
  const int tu = s.tip_u >= 0 ? s.tip_u : cam.width / 2, tv = s.tip_v >= 0 ? s.tip_v : cam.height / 2;
  const Eigen::Vector2d tip ((tu - cam.cx) * s.axis_depth / cam.fx, (tv - cam.cy) * s.axis_depth / cam.fy);
  const Eigen::Vector2d dir = s.direction ();
  const Eigen::Vector2d base = tip - s.length * dir;
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u)
    {
      const Eigen::Vector2d p ((u - cam.cx) * s.axis_depth / cam.fx, (v - cam.cy) * s.axis_depth / cam.fy);
      const double t = std::clamp ((p - base).dot (dir), 0.0, s.length);
      const double d = (p - (base + t * dir)).norm ();
      if (d <= s.radius)
        (*r.cloud) (u, v) = rayPoint (cam, u, v, s.axis_depth - std::sqrt (s.radius * s.radius - d * d));
      else if (s.plane_depth > 0)
        (*r.cloud) (u, v) = rayPoint (cam, u, v, s.plane_depth);
    }
  r.tip_index = tv * cam.width + tu;
  r.orientation = Eigen::Vector3f (static_cast<float> (dir.x ()), static_cast<float> (dir.y ()), 0.f);
  return r;
}

IPCloud::Ptr
interestPoints (const Cloud &cloud, const std::vector<int> &indices, const std::vector<Eigen::Vector3f> &orientations)
{
  IPCloud::Ptr points (new IPCloud);
  for (std::size_t i = 0; i < indices.size (); ++i)
  {
    agex::InterestPoint ip;
    ip.getVector3fMap () = cloud[indices[i]].getVector3fMap ();
    ip.getOrientationVector3fMap () = orientations[i];
    ip.u = indices[i] % static_cast<int> (cloud.width);
    ip.v = indices[i] / static_cast<int> (cloud.width);
    points->push_back (ip);
  }
  return points;
}

/** Patches at the given indices; orientations (same order) unless null. */
Patches
computePatches (const Cloud::ConstPtr &cloud, const std::vector<int> &indices,
                const std::vector<Eigen::Vector3f> *orientations, float focal = 0.f, Estimation *estimation = nullptr)
{
  Estimation local;
  Estimation &est = estimation ? *estimation : local;
  est.setInputCloud (cloud);
  est.setIndices (pcl::IndicesPtr (new pcl::Indices (indices.begin (), indices.end ())));
  est.setInterestPoints (orientations ? interestPoints (*cloud, indices, *orientations) : nullptr);
  est.setFocalLength (focal);
  Patches out;
  est.compute (out);
  return out;
}

agex::DepthPatch
limbPatch (const LimbScene &s, const Camera &cam, bool oriented, float extent = 0.6f)
{
  const Rendered r = renderLimb (s, cam);
  const std::vector<Eigen::Vector3f> orientations{r.orientation};
  Estimation est;
  est.setPatchExtent (extent);
  const Patches out = computePatches (r.cloud, {r.tip_index}, oriented ? &orientations : nullptr,
                                      static_cast<float> (cam.fx), &est);
  EXPECT_EQ (out.size (), 1u);
  return out.empty () ? agex::DepthPatch () : out[0];
}

struct PatchDifference
{
  double mean_abs = 0;        ///< mean |a - b| over the cells (metres)
  double differing = 0;       ///< fraction of cells with |a - b| > 0.03 m
};

PatchDifference
compare (const agex::DepthPatch &a, const agex::DepthPatch &b)
{
  EXPECT_EQ (a.size, b.size);
  PatchDifference d;
  const int cells = a.size * a.size;
  for (int i = 0; i < cells; ++i)
  {
    const double diff = std::abs (a.patch[i] - b.patch[i]);
    d.mean_abs += diff;
    d.differing += diff > 0.03 ? 1 : 0;
  }
  d.mean_abs /= cells;
  d.differing /= cells;
  return d;
}

// ---------------------------------------------------------------------------
// Rotation

void
expectRotationInvariance (const Camera &cam, double max_differing, double max_mean_abs)
{
  LimbScene scene;
  const agex::DepthPatch reference = limbPatch (scene, cam, true);
  const agex::DepthPatch unrotated_reference = limbPatch (scene, cam, false);
  for (const double angle : {30.0, 90.0, 145.0, 200.0, 270.0, 333.0})
  {
    SCOPED_TRACE ("limb at " + std::to_string (angle) + " deg");
    scene.angle_deg = angle;
    const PatchDifference aligned = compare (limbPatch (scene, cam, true), reference);
    EXPECT_LT (aligned.differing, max_differing);
    EXPECT_LT (aligned.mean_abs, max_mean_abs);
    // The same comparison without orientations fails by far.
    const PatchDifference unaligned = compare (limbPatch (scene, cam, false), unrotated_reference);
    EXPECT_GT (unaligned.differing, 3 * max_differing);
    EXPECT_GT (unaligned.mean_abs, 3 * max_mean_abs);
    std::printf ("  %5.0f deg: aligned %.2f%% cells differ (mean |d| %.4f m), unaligned %.2f%% (%.4f m)\n", angle,
                 100 * aligned.differing, aligned.mean_abs, 100 * unaligned.differing, unaligned.mean_abs);
  }
}

TEST (DepthPatchRotation, AlignedLimbGivesTheSamePatchAtEveryAngle)
{
  expectRotationInvariance (kinectCamera (), 0.02, 0.004);
}

TEST (DepthPatchRotation, AlignedLimbGivesTheSamePatchInThePortraitView)
{
  // 1.5 pixels per cell: nearest-pixel sampling shows a little more.
  expectRotationInvariance (portraitCamera (), 0.02, 0.004);
}

TEST (DepthPatchRotation, OrientationPointsDownThePatch)
{
  for (const double angle : {0.0, 90.0, 200.0})
  {
    SCOPED_TRACE ("limb at " + std::to_string (angle) + " deg");
    LimbScene scene;
    scene.angle_deg = angle;
    const agex::DepthPatch p = limbPatch (scene, kinectCamera (), true);
    ASSERT_EQ (p.size, 41);
    const int c = 20;
    // The limb (at most radius = 0.05 behind the tip's front) lies above the centre,
    // the plane (0.25 behind) below it and to the sides.
    for (int row = 0; row < c - 4; ++row)
      EXPECT_LE (p.at (row, c), 0.051f) << "row " << row;
    for (int row = c + 5; row < 41; ++row)
      EXPECT_NEAR (p.at (row, c), 0.25f, 1e-4f) << "row " << row;
    EXPECT_NEAR (p.at (c - 8, 2), 0.25f, 1e-4f);
    EXPECT_NEAR (p.at (c - 8, 38), 0.25f, 1e-4f);
    EXPECT_EQ (p.orientation[0], static_cast<float> (std::cos (angle * kPi / 180)));
    EXPECT_EQ (p.orientation[1], static_cast<float> (std::sin (angle * kPi / 180)));
  }
}

TEST (DepthPatchRotation, NoOrZeroOrViewingRayOrientationMeansImageAxes)
{
  Camera cam = kinectCamera ();
  cam.cx = 160;
  cam.cy = 120;
  LimbScene scene;
  scene.angle_deg = 145;
  const Rendered r = renderLimb (scene, cam);
  // A point on the optical axis, so that (0, 0, 1) is exactly along its viewing ray.
  const int on_axis = 120 * cam.width + 160;
  ASSERT_EQ (on_axis, r.tip_index);
  const std::vector<int> indices (4, r.tip_index);
  const std::vector<Eigen::Vector3f> orientations{Eigen::Vector3f::Zero (), Eigen::Vector3f (0.f, 0.f, 1.f),
                                                  Eigen::Vector3f (0.f, 1.f, 0.f),
                                                  Eigen::Vector3f (std::nanf (""), 0.f, 0.f)};
  const Patches with = computePatches (r.cloud, indices, &orientations, 525.f);
  const Patches without = computePatches (r.cloud, indices, nullptr, 525.f);
  ASSERT_EQ (with.size (), 4u);
  ASSERT_EQ (without.size (), 4u);
  for (std::size_t i = 0; i < 4; ++i)
  {
    SCOPED_TRACE ("orientation " + std::to_string (i));
    for (int c = 0; c < agex::DepthPatch::kMaxCells; ++c)
      ASSERT_EQ (bits (with[i].patch[c]), bits (without[0].patch[c])) << "cell " << c;
    const bool rotated = i == 2;  // (0, 1, 0) is "down" already: used, but the identity
    EXPECT_EQ (with[i].orientation[1], rotated ? 1.f : 0.f);
    EXPECT_EQ (with[i].orientation[0], 0.f);
    EXPECT_EQ (with[i].orientation[2], 0.f);
    EXPECT_EQ (without[i].orientation[1], 0.f);
  }
}

// ---------------------------------------------------------------------------
// Values

TEST (DepthPatchValues, CentreZeroRelativeDepthClampAndBackground)
{
  // Pixel (40, 30) of a 320x240 frame at z = 2; around it: a region 2 m behind, one
  // 0.5 m in front, one 0.1 m behind, NaN holes, and the frame border 40 px away.
  const Camera cam = kinectCamera ();
  Cloud::Ptr cloud = nanCloud (cam.width, cam.height);
  auto depth_at = [] (int u, int v) -> double {
    if (u >= 30 && u < 50 && v >= 20 && v < 40)
      return 2.0;
    if (u >= 50 && u < 70 && v >= 20 && v < 40)
      return 4.0;
    if (u >= 30 && u < 50 && v >= 40 && v < 60)
      return 1.5;
    if (u >= 50 && u < 70 && v >= 40 && v < 60)
      return 2.1;
    return -1;  // NaN
  };
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u)
      if (depth_at (u, v) > 0)
        (*cloud) (u, v) = rayPoint (cam, u, v, depth_at (u, v));
  const int centre = 30 * cam.width + 40;

  Estimation est;
  est.setClampDepth (0.25f);
  const Patches out = computePatches (cloud, {centre}, nullptr, 525.f, &est);
  ASSERT_EQ (out.size (), 1u);
  const agex::DepthPatch &p = out[0];
  EXPECT_EQ (p.size, 41);
  EXPECT_FLOAT_EQ (p.metres_per_cell, 0.6f / 41);
  EXPECT_EQ (est.getBackgroundValue (), 0.25f);
  // One cell is 0.6 / 41 m = 3.84 px at 2 m: cell (r, c) samples pixel
  // (40 + 3.84 (c - 20), 30 + 3.84 (r - 20)), rounded.
  auto pixel_of = [] (int k, int centre_px) {
    return static_cast<int> (std::floor (centre_px + 0.5 + (k - 20) * (0.6 / 41) * 525.0 / 2.0));
  };
  int counts[5] = {0, 0, 0, 0, 0};
  for (int row = 0; row < 41; ++row)
    for (int col = 0; col < 41; ++col)
    {
      const int u = pixel_of (col, 40), v = pixel_of (row, 30);
      // Avoid cells whose sample lies within float rounding of a pixel boundary.
      const double exact_u = 40.5 + (col - 20) * (0.6 / 41) * 525.0 / 2.0;
      const double exact_v = 30.5 + (row - 20) * (0.6 / 41) * 525.0 / 2.0;
      if (std::abs (exact_u - std::round (exact_u)) < 1e-3 || std::abs (exact_v - std::round (exact_v)) < 1e-3)
        continue;
      const float value = p.at (row, col);
      if (u < 0 || v < 0)
      {
        EXPECT_EQ (value, 0.25f) << "off-frame cell (" << row << ", " << col << ")";
        ++counts[0];
        continue;
      }
      const double d = depth_at (u, v);
      if (d < 0)
      {
        EXPECT_EQ (value, 0.25f) << "NaN cell";
        ++counts[1];
      }
      else if (d == 4.0)
      {
        EXPECT_EQ (value, 0.25f) << "2 m behind: +clamp";
        ++counts[2];
      }
      else if (d == 1.5)
      {
        EXPECT_EQ (value, -0.25f) << "0.5 m in front: -clamp";
        ++counts[3];
      }
      else
      {
        EXPECT_NEAR (value, static_cast<float> (d - 2.0), 1e-6f);
        ++counts[4];
      }
    }
  EXPECT_EQ (bits (p.at (20, 20)), bits (0.f));
  for (int k = 0; k < 5; ++k)
    EXPECT_GT (counts[k], 4) << "case " << k << " not exercised";
  for (int c = 41 * 41; c < agex::DepthPatch::kMaxCells; ++c)
    ASSERT_EQ (p.patch[c], 0.f);
  EXPECT_TRUE (out.is_dense);
}

TEST (DepthPatchValues, SmallerPatchUsesTheFirstCellsAndTheSameExtent)
{
  const Camera cam = kinectCamera ();
  const Rendered r = renderLimb (LimbScene (), cam);
  Estimation est;
  est.setPatchSize (21);
  est.setPatchExtent (0.3f);
  const std::vector<Eigen::Vector3f> orientations{r.orientation};
  const Patches small = computePatches (r.cloud, {r.tip_index}, &orientations, 525.f, &est);
  ASSERT_EQ (small.size (), 1u);
  EXPECT_EQ (small[0].size, 21);
  EXPECT_FLOAT_EQ (small[0].metres_per_cell, 0.3f / 21);
  EXPECT_EQ (small[0].at (10, 10), 0.f);
  for (int c = 21 * 21; c < agex::DepthPatch::kMaxCells; ++c)
    ASSERT_EQ (small[0].patch[c], 0.f) << "cell " << c;
  // Limb above, plane below.
  EXPECT_LE (small[0].at (2, 10), 0.051f);
  EXPECT_NEAR (small[0].at (18, 10), 0.25f, 1e-4f);
  // Even sizes have no centre cell but work.
  est.setPatchSize (8);
  const Patches even = computePatches (r.cloud, {r.tip_index}, &orientations, 525.f, &est);
  ASSERT_EQ (even.size (), 1u);
  EXPECT_EQ (even[0].size, 8);
  EXPECT_NEAR (even[0].at (7, 4), 0.25f, 1e-4f);
}

// ---------------------------------------------------------------------------
// Metric extent

TEST (DepthPatchExtent, SameLimbAtTwoDistancesGivesSimilarPatches)
{
  // 640x480 rather than 320x240: at 1.5 m the corners of a rotated 0.6 m patch
  // would leave a 320x240 frame (background instead of the plane).
  Camera full;
  full.width = 640;
  full.height = 480;
  full.cx = 319.5;
  full.cy = 239.5;
  for (const Camera &cam : {full, portraitCamera ()})
  {
    SCOPED_TRACE ("f = " + std::to_string (cam.fx));
    LimbScene near_scene, far_scene;
    near_scene.angle_deg = far_scene.angle_deg = 60;
    near_scene.axis_depth = 1.5;
    near_scene.plane_depth = 1.7;
    far_scene.axis_depth = 3.0;
    far_scene.plane_depth = 3.2;
    const agex::DepthPatch near_patch = limbPatch (near_scene, cam, true);
    const agex::DepthPatch far_patch = limbPatch (far_scene, cam, true);
    const PatchDifference d = compare (near_patch, far_patch);
    std::printf ("  f = %.0f: 1.5 m vs 3 m: %.2f%% cells differ (mean |d| %.4f m)\n", cam.fx, 100 * d.differing,
                 d.mean_abs);
    EXPECT_LT (d.differing, 0.02);
    EXPECT_LT (d.mean_abs, 0.003);
    // What a patch of fixed pixel size would see: at 1.5 m, the pixels of the 3 m
    // patch span 0.3 m.
    const PatchDifference wrong = compare (limbPatch (near_scene, cam, true, 0.3f), far_patch);
    std::printf ("  f = %.0f: 3 m vs 1.5 m with the same pixels: %.2f%% cells differ (mean |d| %.4f m)\n",
                 cam.fx, 100 * wrong.differing, wrong.mean_abs);
    EXPECT_GT (wrong.differing, 0.06);
    EXPECT_GT (wrong.mean_abs, 0.015);
  }
}

// ---------------------------------------------------------------------------
// Focal length

TEST (DepthPatchFocalLength, EstimateRecoversTheCameraWithinOnePercent)
{
  for (const Camera &cam : {kinectCamera (), portraitCamera ()})
  {
    SCOPED_TRACE ("f = " + std::to_string (cam.fx));
    // A full frame (limb and plane), and a sparse one (limb only, NaN elsewhere).
    for (const bool plane : {true, false})
    {
      LimbScene scene;
      scene.angle_deg = 20;
      scene.plane_depth = plane ? 2.2 : -1;
      const Rendered r = renderLimb (scene, cam);
      const float f = Estimation::estimateFocalLength (*r.cloud);
      EXPECT_NEAR (f, cam.fx, 0.01 * cam.fx);
      // compute() estimates it once when none is set, and uses the one set otherwise.
      Estimation est;
      const std::vector<Eigen::Vector3f> orientations{r.orientation};
      const Patches estimated = computePatches (r.cloud, {r.tip_index}, &orientations, 0.f, &est);
      EXPECT_EQ (est.getUsedFocalLength (), f);
      const Patches given = computePatches (r.cloud, {r.tip_index}, &orientations, static_cast<float> (cam.fx), &est);
      EXPECT_EQ (est.getUsedFocalLength (), static_cast<float> (cam.fx));
      ASSERT_EQ (estimated.size (), 1u);
      ASSERT_EQ (given.size (), 1u);
      EXPECT_LT (compare (estimated[0], given[0]).differing, 0.01);
    }
  }
  // Points off their pixel centres by up to half a pixel (what a nearest-pixel resampling
  // such as agex::applyView leaves) and with 1 cm depth noise: the estimate holds.
  LimbScene scene;
  const Camera cam = kinectCamera ();
  Rendered r = renderLimb (scene, cam);
  std::mt19937 rng (7);
  std::uniform_real_distribution<double> jitter (-0.5, 0.5);
  std::normal_distribution<double> noise (0.0, 0.01);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u)
    {
      pcl::PointXYZ &p = (*r.cloud) (u, v);
      if (!isFinite (p))
        continue;
      const double z = p.z + noise (rng);
      p = pcl::PointXYZ (static_cast<float> ((u + jitter (rng) - cam.cx) * z / cam.fx),
                         static_cast<float> ((v + jitter (rng) - cam.cy) * z / cam.fy), static_cast<float> (z));
    }
  EXPECT_NEAR (Estimation::estimateFocalLength (*r.cloud), cam.fx, 0.01 * cam.fx);
}

TEST (DepthPatchFocalLength, DegenerateCloudsGiveNoEstimate)
{
  Cloud unorganized;
  unorganized.push_back (pcl::PointXYZ (0.f, 0.f, 1.f));
  EXPECT_EQ (Estimation::estimateFocalLength (unorganized), 0.f);
  Cloud::Ptr cloud = nanCloud (20, 10);
  EXPECT_EQ (Estimation::estimateFocalLength (*cloud), 0.f);
  (*cloud) (3, 4) = pcl::PointXYZ (0.1f, 0.2f, 1.f);
  (*cloud) (4, 4) = pcl::PointXYZ (0.1f, 0.2f, 1.f);
  (*cloud) (5, 4) = pcl::PointXYZ (0.1f, 0.2f, 1.f);  // three points, one ray
  EXPECT_EQ (Estimation::estimateFocalLength (*cloud), 0.f);
  // Mirrored (f < 0) is not a pinhole image either.
  for (int u = 0; u < 20; ++u)
    (*cloud) (u, 4) = pcl::PointXYZ (-0.01f * u, 0.f, 1.f);
  EXPECT_EQ (Estimation::estimateFocalLength (*cloud), 0.f);
}

// ---------------------------------------------------------------------------
// API: indices and/or interest points, output layout, point types

TEST (DepthPatchFeature, InterestPointsAloneLocatePixelsByUV)
{
  const Camera cam = kinectCamera ();
  LimbScene scene;
  scene.angle_deg = 145;
  const Rendered r = renderLimb (scene, cam);
  const std::vector<int> indices{r.tip_index, r.tip_index - 7, 5};  // 5: a NaN-free plane pixel
  const std::vector<Eigen::Vector3f> orientations{r.orientation, Eigen::Vector3f (1.f, 0.f, 0.f),
                                                  Eigen::Vector3f::Zero ()};
  const Patches by_indices = computePatches (r.cloud, indices, &orientations, 525.f);

  Estimation est;
  est.setInputCloud (r.cloud);
  est.setFocalLength (525.f);
  est.setInterestPoints (interestPoints (*r.cloud, indices, orientations));
  Patches by_uv;
  est.compute (by_uv);
  ASSERT_EQ (by_uv.size (), 3u);
  EXPECT_EQ (by_uv.width, 3u);
  EXPECT_EQ (by_uv.height, 1u);
  ASSERT_EQ (by_indices.size (), 3u);
  for (std::size_t i = 0; i < 3; ++i)
    for (int c = 0; c < agex::DepthPatch::kMaxCells; ++c)
      ASSERT_EQ (bits (by_uv[i].patch[c]), bits (by_indices[i].patch[c])) << "patch " << i << " cell " << c;

  // Again with fewer points (the indices from (u, v) are rebuilt), then with
  // explicit indices taking over.
  est.setInterestPoints (interestPoints (*r.cloud, {indices[1]}, {orientations[1]}));
  est.compute (by_uv);
  ASSERT_EQ (by_uv.size (), 1u);
  EXPECT_EQ (bits (by_uv[0].patch[100]), bits (by_indices[1].patch[100]));
  est.setIndices (pcl::IndicesPtr (new pcl::Indices{indices[0]}));
  est.setInterestPoints (interestPoints (*r.cloud, {indices[0]}, {orientations[0]}));
  est.compute (by_uv);
  ASSERT_EQ (by_uv.size (), 1u);
  EXPECT_EQ (bits (by_uv[0].patch[100]), bits (by_indices[0].patch[100]));
}

TEST (DepthPatchFeature, AgexOutputByIndicesOrByUVAndLimbsAbove)
{
  // A five-limbed star: AGEX finds the centroid and the five tips, oriented outwards.
  const Camera cam = kinectCamera ();
  const Figure star = makeStar (Eigen::Vector2d (0.0, 0.0), 2.0, 5, 0.35, 0.04, 0.1, -70.0);
  const Cloud::Ptr cloud = rasterise ({star}, cam);
  agex::AGEXKeypoint<pcl::PointXYZ> agex;
  agex.setInputCloud (cloud);
  agex.setPointsPerMesh (6);
  IPCloud::Ptr points (new IPCloud);
  agex.compute (*points);
  ASSERT_EQ (points->size (), 6u);

  Estimation by_indices;
  by_indices.setInputCloud (cloud);
  by_indices.setIndices (agex.getKeypointsIndices ());
  by_indices.setInterestPoints (points);
  Patches a;
  by_indices.compute (a);
  Estimation by_uv;
  by_uv.setInputCloud (cloud);
  by_uv.setInterestPoints (points);
  Patches b;
  by_uv.compute (b);
  ASSERT_EQ (a.size (), 6u);
  ASSERT_EQ (b.size (), 6u);
  EXPECT_NEAR (by_indices.getUsedFocalLength (), 525.f, 0.5f);
  for (std::size_t i = 0; i < 6; ++i)
    for (int c = 0; c < agex::DepthPatch::kMaxCells; ++c)
      ASSERT_EQ (bits (a[i].patch[c]), bits (b[i].patch[c])) << "patch " << i << " cell " << c;
  // The centroid is not rotated; every tip has its limb above the centre (foreground, 0)
  // and background (+clamp, NaN pixels) straight below.
  EXPECT_EQ (a[0].getOrientationVector3fMap (), Eigen::Vector3f::Zero ());
  for (std::size_t i = 1; i < 6; ++i)
  {
    SCOPED_TRACE ("tip " + std::to_string (i));
    EXPECT_GT (a[i].getOrientationVector3fMap ().norm (), 0.99f);
    // Near the tip only: AGEX orientations on this grid are up to 15 degrees off the limb
    // axis (its 8-neighbour geodesic paths), enough to leave a 0.08 m wide limb farther up.
    for (int row = 13; row < 20; ++row)
      EXPECT_EQ (a[i].at (row, 20), 0.f) << "row " << row;
    for (int row = 22; row < 41; ++row)
      EXPECT_EQ (a[i].at (row, 20), 0.3f) << "row " << row;
  }
}

TEST (DepthPatchFeature, WithoutIndicesEveryPixelAndAnOrganizedOutput)
{
  Camera cam;
  cam.width = 12;
  cam.height = 9;
  cam.cx = 5.5;
  cam.cy = 4;
  cam.fx = cam.fy = 20;
  LimbScene scene;
  scene.radius = 0.2;
  const Rendered r = renderLimb (scene, cam);
  Estimation est;
  est.setInputCloud (r.cloud);
  est.setPatchSize (5);
  Patches out;
  est.compute (out);
  EXPECT_EQ (out.width, 12u);
  EXPECT_EQ (out.height, 9u);
  ASSERT_EQ (out.size (), 108u);
  EXPECT_TRUE (out.is_dense);
  EXPECT_NEAR (est.getUsedFocalLength (), 20.f, 0.2f);
  for (const auto &p : out)
    EXPECT_EQ (p.at (2, 2), 0.f);
}

TEST (DepthPatchFeature, AllInstantiatedPointTypesAgree)
{
  const Camera cam = kinectCamera ();
  LimbScene scene;
  scene.angle_deg = 30;
  const Rendered r = renderLimb (scene, cam);
  const std::vector<Eigen::Vector3f> orientations{r.orientation};
  const Patches reference = computePatches (r.cloud, {r.tip_index}, &orientations);

  auto run = [&] (auto cloud) {
    pcl::copyPointCloud (*r.cloud, *cloud);
    using PointT = typename std::decay_t<decltype (*cloud)>::PointType;
    agex::DepthPatchEstimation<PointT> est;
    est.setInputCloud (cloud);
    est.setIndices (pcl::IndicesPtr (new pcl::Indices{r.tip_index}));
    est.setInterestPoints (interestPoints (*r.cloud, {r.tip_index}, orientations));
    Patches out;
    est.compute (out);
    return out;
  };
  const Patches xyzi = run (pcl::PointCloud<pcl::PointXYZI>::Ptr (new pcl::PointCloud<pcl::PointXYZI>));
  const Patches rgba = run (pcl::PointCloud<pcl::PointXYZRGBA>::Ptr (new pcl::PointCloud<pcl::PointXYZRGBA>));
  ASSERT_EQ (reference.size (), 1u);
  ASSERT_EQ (xyzi.size (), 1u);
  ASSERT_EQ (rgba.size (), 1u);
  for (int c = 0; c < agex::DepthPatch::kMaxCells; ++c)
  {
    ASSERT_EQ (bits (xyzi[0].patch[c]), bits (reference[0].patch[c]));
    ASSERT_EQ (bits (rgba[0].patch[c]), bits (reference[0].patch[c]));
  }
}

// ---------------------------------------------------------------------------
// Bad input

TEST (DepthPatchBadInput, MisuseGivesAnEmptyOutputAndNoCrash)
{
  QuietPcl quiet;
  const Camera cam = kinectCamera ();
  const Rendered r = renderLimb (LimbScene (), cam);
  const std::vector<Eigen::Vector3f> one{r.orientation};
  Patches out;
  auto expect_empty = [&] (Estimation &est, const char *what) {
    out.resize (3);  // stale content must go
    est.compute (out);
    EXPECT_TRUE (out.empty ()) << what;
    EXPECT_EQ (out.width, 0u) << what;
  };

  {
    Estimation est;  // no input
    expect_empty (est, "no input");
  }
  {
    Cloud::Ptr flat (new Cloud (*r.cloud));
    flat->width = static_cast<std::uint32_t> (flat->size ());
    flat->height = 1;
    Estimation est;
    est.setInputCloud (flat);
    est.setIndices (pcl::IndicesPtr (new pcl::Indices{r.tip_index}));
    est.setFocalLength (525.f);
    expect_empty (est, "unorganized");
  }
  for (const int bad : {-1, static_cast<int> (r.cloud->size ())})
  {
    Estimation est;
    est.setInputCloud (r.cloud);
    est.setIndices (pcl::IndicesPtr (new pcl::Indices{r.tip_index, bad}));
    expect_empty (est, "index out of range");
  }
  {
    Estimation est;
    est.setInputCloud (r.cloud);
    est.setIndices (pcl::IndicesPtr (new pcl::Indices{r.tip_index, r.tip_index}));
    est.setInterestPoints (interestPoints (*r.cloud, {r.tip_index}, one));
    expect_empty (est, "one interest point for two indices");
  }
  {
    IPCloud::Ptr points = interestPoints (*r.cloud, {r.tip_index}, one);
    (*points)[0].u = cam.width;
    Estimation est;
    est.setInputCloud (r.cloud);
    est.setInterestPoints (points);
    expect_empty (est, "(u, v) outside the frame");
  }
  {
    Estimation est;
    est.setInputCloud (r.cloud);
    est.setIndices (pcl::IndicesPtr (new pcl::Indices{r.tip_index}));
    est.setPatchSize (0);
    expect_empty (est, "patch size 0");
    est.setPatchSize (42);
    expect_empty (est, "patch size 42");
    est.setPatchSize (41);
    est.setPatchExtent (0.f);
    expect_empty (est, "extent 0");
    est.setPatchExtent (std::nanf (""));
    expect_empty (est, "extent NaN");
    est.setPatchExtent (0.6f);
    est.setClampDepth (-0.1f);
    expect_empty (est, "negative clamp");
    est.setClampDepth (0.3f);
    est.setFocalLength (-525.f);
    expect_empty (est, "negative focal length");
    est.setFocalLength (0.f);
    est.compute (out);
    EXPECT_EQ (out.size (), 1u) << "valid again";
  }
  {
    // The focal length cannot be estimated from a single finite point.
    Cloud::Ptr lonely = nanCloud (cam.width, cam.height);
    (*lonely) (10, 10) = rayPoint (cam, 10, 10, 2.0);
    Estimation est;
    est.setInputCloud (lonely);
    est.setIndices (pcl::IndicesPtr (new pcl::Indices{10 * cam.width + 10}));
    expect_empty (est, "focal length not estimable");
    est.setFocalLength (525.f);
    est.compute (out);
    ASSERT_EQ (out.size (), 1u);
    EXPECT_EQ (out[0].at (20, 20), 0.f);
    EXPECT_EQ (out[0].at (0, 0), 0.3f);
  }
}

TEST (DepthPatchBadInput, EmptyIndicesGiveAnEmptyOutput)
{
  const Rendered r = renderLimb (LimbScene (), kinectCamera ());
  Estimation est;
  est.setInputCloud (r.cloud);
  est.setIndices (pcl::IndicesPtr (new pcl::Indices));
  Patches out;
  out.resize (2);
  est.compute (out);
  EXPECT_TRUE (out.empty ());
  EXPECT_EQ (out.width, 0u);
  // And empty interest points alone.
  Estimation by_uv;
  by_uv.setInputCloud (r.cloud);
  by_uv.setInterestPoints (IPCloud::Ptr (new IPCloud));
  out.resize (2);
  by_uv.compute (out);
  EXPECT_TRUE (out.empty ());
}

TEST (DepthPatchBadInput, NanPointsAndAllNanFramesGiveBackgroundPatches)
{
  const Camera cam = kinectCamera ();
  // All-NaN frame, no focal length: nothing to estimate, nothing needed.
  Cloud::Ptr nan_frame = nanCloud (cam.width, cam.height);
  const std::vector<Eigen::Vector3f> orientations (2, Eigen::Vector3f (1.f, 0.f, 0.f));
  Estimation est;
  const Patches out = computePatches (nan_frame, {0, 1000}, &orientations, 0.f, &est);
  ASSERT_EQ (out.size (), 2u);
  EXPECT_TRUE (out.is_dense);
  EXPECT_EQ (est.getUsedFocalLength (), 0.f);
  for (const auto &p : out)
  {
    EXPECT_EQ (p.size, 41);
    EXPECT_EQ (p.getOrientationVector3fMap (), Eigen::Vector3f::Zero ());
    for (int c = 0; c < 41 * 41; ++c)
      ASSERT_EQ (p.patch[c], 0.3f);
  }
  // A NaN interest point in a normal frame: background patch, the others unaffected.
  LimbScene scene;
  scene.plane_depth = -1;
  const Rendered r = renderLimb (scene, cam);
  const int nan_pixel = 5;
  ASSERT_FALSE (isFinite ((*r.cloud)[nan_pixel]));
  const std::vector<Eigen::Vector3f> two{Eigen::Vector3f (1.f, 0.f, 0.f), r.orientation};
  const Patches mixed = computePatches (r.cloud, {nan_pixel, r.tip_index}, &two, 525.f);
  ASSERT_EQ (mixed.size (), 2u);
  EXPECT_TRUE (mixed.is_dense);
  for (int c = 0; c < 41 * 41; ++c)
    ASSERT_EQ (mixed[0].patch[c], 0.3f);
  EXPECT_EQ (mixed[1].at (20, 20), 0.f);
  EXPECT_LE (mixed[1].at (5, 20), 0.051f);
}

// ---------------------------------------------------------------------------
// The point type

TEST (DepthPatchType, PcdRoundTripKeepsEveryValue)
{
  Patches patches;
  std::mt19937 rng (42);
  std::uniform_real_distribution<float> value (-0.3f, 0.3f);
  for (int i = 0; i < 4; ++i)
  {
    agex::DepthPatch p;
    for (float &c : p.patch)
      c = value (rng);
    p.patch[0] = -0.f;
    p.patch[1] = std::numeric_limits<float>::denorm_min ();
    p.patch[agex::DepthPatch::kMaxCells - 1] = 1e30f;
    p.orientation[0] = value (rng);
    p.orientation[1] = value (rng);
    p.orientation[2] = -1.f;
    p.size = 41 - i;
    p.metres_per_cell = 0.6f / p.size;
    patches.push_back (p);
  }
  TempDir dir;
  for (const bool compressed : {false, true})
  {
    SCOPED_TRACE (compressed ? "binary_compressed" : "binary");
    const std::string path = dir.file (compressed ? "c.pcd" : "b.pcd");
    if (compressed)
      ASSERT_EQ (pcl::io::savePCDFileBinaryCompressed (path, patches), 0);
    else
      ASSERT_EQ (pcl::io::savePCDFileBinary (path, patches), 0);
    Patches loaded;
    ASSERT_EQ (pcl::io::loadPCDFile (path, loaded), 0);
    ASSERT_EQ (loaded.size (), patches.size ());
    for (std::size_t i = 0; i < patches.size (); ++i)
    {
      for (int c = 0; c < agex::DepthPatch::kMaxCells; ++c)
        ASSERT_EQ (bits (loaded[i].patch[c]), bits (patches[i].patch[c])) << "patch " << i << " cell " << c;
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ (bits (loaded[i].orientation[k]), bits (patches[i].orientation[k]));
      EXPECT_EQ (loaded[i].size, patches[i].size);
      EXPECT_EQ (bits (loaded[i].metres_per_cell), bits (patches[i].metres_per_cell));
    }
  }
  // The header names the 1681-count field.
  pcl::PCLPointCloud2 header;
  pcl::PCDReader reader;
  ASSERT_EQ (reader.readHeader (dir.file ("b.pcd"), header), 0);
  ASSERT_EQ (header.fields.size (), 4u);
  EXPECT_EQ (header.fields[0].name, "patch");
  EXPECT_EQ (header.fields[0].count, 1681u);
}

// ---------------------------------------------------------------------------
// A real Bonn frame: the portrait view and the full frame, AGEX points, timing

double
timePatches (const Cloud::ConstPtr &cloud, const IPCloud::ConstPtr &points, const pcl::IndicesPtr &indices,
             float focal, int repetitions, Patches &out)
{
  Estimation est;
  est.setInputCloud (cloud);
  est.setIndices (indices);
  est.setInterestPoints (points);
  est.setFocalLength (focal);
  est.compute (out);  // warm-up
  const auto start = std::chrono::steady_clock::now ();
  for (int i = 0; i < repetitions; ++i)
    est.compute (out);
  const auto stop = std::chrono::steady_clock::now ();
  return std::chrono::duration<double, std::milli> (stop - start).count () / repetitions;
}

/** More cells near the point's depth (|value| < 0.1 m) in the upper half than in the lower. */
bool
bodyAbove (const agex::DepthPatch &p)
{
  const int c = p.size / 2;
  int upper = 0, lower = 0;
  for (int row = 0; row < p.size; ++row)
    for (int col = 0; col < p.size; ++col)
      if (row != c && std::abs (p.at (row, col)) < 0.1f)
        ++(row < c ? upper : lower);
  return upper > lower;
}

TEST (DepthPatchBonn, TwentyPatchesOnARealFrame)
{
  const std::string path = sharedData ("bonn/depth/1/000.png");
  AGEX_REQUIRE_BONN (path);
  const agex::Frame frame = agex::loadFrame (path);
  Cloud::Ptr portrait (new Cloud);
  agex::applyView (*frame.cloud, agex::bonnPortraitView (), *portrait);

  for (const Cloud::Ptr &cloud : {portrait, frame.cloud})
  {
    const bool is_portrait = cloud == portrait;
    SCOPED_TRACE (is_portrait ? "144x176 portrait view" : "640x480 frame");
    const float expected_f = is_portrait ? 210.f : 525.f;
    const float f = Estimation::estimateFocalLength (*cloud);
    EXPECT_NEAR (f, expected_f, 0.01f * expected_f);

    // AGEX on the box the pipeline uses (no floor removal here: extra meshes are fine).
    pcl::IndicesPtr box (new pcl::Indices);
    for (std::size_t i = 0; i < cloud->size (); ++i)
    {
      const auto &p = (*cloud)[i];
      if (isFinite (p) && std::abs (p.x) <= 0.75f && p.z >= 1.3f && p.z <= 2.6f)
        box->push_back (static_cast<int> (i));
    }
    agex::AGEXKeypoint<pcl::PointXYZ> agex;
    agex.setInputCloud (cloud);
    agex.setIndices (box);
    agex.setPointsPerMesh (20);
    agex.setDeltaConnected (0.03f);
    agex.setMinMeshSize (cloud->size () / 100);
    IPCloud::Ptr points (new IPCloud);
    agex.compute (*points);
    ASSERT_GE (points->size (), 20u);
    points->resize (20);
    pcl::IndicesPtr indices (new pcl::Indices (agex.getKeypointsIndices ()->indices.begin (),
                                               agex.getKeypointsIndices ()->indices.begin () + 20));

    Patches out;
    const int reps = 200;
    const double ms_estimated = timePatches (cloud, points, indices, 0.f, reps, out);
    const double ms_given = timePatches (cloud, points, indices, expected_f, reps, out);
    ASSERT_EQ (out.size (), 20u);
    int rotated = 0, body_above = 0;
    for (const auto &p : out)
    {
      EXPECT_EQ (p.at (20, 20), 0.f);
      for (int c = 0; c < 41 * 41; ++c)
        ASSERT_TRUE (std::abs (p.patch[c]) <= 0.3f);
      if (p.getOrientationVector3fMap ().norm () == 0.f)
        continue;
      ++rotated;
      // An extremity's orientation points out of the body, i.e. down the patch: the
      // body (cells near the point's depth) lies mostly in the upper half.
      body_above += bodyAbove (p) ? 1 : 0;
    }
    // Without orientations (image axes) far fewer patches have the body above.
    Patches unrotated;
    timePatches (cloud, nullptr, indices, expected_f, 1, unrotated);
    int unrotated_above = 0;
    for (std::size_t i = 0; i < unrotated.size (); ++i)
      unrotated_above += out[i].getOrientationVector3fMap ().norm () > 0.f && bodyAbove (unrotated[i]) ? 1 : 0;
    EXPECT_GE (body_above, unrotated_above + 4);
    EXPECT_GE (rotated, 18);  // every AGEX point but the mesh centroids
    // Deterministic on this frame: 15 of 19 (the misses are late AGEX points with a large
    // depth component, on clutter the crop keeps), 8 of 19 without orientations.
    EXPECT_GE (body_above, rotated * 2 / 3) << body_above << " of " << rotated;
    std::printf ("  %s: body above the centre in %d of %d oriented patches (%d without orientations)\n",
                 is_portrait ? "portrait 144x176" : "full 640x480", body_above, rotated, unrotated_above);
    std::printf ("  %s: f estimated %.2f; 20 patches %.4f ms (%.2f us/patch) with f given, "
                 "%.4f ms with f estimated\n",
                 is_portrait ? "portrait 144x176" : "full 640x480", f, ms_given, 1000 * ms_given / 20, ms_estimated);
    RecordProperty (is_portrait ? "portrait_ms_per_20" : "full_ms_per_20", std::to_string (ms_given));
    EXPECT_LT (ms_given, 20.0);  // ~0.05 ms in Release; generous for Debug and shared machines
  }
}
}  // namespace
